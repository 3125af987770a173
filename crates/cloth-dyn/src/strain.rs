//! Provot's (1995) deformation constraint: after a substep, edges stretched beyond a ratio of their
//! rest length are shortened back to it by moving both ends (in proportion to their inverse masses,
//! so momentum is kept), in Gauss-Seidel passes of alternating direction.

use crate::model::ClothModel;
use tryon_core::math::{Real, Vec3};

/// Limits structural and shear springs to `max_ratio` times rest length. Returns how many
/// corrections were made in the last pass (0 means the limit holds everywhere).
pub fn limit_strain(model: &ClothModel, max_ratio: Real, iterations: u32, x: &mut [Vec3]) -> usize {
    let s = &model.springs;
    let end = model.shear.end.max(model.structural.end);
    let mut last = 0;
    for it in 0..iterations {
        let mut count = 0;
        let mut correct = |k: usize, x: &mut [Vec3]| {
            let (i, j) = (s.i[k] as usize, s.j[k] as usize);
            let (wi, wj) = (model.inv_mass[i], model.inv_mass[j]);
            let w = wi + wj;
            if w == 0.0 {
                return;
            }
            let d = x[j] - x[i];
            let max_len = max_ratio * s.rest[k];
            let len2 = d.norm_squared();
            if len2 <= max_len * max_len {
                return;
            }
            let len = len2.sqrt();
            let corr = d * ((len - max_len) / (len * w));
            x[i] += corr * wi;
            x[j] -= corr * wj;
            count += 1;
        };
        if it % 2 == 0 {
            (0..end).for_each(|k| correct(k, x));
        } else {
            (0..end).rev().for_each(|k| correct(k, x));
        }
        last = count;
        if count == 0 {
            break;
        }
    }
    last
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ClothParams;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn stretched_grid_is_pulled_back_with_momentum_kept() {
        let m = ClothModel::build(
            &grid_xz(4, 4, 1.0, 1.0, 0.0),
            &ClothParams::default(),
            vec![],
        )
        .unwrap();
        let mut x: Vec<Vec3> = m
            .rest_positions
            .iter()
            .map(|p| p.component_mul(&Vec3::new(1.5, 1.0, 1.0)))
            .collect();
        let before: Vec3 = x.iter().zip(&m.mass).map(|(p, m)| p * *m).sum();
        limit_strain(&m, 1.05, 50, &mut x);
        let after: Vec3 = x.iter().zip(&m.mass).map(|(p, m)| p * *m).sum();
        assert!((before - after).norm() < 1e-12);
        for k in 0..m.shear.end {
            let (i, j) = (m.springs.i[k] as usize, m.springs.j[k] as usize);
            let ratio = (x[i] - x[j]).norm() / m.springs.rest[k];
            assert!(ratio < 1.0501, "spring {k} still at {ratio}");
        }
    }
}
