//! Refinement as the frame loop runs it ([`SurfaceStage`] "refine"): the coarse cloth's vertex
//! normals (turned to face away from the body), then the PN surface evaluated from them.

use crate::refine::PnRefiner;
use tryon_core::frames::FineSurface;
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_core::stages::{Clock, SurfaceInput, SurfaceStage};

/// The PN refiner with the coarse normals' orientation.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct PnStage {
    pub refiner: PnRefiner,
    /// -1 when the garment's triangles wind inward (normals are flipped to face away from the
    /// body), else 1.
    pub orientation: Real,
    coarse_normals: Vec<Vec3>,
}

impl PnStage {
    pub fn new(refiner: PnRefiner, orientation: Real) -> Self {
        PnStage {
            refiner,
            orientation,
            coarse_normals: Vec::new(),
        }
    }

    /// Evaluates the fine surface of the coarse cloth at `x`.
    pub fn evaluate(&mut self, x: &[Vec3], surface: &mut FineSurface) {
        vertex_normals(x, &self.refiner.coarse_triangles, &mut self.coarse_normals);
        if self.orientation < 0.0 {
            self.coarse_normals.iter_mut().for_each(|n| *n = -*n);
        }
        self.refiner.evaluate(x, &self.coarse_normals, surface);
    }
}

impl SurfaceStage for PnStage {
    tryon_core::whole_state!();
    fn parts(&self) -> Vec<&'static str> {
        vec!["refine"]
    }

    fn run(&mut self, input: &SurfaceInput<'_>, surface: &mut FineSurface, clock: &mut dyn Clock) {
        let x = &input.coarse.positions;
        clock.time("refine", &mut || self.evaluate(x, surface));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::frames::CoarseFrame;
    use tryon_core::mesh::grid_xz;
    use tryon_core::stages::Untimed;

    #[test]
    fn a_flat_sheet_refines_flat_with_normals_by_orientation() {
        let mesh = grid_xz(2, 2, 1.0, 1.0, 0.0);
        let coarse = CoarseFrame::at_rest(mesh.positions.clone());
        let input = SurfaceInput {
            coarse: &coarse,
            body: None,
        };
        let mut normals = Vec::new();
        for orientation in [1.0, -1.0] {
            let mut stage = PnStage::new(PnRefiner::new(&mesh, 2).unwrap(), orientation);
            let mut s = FineSurface::default();
            stage.run(&input, &mut s, &mut Untimed);
            assert_eq!(s.positions.len(), stage.refiner.fine_vertices());
            assert!(s.positions.iter().all(|p| p.y.abs() < 1e-12));
            assert!(s.normals.iter().all(|n| (n.y.abs() - 1.0).abs() < 1e-12));
            normals.push(s.normals[0].y);
        }
        assert_eq!(normals[0], -normals[1], "the orientation flips the normals");
    }
}
