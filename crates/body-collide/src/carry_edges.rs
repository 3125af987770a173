//! The carry kept from tearing the cloth. P1's following moves each point with its own nearest
//! body face, by its own weight (full near the body, fading with distance): two ends of one cloth
//! edge bound to different limbs (an armpit between arm and torso), or at different distances,
//! are carried apart when the body moves fast. On CMU 131_01 a 1 cm edge of the elegant suit under
//! the raised arm grew by 1 cm at each frame's carry. The solver pulls such an edge back only as
//! fast as its step allows; with self-contact's bounds (a fraction of a millimetre a step in
//! packed layers) it never did, and the garment tore.
//!
//! So the carry's displacements are limited edge by edge, Provot's strain limit applied to the
//! carry alone: where an edge's length after the carry differs from its length before by more
//! than `slack` of it, both ends' displacements are moved toward each other until it does not.
//! Where the carry is rigid (both ends on one face, or a rigidly moving body) nothing changes.

use tryon_core::math::{Real, Vec3};

/// Cloth edges whose lengths the carry keeps within a share of what they were.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CarryEdges {
    pub edges: Vec<[u32; 2]>,
    /// Largest relative change of an edge's length the carry may make.
    pub slack: Real,
    /// Gauss-Seidel passes over the edges.
    pub passes: u32,
}

impl CarryEdges {
    /// The edges of `tris` (each once), kept within 10% by 8 passes.
    pub fn of_triangles(tris: &[[u32; 3]]) -> Self {
        let mut edges: Vec<[u32; 2]> = tris
            .iter()
            .flat_map(|t| (0..3).map(move |k| [t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3])]))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        CarryEdges {
            edges,
            slack: 0.1,
            passes: 8,
        }
    }

    /// Limits the displacements `d` of the points `x` (before the carry) edge by edge; returns how
    /// many edge corrections were made. Edges naming a point out of range are skipped.
    pub fn limit(&self, x: &[Vec3], d: &mut [Vec3]) -> usize {
        let n = x.len().min(d.len());
        let mut fixed = 0;
        for _ in 0..self.passes {
            let mut this_pass = 0;
            for &[i, j] in &self.edges {
                let (i, j) = (i as usize, j as usize);
                if i >= n || j >= n {
                    continue;
                }
                let l0 = (x[i] - x[j]).norm();
                let e = (x[i] + d[i]) - (x[j] + d[j]);
                let l = e.norm();
                if !(l > 1e-12 && l0 > 1e-12) {
                    continue;
                }
                let target = l.clamp((1.0 - self.slack) * l0, (1.0 + self.slack) * l0);
                if target == l {
                    continue;
                }
                let corr = e * (0.5 * (1.0 - target / l));
                d[i] -= corr;
                d[j] += corr;
                this_pass += 1;
            }
            fixed += this_pass;
            if this_pass == 0 {
                break;
            }
        }
        fixed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of two triangles: 0-1-2 and 1-3-2, unit square in the xy plane.
    fn square() -> (Vec<Vec3>, CarryEdges) {
        let x = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        (x, CarryEdges::of_triangles(&[[0, 1, 2], [1, 3, 2]]))
    }

    fn lengths(x: &[Vec3], d: &[Vec3], e: &CarryEdges) -> Vec<Real> {
        e.edges
            .iter()
            .map(|&[i, j]| {
                ((x[i as usize] + d[i as usize]) - (x[j as usize] + d[j as usize])).norm()
            })
            .collect()
    }

    #[test]
    fn each_edge_is_listed_once() {
        let (_, e) = square();
        assert_eq!(e.edges, vec![[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]);
    }

    #[test]
    fn a_rigid_carry_is_left_as_it_is() {
        let (x, e) = square();
        let r = tryon_core::math::UnitQuat::from_axis_angle(&Vec3::z_axis(), 0.7);
        let mut d: Vec<Vec3> = x
            .iter()
            .map(|p| r * p + Vec3::new(0.3, -2.0, 1.0) - p)
            .collect();
        let before = d.clone();
        assert_eq!(e.limit(&x, &mut d), 0);
        assert_eq!(d, before);
    }

    #[test]
    fn a_carry_that_tears_an_edge_is_held_within_the_slack_both_ways() {
        let (x, e) = square();
        // Vertex 3 carried 0.5 away from the others (a limb pulling one corner), vertex 0 pushed
        // 0.5 into the square.
        let mut d = vec![Vec3::zeros(); 4];
        d[3] = Vec3::new(0.5, 0.5, 0.0);
        d[0] = Vec3::new(0.5, 0.5, 0.0) * 0.6;
        assert!(e.limit(&x, &mut d) > 0);
        let rest = lengths(&x, &[Vec3::zeros(); 4], &e);
        for (l, l0) in lengths(&x, &d, &e).iter().zip(&rest) {
            // Gauss-Seidel passes leave the last edges exact and the first near.
            assert!(
                *l <= 1.1 * l0 + 0.02 && *l >= 0.9 * l0 - 0.02,
                "{l} against {l0}"
            );
        }
        // The whole moved on the mean: the carry's sum is kept (each correction is equal and
        // opposite).
        let sum: Vec3 = d.iter().sum();
        assert!((sum - Vec3::new(0.8, 0.8, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn edges_naming_points_that_are_not_there_are_skipped() {
        let (x, _) = square();
        let e = CarryEdges::of_triangles(&[[0, 1, 9]]);
        let mut d = vec![Vec3::zeros(); 4];
        d[1] = Vec3::new(5.0, 0.0, 0.0);
        e.limit(&x, &mut d);
        assert!(d.iter().all(|v| v.iter().all(|c| c.is_finite())));
        assert!((d[1] - d[0]).norm() < 5.0);
    }
}
