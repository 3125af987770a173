//! The layers' fail-safe for moves made outside the solve's bounds: the body's fail-safe
//! projecting a vertex out of a limb, and the body following's carry (each vertex moved with its
//! nearest body face, fully near the body and less farther out, so a limb swinging forward
//! carries an inner layer through the outer one). Of each pair such a move closed to under its
//! kept gap, the side that moved less toward the other yields, moving out along the pair's normal
//! until the gap is back; what yields is a moved side for the next pass, so a stack of layers
//! opens outward.

use super::{REST_SHARE, SelfContacts, Stencil};
use tryon_core::math::{Real, Vec3};

/// A pair keeps at least this share of its thickness (or of its distance before the move, when
/// nearer) after the fail-safe.
const KEEP_SHARE: Real = 0.5;

/// Passes: a stack of this many layers over a pushed one opens.
const KEEP_PASSES: usize = 4;

/// Farthest a carry's pairs are looked for (m).
const CARRY_REACH: Real = 0.05;

/// Opens the pairs `stencils` that moves `x - from` closed to under their kept gap (see the
/// module's note); returns the vertices it moved.
fn open_pairs(
    stencils: &[Stencil],
    x: &mut [Vec3],
    from: &[Vec3],
    fixed: impl Fn(usize) -> bool,
) -> usize {
    let mut shifted = vec![false; x.len()];
    let mut push = vec![Vec3::zeros(); x.len()];
    for _ in 0..KEEP_PASSES {
        push.iter_mut().for_each(|p| *p = Vec3::zeros());
        let mut any = false;
        for st in stencils {
            let offset: Vec3 = (0..4).map(|m| x[st.v[m] as usize] * st.w[m]).sum();
            let want = (KEEP_SHARE * st.thickness).min(REST_SHARE * st.gap);
            let deficit = want - offset.dot(&st.normal);
            if !(deficit > 0.0) {
                continue;
            }
            // How far each side moved toward the other along the normal.
            let toward = |positive: bool| -> Real {
                let sign = if positive { -1.0 } else { 1.0 };
                (0..4)
                    .filter(|&m| st.w[m] != 0.0 && (st.w[m] > 0.0) == positive)
                    .map(|m| {
                        let v = st.v[m] as usize;
                        sign * st.w[m].abs() * (x[v] - from[v]).dot(&st.normal)
                    })
                    .sum()
            };
            let (a_pos, a_neg) = (toward(true), toward(false));
            if a_pos <= 0.0 && a_neg <= 0.0 {
                // Neither side moved toward the other: the solve's own contact, not a push.
                continue;
            }
            let (to_pos, to_neg) = if a_pos > a_neg {
                (0.0, deficit)
            } else {
                (deficit, 0.0)
            };
            for m in 0..4 {
                let (v, w) = (st.v[m] as usize, st.w[m]);
                let d = match w {
                    w if w > 0.0 => st.normal * to_pos,
                    w if w < 0.0 => -st.normal * to_neg,
                    _ => continue,
                };
                if d.norm_squared() > push[v].norm_squared() && !fixed(v) {
                    push[v] = d;
                    any = true;
                }
            }
        }
        if !any {
            break;
        }
        for (v, p) in push.iter().enumerate() {
            if *p != Vec3::zeros() {
                x[v] += p;
                shifted[v] = true;
            }
        }
    }
    shifted.iter().filter(|&&s| s).count()
}

impl SelfContacts {
    /// After the body's fail-safe moved `x` from `before` (both within this step's detection):
    /// the step's pairs it closed opened again. Returns the vertices moved.
    pub fn keep_apart(
        &self,
        x: &mut [Vec3],
        before: &[Vec3],
        fixed: impl Fn(usize) -> bool,
    ) -> usize {
        open_pairs(&self.stencils, x, before, fixed)
    }

    /// After a carry moved the cloth from `from` (where no pair crossed) to `x`: the pairs at
    /// `from` that the carry brought within their kept gap, or through each other, opened again.
    /// Returns the vertices moved.
    pub fn carry_apart(
        &mut self,
        x: &mut [Vec3],
        from: &[Vec3],
        fixed: impl Fn(usize) -> bool,
    ) -> usize {
        let p = self.params;
        // The carry less its mean (the body's translation, which moves every layer alike): two
        // vertices close by at most the sum of their departures from it.
        let n = x.len().max(1) as Real;
        let mean: Vec3 = x.iter().zip(from).map(|(a, b)| a - b).sum::<Vec3>() / n;
        let reach: Vec<Real> = x
            .iter()
            .zip(from)
            .map(|(a, b)| (2.0 * (a - b - mean).norm() + p.thickness).min(CARRY_REACH))
            .collect();
        let found = self.find(from, &reach);
        let stencils: Vec<Stencil> = found
            .into_iter()
            .filter(|(key, _)| !self.rest_near.contains(key))
            .map(|(_, (mut st, dist))| {
                st.gap = dist;
                st.thickness = p.thickness.min(REST_SHARE * self.rest_distance(&st));
                st
            })
            .collect();
        open_pairs(&stencils, x, from, fixed)
    }
}
