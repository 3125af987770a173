//! Elastic bands (waistbands, collars, cuffs): garment vertices bound to the body's surface where
//! they lie on it, and driven there as the cloth's kinematic handles while the body moves.

use crate::body::{BodyError, BodyMesh};
use crate::follow::SurfaceBinding;
use tryon_core::frames::BodyFrame;
use tryon_core::math::Vec3;
use tryon_core::mesh::PolyMesh;

/// Garment vertices bound to the body: handle `first_handle + k` of the cloth holds vertex
/// `vertices[k]` at its binding on the body's current shape.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Bands {
    pub vertices: Vec<u32>,
    pub bindings: Vec<SurfaceBinding>,
    pub first_handle: usize,
    /// The body's current shape, on which the bindings are evaluated.
    pub body: BodyMesh,
    targets: Vec<Vec3>,
}

impl Bands {
    /// Binds each of `vertices` (of the garment at `positions`) to its nearest face of `body` in
    /// its current shape; vertices over a degenerate face are left out. `None` when none binds.
    pub fn bind(
        body: &PolyMesh,
        positions: &[Vec3],
        vertices: &[u32],
    ) -> Result<Option<Bands>, BodyError> {
        let body = BodyMesh::new(body)?;
        let mut kept = Vec::new();
        let mut bindings = Vec::new();
        for &v in vertices {
            if let Some(b) = positions
                .get(v as usize)
                .and_then(|p| SurfaceBinding::bind(&body, p))
            {
                kept.push(v);
                bindings.push(b);
            }
        }
        Ok((!kept.is_empty()).then_some(Bands {
            vertices: kept,
            bindings,
            first_handle: 0,
            body,
            targets: Vec::new(),
        }))
    }

    /// Where every band vertex belongs on the body's new shape (in `vertices` order), or `None`
    /// when the frame does not fit the body (the handles then stay where they were).
    pub fn targets(&mut self, frame: &BodyFrame) -> Option<&[Vec3]> {
        self.body.set_frame(frame).ok()?;
        self.targets.clear();
        let body = &self.body;
        self.targets
            .extend(self.bindings.iter().map(|b| b.position(body)));
        Some(&self.targets)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::shapes::icosphere;

    #[test]
    fn band_vertices_follow_their_faces_and_a_wrong_frame_gives_no_targets() {
        let sphere = icosphere(0.3, 2, Vec3::zeros());
        let garment = [Vec3::new(0.0, 0.3, 0.0), Vec3::new(0.301, 0.0, 0.0)];
        let mut bands = Bands::bind(&sphere, &garment, &[0, 1, 7]).unwrap().unwrap();
        assert_eq!(
            bands.vertices,
            vec![0, 1],
            "a vertex the garment lacks is left out"
        );
        let mut frame = BodyFrame {
            time: 0.0,
            positions: sphere
                .positions
                .iter()
                .map(|p| p + Vec3::new(0.0, 0.0, 0.5))
                .collect(),
            velocities: Vec::new(),
        };
        let t = bands.targets(&frame).unwrap().to_vec();
        for (got, was) in t.iter().zip(garment) {
            assert!(
                (got - (was + Vec3::new(0.0, 0.0, 0.5))).norm() < 1e-9,
                "{got}"
            );
        }
        frame.positions.pop();
        assert!(bands.targets(&frame).is_none());
    }
}
