//! The fine surface's layers (`FineLayers`, a [`SurfaceStage`]): the PN surfaces of two garments
//! a few millimetres apart bulge by their own normals and can pass through each other where the
//! coarse layers do not. After the other surface stages, the fine surface is untangled between
//! garments as the starting shape is (`SelfContacts::untangle`): the higher layer's side of a
//! crossing pair, or of a pair nearer than the gap, moves out along its outward normal, never
//! farther than two gaps in a frame.

use super::{SelfContacts, SelfParams};
use tryon_core::frames::FineSurface;
use tryon_core::math::Real;
use tryon_core::stages::{Clock, Probe, SurfaceInput, SurfaceStage};

/// Passes of untangling per frame.
const PASSES: u32 = 8;

/// Contact between the garments of a fine surface.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct FineLayers {
    contacts: SelfContacts,
    /// Distance kept between garments (m).
    gap: Real,
    /// 1 where the surface's triangles wind with their normals away from the body, else -1.
    orientation: Real,
    probes: Vec<Probe>,
}

impl FineLayers {
    /// The stage for `surface` (the fine surface as first evaluated), whose coarse vertex `v`
    /// belongs to garment `garment[v]` worn in layer `layer[v]`; `gap` is kept between garments.
    pub fn new(
        surface: &FineSurface,
        (garment, layer): (&[u16], &[u32]),
        gap: Real,
        orientation: Real,
    ) -> FineLayers {
        let coarse = |s: &tryon_core::frames::FineVertexSource| {
            surface
                .coarse_triangles
                .get(s.face as usize)
                .map_or(0, |t| t[0] as usize)
        };
        let fine_garment: Vec<u16> = surface
            .sources
            .iter()
            .map(|s| garment.get(coarse(s)).copied().unwrap_or(0))
            .collect();
        let fine_layer: Vec<u32> = surface
            .sources
            .iter()
            .map(|s| layer.get(coarse(s)).copied().unwrap_or(0))
            .collect();
        let params = SelfParams {
            thickness: gap,
            within: false,
            between: true,
            untangle_near: false,
            ..SelfParams::default()
        };
        let contacts = SelfContacts::new(&surface.triangles, &surface.positions, params)
            .with_garments(&fine_garment, &fine_layer);
        FineLayers {
            contacts,
            gap,
            orientation,
            probes: Vec::new(),
        }
    }
}

impl SurfaceStage for FineLayers {
    tryon_core::whole_state!();
    fn parts(&self) -> Vec<&'static str> {
        vec!["fine_layers"]
    }

    fn run(&mut self, _: &SurfaceInput<'_>, surface: &mut FineSurface, clock: &mut dyn Clock) {
        let (sc, probes, gap) = (&mut self.contacts, &mut self.probes, self.gap);
        let o = self.orientation;
        clock.time("fine_layers", &mut || {
            probes.clear();
            probes.extend(surface.normals.iter().map(|n| Probe {
                distance: 0.0,
                normal: *n * o,
            }));
            sc.untangle(&mut surface.positions, probes, (gap, PASSES), |_| false);
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::frames::FineVertexSource;
    use tryon_core::math::Vec3;
    use tryon_core::mesh::grid_xz;
    use tryon_core::stages::Untimed;

    /// Two 5 x 5 sheets as one fine surface (each its own coarse triangle's lattice is not
    /// needed: every vertex is its own source), the upper (layer 1) dipping through the lower
    /// (layer 0) in its middle.
    fn crossing_sheets() -> (FineSurface, Vec<u16>, Vec<u32>) {
        let a = grid_xz(4, 4, 0.1, 0.1, 0.0);
        let mut b = grid_xz(4, 4, 0.1, 0.1, 0.002);
        for p in &mut b.positions {
            if p.x.abs() < 0.01 && p.z.abs() < 0.01 {
                p.y = -0.001;
            }
        }
        let (ta, _) = a.triangulate();
        let (tb, _) = b.triangulate();
        let n = a.positions.len() as u32;
        let mut s = FineSurface::default();
        s.positions = a.positions.iter().chain(&b.positions).copied().collect();
        s.normals = vec![Vec3::y(); s.positions.len()];
        s.triangles = ta
            .iter()
            .copied()
            .chain(tb.iter().map(|t| t.map(|v| v + n)))
            .collect();
        // Coarse triangles: one per vertex, whose first corner is the vertex itself.
        s.coarse_triangles = (0..s.positions.len() as u32).map(|v| [v, v, v]).collect();
        s.sources = (0..s.positions.len() as u32)
            .map(|v| FineVertexSource {
                face: v,
                bary: [1.0, 0.0, 0.0],
                level: 0,
            })
            .collect();
        let garment = (0..2 * n).map(|v| (v >= n) as u16).collect();
        let layer = (0..2 * n).map(|v| (v >= n) as u32).collect();
        (s, garment, layer)
    }

    #[test]
    fn the_outer_garment_is_lifted_out_of_the_inner_one() {
        let (mut s, g, l) = crossing_sheets();
        let mut contacts = SelfContacts::new(&s.triangles, &s.positions, SelfParams::default());
        assert!(!contacts.crossing_triangles(&s.positions).is_empty());
        let before = s.positions.clone();
        let mut stage = FineLayers::new(&s, (&g, &l), 0.001, 1.0);
        let input = SurfaceInput {
            coarse: &Default::default(),
            body: None,
        };
        stage.run(&input, &mut s, &mut Untimed);
        assert!(contacts.crossing_triangles(&s.positions).is_empty());
        // Only the outer sheet moved, and only upward.
        let n = before.len() / 2;
        assert_eq!(s.positions[..n], before[..n]);
        assert!(
            s.positions[n..]
                .iter()
                .zip(&before[n..])
                .all(|(a, b)| a.y >= b.y)
        );
    }
}
