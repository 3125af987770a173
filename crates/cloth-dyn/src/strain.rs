//! Provot's (1995) deformation constraint: after a substep, edges stretched beyond a ratio of their
//! rest length are shortened back to it by moving both ends (in proportion to their inverse masses,
//! so momentum is kept), in Gauss-Seidel passes of alternating direction.

use crate::model::ClothModel;
use tryon_core::math::{Real, Vec3};

/// A one-sided plane constraint `normal . x[point] >= offset` (a body contact held during the passes).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ContactPlane {
    pub point: u32,
    pub normal: Vec3,
    pub offset: Real,
}

const UNREACHED: u32 = u32::MAX;

/// Long-range attachments (after Kim, Chentanez & Mueller 2012) to the particles that hold the cloth:
/// pins and handles. (Anchoring to body contacts as well was tried on the drape scene and made it
/// unstable: the contact set is large and changes every substep.) Each other particle reachable from
/// them is tethered to
/// its nearest anchor (fewest springs) at the rest length of that path, times the strain limit. A path's
/// rest length is never shorter than what the springs along it allow, so tethers never fight the
/// spring limits; they carry a hanging cloth's weight to its support at once, where Gauss-Seidel
/// passes would need a number of passes growing with the hanging length.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Tethers {
    anchor: Vec<u32>,
    rest: Vec<Real>,
    level: Vec<u32>,
    queue: Vec<u32>,
}

impl Tethers {
    /// Finds each particle's anchor and tether rest length by a multi-source breadth-first search over
    /// the structural and shear springs. Without anchors there are no tethers.
    pub fn compute(&mut self, model: &ClothModel) {
        let n = model.particle_count();
        self.level.clear();
        self.level.resize(n, UNREACHED);
        self.anchor.clear();
        self.anchor.resize(n, UNREACHED);
        self.rest.clear();
        self.rest.resize(n, 0.0);
        self.queue.clear();
        for a in (0..n as u32).filter(|&i| model.inv_mass[i as usize] == 0.0) {
            if self.level[a as usize] == UNREACHED {
                self.level[a as usize] = 0;
                self.anchor[a as usize] = a;
                self.queue.push(a);
            }
        }
        let g = &model.limit_graph;
        let mut head = 0;
        while head < self.queue.len() {
            let v = self.queue[head] as usize;
            head += 1;
            let row = g.offsets[v] as usize..g.offsets[v + 1] as usize;
            for (&w, &r) in g.items[row.clone()]
                .iter()
                .zip(&model.limit_graph_rest[row])
            {
                let w = w as usize;
                let d = self.rest[v] + r;
                if self.level[w] == UNREACHED {
                    self.level[w] = self.level[v] + 1;
                    self.rest[w] = d;
                    self.anchor[w] = self.anchor[v];
                    self.queue.push(w as u32);
                } else if self.level[w] == self.level[v] + 1 && d < self.rest[w] {
                    self.rest[w] = d;
                    self.anchor[w] = self.anchor[v];
                }
            }
        }
    }

    /// Pulls every tethered particle back within `max_ratio` times its tether's rest length of its anchor.
    pub fn project(&self, max_ratio: Real, x: &mut [Vec3]) {
        for i in 0..self.anchor.len() {
            let a = self.anchor[i];
            if a == UNREACHED || a as usize == i {
                continue;
            }
            let d = x[i] - x[a as usize];
            let max_len = max_ratio * self.rest[i];
            let len2 = d.norm_squared();
            if len2 > max_len * max_len {
                x[i] = x[a as usize] + d * (max_len / len2.sqrt());
            }
        }
    }
}

/// Limits structural and shear springs to `max_ratio` times rest length. Each correction is scaled by
/// `relaxation` (successive over-relaxation: 1 is plain Gauss-Seidel; up to about 1.8 converges
/// much faster on long hanging chains). After every pass each contact particle is put back on the
/// outer side of its contact plane, so the limit and the body do not undo each other. Returns how
/// many corrections were made in the last pass (0 means the limit holds everywhere).
pub fn limit_strain(
    model: &ClothModel,
    max_ratio: Real,
    iterations: u32,
    relaxation: Real,
    x: &mut [Vec3],
    planes: &[ContactPlane],
    tethers: Option<&Tethers>,
    min_bend_ratio: Option<Real>,
) -> usize {
    let springs = &model.limit_springs;
    let mut last = 0;
    for it in 0..iterations {
        if let Some(t) = tethers {
            t.project(max_ratio, x);
        }
        // Bending first, so the stretch limit has the last word in every pass.
        if let Some(r) = min_bend_ratio {
            bend_pass(&model.bend_limit_springs, r, x);
        }
        // Long-range constraints (coarse scales first) before the springs themselves.
        limit_pass(model.long_range_springs.iter(), max_ratio, 1.0, x);
        let count = if it % 2 == 0 {
            limit_pass(springs.iter(), max_ratio, relaxation, x)
        } else {
            limit_pass(springs.iter().rev(), max_ratio, relaxation, x)
        };
        for c in planes {
            let p = &mut x[c.point as usize];
            let d = c.normal.dot(p) - c.offset;
            if d < 0.0 {
                *p -= c.normal * d;
            }
        }
        last = count;
        if count == 0 {
            break;
        }
    }
    last
}

/// One Gauss-Seidel pass over `springs` in the given order; returns how many were corrected.
#[inline]
fn limit_pass<'a>(
    springs: impl Iterator<Item = &'a LimitSpring>,
    max_ratio: Real,
    relaxation: Real,
    x: &mut [Vec3],
) -> usize {
    let mut count = 0;
    for s in springs {
        let (i, j) = (s.i as usize, s.j as usize);
        let d = x[j] - x[i];
        let max_len = max_ratio * s.rest;
        let len2 = d.norm_squared();
        if len2 <= max_len * max_len {
            continue;
        }
        let len = len2.sqrt();
        let corr = d * (relaxation * (len - max_len) / len);
        x[i] += corr * s.wi;
        x[j] -= corr * s.wj;
        count += 1;
    }
    count
}

/// Pushes apart the ends of bending springs shorter than `min_ratio` times rest length.
fn bend_pass(springs: &[LimitSpring], min_ratio: Real, x: &mut [Vec3]) {
    for s in springs {
        let (i, j) = (s.i as usize, s.j as usize);
        let d = x[j] - x[i];
        let min_len = min_ratio * s.rest;
        let len2 = d.norm_squared();
        if len2 >= min_len * min_len || len2 < 1e-24 {
            continue;
        }
        let len = len2.sqrt();
        let corr = d * ((len - min_len) / len);
        x[i] += corr * s.wi;
        x[j] -= corr * s.wj;
    }
}

/// A spring the strain limit acts on, with its ends' shares of a correction (inverse mass over the
/// pair's total; zero for both when neither end can move, which makes the spring a no-op).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LimitSpring {
    pub i: u32,
    pub j: u32,
    pub rest: Real,
    pub wi: Real,
    pub wj: Real,
}

impl LimitSpring {
    /// A limit spring between i and j, or `None` when neither end can move.
    pub fn new(i: u32, j: u32, rest: Real, inv_mass: &[Real]) -> Option<Self> {
        let (a, b) = (inv_mass[i as usize], inv_mass[j as usize]);
        let w = a + b;
        (w > 0.0).then(|| LimitSpring {
            i,
            j,
            rest,
            wi: a / w,
            wj: b / w,
        })
    }
}

/// The structural and shear springs of `model`'s spring set packed for the strain limit.
pub fn limit_springs(
    springs: &crate::model::SpringSet,
    range: std::ops::Range<usize>,
    inv_mass: &[Real],
) -> Vec<LimitSpring> {
    range
        .filter_map(|k| {
            let (i, j) = (springs.i[k], springs.j[k]);
            let (a, b) = (inv_mass[i as usize], inv_mass[j as usize]);
            let w = a + b;
            (w > 0.0).then(|| LimitSpring {
                i,
                j,
                rest: springs.rest[k],
                wi: a / w,
                wj: b / w,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::ClothParams;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn tethers_hold_a_hanging_strip_in_two_passes() {
        // A 1 x 30 strip pinned at both top corners, every edge stretched 50%.
        let pins = [0u32, 1].map(|p| crate::model::Handle {
            particle: p,
            path: vec![(0.0, Vec3::zeros())],
        });
        let m = ClothModel::build(
            &grid_xz(1, 30, 0.03, 1.0, 0.0),
            &ClothParams::default(),
            pins.to_vec(),
        )
        .unwrap();
        let stretched = |m: &ClothModel| -> Vec<Vec3> {
            m.rest_positions
                .iter()
                .map(|p| p.component_mul(&Vec3::new(1.0, 1.0, 1.5)))
                .collect()
        };
        let worst = |x: &[Vec3]| {
            (0..m.shear.end)
                .map(|k| {
                    (x[m.springs.i[k] as usize] - x[m.springs.j[k] as usize]).norm()
                        / m.springs.rest[k]
                })
                .fold(0.0, Real::max)
        };
        let mut tethers = Tethers::default();
        tethers.compute(&m);
        let mut with = stretched(&m);
        limit_strain(&m, 1.02, 2, 1.0, &mut with, &[], Some(&tethers), None);
        let mut without = stretched(&m);
        limit_strain(&m, 1.02, 2, 1.0, &mut without, &[], None, None);
        let (w, wo) = (worst(&with), worst(&without));
        assert!(w < 1.03, "with tethers the strip is at {w}");
        assert!(
            wo > 1.1,
            "without tethers two passes should not suffice ({wo})"
        );
        // The far end is within the limit of the pins.
        assert!((with[61] - with[1]).norm() <= 1.02 * 1.0 + 1e-9);
    }

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
        limit_strain(&m, 1.05, 50, 1.0, &mut x, &[], None, None);
        let after: Vec3 = x.iter().zip(&m.mass).map(|(p, m)| p * *m).sum();
        assert!((before - after).norm() < 1e-12);
        for k in 0..m.shear.end {
            let (i, j) = (m.springs.i[k] as usize, m.springs.j[k] as usize);
            let ratio = (x[i] - x[j]).norm() / m.springs.rest[k];
            assert!(ratio < 1.0501, "spring {k} still at {ratio}");
        }
    }
}
