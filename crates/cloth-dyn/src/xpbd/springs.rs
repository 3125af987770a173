//! P3's (and Provot's) bend springs as XPBD constraints: each spring of the model's bend set (the
//! two vertices opposite an interior edge) is a compliant distance constraint whose compliance is
//! the spring's own rest length over its stiffness (the spring force `k / L (|x| - L)` of P1's
//! eq. 1 is the energy XPBD's compliance `L / k` stands for), so a stiffened or shortened spring
//! (the folds' bend changes, `ClothModel::change_bends`) acts at any step with no cost in stability.

use super::constraints::colour;
use crate::model::ClothModel;
use std::ops::Range;
use tryon_core::math::{Real, Vec3};

/// One bend spring as a constraint.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BendSpring {
    pub i: u32,
    pub j: u32,
    pub rest: Real,
    /// Compliance when longer than rest (m/N).
    pub stretch_compliance: Real,
    /// Compliance when shorter than rest (m/N).
    pub compress_compliance: Real,
}

/// The model's bend springs with a stiffness but for those `change_bends` changed (a fold's, which
/// the solver holds by their hinges' angles instead), coloured (no two of a colour share a
/// particle); the rest lengths are the model's (already scaled by the garment's rest scale).
pub fn bend_springs(model: &ClothModel) -> (Vec<BendSpring>, Vec<Range<usize>>) {
    let s = &model.springs;
    let changed: std::collections::HashSet<usize> =
        model.changed_bends.iter().map(|c| c.0).collect();
    let list: Vec<usize> = model
        .bend
        .clone()
        .filter(|&k| (s.k_stretch[k] > 0.0 || s.k_compress[k] > 0.0) && !changed.contains(&k))
        .collect();
    let pairs: Vec<[u32; 2]> = list.iter().map(|&k| [s.i[k], s.j[k]]).collect();
    let refs: Vec<&[u32]> = pairs.iter().map(|p| &p[..]).collect();
    let (order, colours) = colour(&refs, model.particle_count());
    let compliance = |k: Real, rest: Real| if k > 0.0 { rest / k } else { Real::INFINITY };
    let springs = order
        .iter()
        .map(|&o| {
            let k = list[o as usize];
            BendSpring {
                i: s.i[k],
                j: s.j[k],
                rest: s.rest[k],
                stretch_compliance: compliance(s.k_stretch[k], s.rest[k]),
                compress_compliance: compliance(s.k_compress[k], s.rest[k]),
            }
        })
        .collect();
    (springs, colours)
}

/// One pass over `springs` (in order) for a substep of length `h`.
pub fn solve(springs: &[BendSpring], inv_mass: &[Real], x: &mut [Vec3], h: Real) {
    let h2 = h * h;
    for s in springs {
        let (i, j) = (s.i as usize, s.j as usize);
        let wsum = inv_mass[i] + inv_mass[j];
        let d = x[i] - x[j];
        let len = d.norm();
        if wsum == 0.0 || len < 1e-12 {
            continue;
        }
        let c = len - s.rest;
        let alpha = if c > 0.0 {
            s.stretch_compliance
        } else {
            s.compress_compliance
        } / h2;
        if !alpha.is_finite() {
            continue;
        }
        let n = d / len;
        let dl = -c / (wsum + alpha);
        x[i] += n * (inv_mass[i] * dl);
        x[j] -= n * (inv_mass[j] * dl);
    }
}

/// `hinges` (each as `[a, b, c, d]`, `c` and `d` opposite the shared edge `a`-`b`) with their
/// compliance scales: a hinge whose opposite vertices are the ends of a bend spring
/// `change_bends` changed gets its compliance divided by that spring's stiffness scale, the others
/// 1; with `only_changed`, the others are left out. A fold's stiffened bend spring (P3 3.5) so
/// becomes a hinge held at the folded rest angle and stiffened by the same factor: a spring across
/// a shallow angle hardly resists bending (its length changes to second order in the angle), the
/// angle does.
pub fn scaled_hinges(
    model: &ClothModel,
    hinges: &[[u32; 4]],
    only_changed: bool,
) -> Vec<([u32; 4], Real)> {
    let s = &model.springs;
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    // A spring changed more than once has the product of its scales, as its stiffness does.
    let mut scale: std::collections::HashMap<(u32, u32), Real> = Default::default();
    for &(k, f) in &model.changed_bends {
        *scale.entry(key(s.i[k], s.j[k])).or_insert(1.0) *= f;
    }
    hinges
        .iter()
        .filter_map(|h| match scale.get(&key(h[2], h[3])) {
            Some(f) => Some((*h, 1.0 / f)),
            None if only_changed => None,
            None => Some((*h, 1.0)),
        })
        .collect()
}
