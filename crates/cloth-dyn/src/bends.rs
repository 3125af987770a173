//! Bend springs changed after the model is built: P3 3.5 shortens and stiffens the bend springs
//! that cross a fold's ridge line, so that simulation keeps the fold.

use crate::model::ClothModel;
use tryon_core::math::Real;

/// A change to the bend spring joining particles `a` and `b`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BendChange {
    pub a: u32,
    pub b: u32,
    /// Its rest length times this.
    pub rest_scale: Real,
    /// Its stiffness and damping times this.
    pub stiffness_scale: Real,
}

impl ClothModel {
    /// Applies `changes` to the model's bend springs; returns how many springs changed (a change
    /// naming no bend spring, or with a scale that is not finite and above 0, changes nothing).
    pub fn change_bends(&mut self, changes: &[BendChange]) -> usize {
        let index: std::collections::HashMap<(u32, u32), usize> = self
            .bend
            .clone()
            .map(|k| {
                let (i, j) = (self.springs.i[k], self.springs.j[k]);
                ((i.min(j), i.max(j)), k)
            })
            .collect();
        if self.spring_scale.len() < self.springs.len() {
            self.spring_scale.resize(self.springs.len(), 1.0);
        }
        let ok = |s: Real| s.is_finite() && s > 0.0;
        let mut changed = 0;
        for c in changes {
            let Some(&k) = index.get(&(c.a.min(c.b), c.a.max(c.b))) else {
                continue;
            };
            if !(ok(c.rest_scale) && ok(c.stiffness_scale)) {
                continue;
            }
            let s = &mut self.springs;
            s.rest[k] *= c.rest_scale;
            s.k_stretch[k] *= c.stiffness_scale;
            s.k_compress[k] *= c.stiffness_scale;
            s.damping[k] *= c.stiffness_scale;
            self.spring_scale[k] *= c.stiffness_scale;
            self.changed_bends.push((k, c.stiffness_scale));
            changed += 1;
        }
        if changed > 0 {
            // The force loop reads the packed copy: without this the changes reach only the
            // limits (found in session 48: the folds' springs had kept their old forces).
            self.packed = self.springs.packed();
            self.bend_limit_springs =
                crate::strain::limit_springs(&self.springs, self.bend.clone(), &self.inv_mass);
        }
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ClothParams;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn only_the_named_bend_springs_change() {
        let mesh = grid_xz(4, 4, 1.0, 1.0, 0.0);
        let p = ClothParams {
            k_bend: 2.0,
            ..ClothParams::default()
        };
        let mut m = ClothModel::build(&mesh, &p, vec![]).unwrap();
        let before = m.clone();
        let k = m.bend.start + 3;
        let (a, b) = (m.springs.i[k], m.springs.j[k]);
        let changes = [
            BendChange {
                a: b,
                b: a,
                rest_scale: 0.5,
                stiffness_scale: 4.0,
            },
            // A structural spring's ends, and a bad scale: no change.
            BendChange {
                a: m.springs.i[0],
                b: m.springs.j[0],
                rest_scale: 0.5,
                stiffness_scale: 4.0,
            },
            BendChange {
                a,
                b,
                rest_scale: Real::NAN,
                stiffness_scale: 4.0,
            },
        ];
        assert_eq!(m.change_bends(&changes), 1);
        assert_eq!(m.springs.rest[k], 0.5 * before.springs.rest[k]);
        assert_eq!(m.springs.k_stretch[k], 4.0 * before.springs.k_stretch[k]);
        assert_eq!(m.spring_scale[k], 4.0);
        for s in (0..m.springs.len()).filter(|&s| s != k) {
            assert_eq!(m.springs.rest[s], before.springs.rest[s]);
            assert_eq!(m.springs.k_stretch[s], before.springs.k_stretch[s]);
            assert_eq!(m.spring_scale[s], 1.0);
        }
        // The force loop's copy: the changed spring's rest halved, its damping times 4.
        let (old, new) = (&before.packed[k], &m.packed[k]);
        assert_eq!((new.i, new.j), (a, b));
        assert_eq!(new.rest, 0.5 * old.rest);
        assert_eq!(new.damping, 4.0 * old.damping);
        assert_eq!(m.packed[0], before.packed[0]);
    }
}
