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

/// Farthest one pass of a reopening moves a side, as a share of the pair's kept gap (so at most
/// `KEEP_PASSES` times that in all). A pair closed by more than its gap has been pushed through
/// (or its stencil, whose weights date from detection, no longer names the nearest points):
/// moving its yielding side by the whole deficit threw seam vertices 7 and 27 mm in one move on
/// the casual suit and tore their edges. Held to this, such a pair is left crossing (the referee
/// counts it) rather than the cloth torn. A quarter let the running layered mannequin cross
/// (docs/decisions, *reopening cap*).
const MOST_PUSH: Real = 0.5;

/// Which side of `st` yields: true for the side of positive weights. Where the vertices' body
/// distances (`depth`, one per vertex, or empty) put one side more than a thickness farther out,
/// that outer side, which moves away from the body; else the side that moved less toward the
/// other (`a_pos`, `a_neg`). An inner layer made to
/// yield would be pushed into the body, and the solve's swept body contact, which keeps each
/// vertex on the side it starts on, would then hold it there.
fn yielding_positive(st: &Stencil, depth: &[Real], (a_pos, a_neg): (Real, Real)) -> bool {
    let side = |positive: bool| -> Option<Real> {
        (0..4)
            .filter(|&m| st.w[m] != 0.0 && (st.w[m] > 0.0) == positive)
            .map(|m| depth.get(st.v[m] as usize).map(|d| st.w[m].abs() * d))
            .sum()
    };
    // Side by side (within a thickness of the same depth) there is no outer side.
    let apart = |a: Real, b: Real| a > b + st.thickness;
    match (side(true), side(false)) {
        (Some(p), Some(n)) if apart(p, n) => true,
        (Some(p), Some(n)) if apart(n, p) => false,
        _ => a_pos <= a_neg,
    }
}

/// Opens the pairs `stencils` that moves `x - from` closed to under their kept gap (see the
/// module's note; `depth`: each vertex's body distance, or empty); returns the vertices it moved.
fn open_pairs(
    stencils: &[Stencil],
    x: &mut [Vec3],
    (from, depth): (&[Vec3], &[Real]),
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
            let deficit = (want - offset.dot(&st.normal)).min(MOST_PUSH * st.thickness);
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
            let (to_pos, to_neg) = if yielding_positive(st, depth, (a_pos, a_neg)) {
                (deficit, 0.0)
            } else {
                (0.0, deficit)
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
    /// the step's pairs it closed opened again, the outer side yielding where `depth` (each
    /// vertex's body distance at `x`, or empty) says which it is. Returns the vertices moved.
    pub fn keep_apart(
        &self,
        x: &mut [Vec3],
        (before, depth): (&[Vec3], &[Real]),
        fixed: impl Fn(usize) -> bool,
    ) -> usize {
        open_pairs(&self.stencils, x, (before, depth), fixed)
    }

    /// After a carry moved the cloth from `from` (where no pair crossed) to `x`: the pairs at
    /// `from` that the carry brought within their kept gap, or through each other, opened again
    /// (`depth` as for [`SelfContacts::keep_apart`]).
    /// Returns the vertices moved.
    pub fn carry_apart(
        &mut self,
        x: &mut [Vec3],
        (from, depth): (&[Vec3], &[Real]),
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
        open_pairs(&stencils, x, (from, depth), fixed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Vertex 0 over triangle (1, 2, 3), 2 mm apart along +y, keeping 3 mm.
    fn pair() -> Stencil {
        Stencil {
            v: [0, 1, 2, 3],
            w: [1.0, -1.0 / 3.0, -1.0 / 3.0, -1.0 / 3.0],
            edges: false,
            normal: Vec3::y(),
            lambda: 0.0,
            gap: 0.002,
            thickness: 0.003,
        }
    }

    #[test]
    fn the_outer_side_yields_whichever_moved() {
        // The vertex moved toward the triangle, which did not move: by motion the triangle
        // would yield, but it is the inner layer (1 cm from the body against the vertex's 2 cm):
        // pushed, it would go toward the body. The vertex yields.
        let moved = (1.0, 0.0);
        assert!(yielding_positive(&pair(), &[0.02, 0.01, 0.01, 0.01], moved));
        // The vertex inner: the triangle yields, outward.
        assert!(!yielding_positive(
            &pair(),
            &[0.01, 0.02, 0.02, 0.02],
            (0.0, 1.0)
        ));
        // Side by side (within a thickness) or with no depths: the side that moved less.
        assert!(!yielding_positive(
            &pair(),
            &[0.011, 0.01, 0.01, 0.01],
            moved
        ));
        assert!(!yielding_positive(&pair(), &[], moved));
        assert!(yielding_positive(&pair(), &[], (0.0, 1.0)));
    }

    #[test]
    fn a_pair_pushed_closed_by_the_inner_layer_opens_outward() {
        // The inner triangle (y = 0.01) was pushed 2 mm up by the body's fail-safe toward the
        // vertex (y = 0.014): the vertex (outer) moves up to keep half the thickness.
        let from = vec![
            Vec3::new(0.0, 0.014, 0.0),
            Vec3::new(-0.1, 0.008, -0.1),
            Vec3::new(0.1, 0.008, -0.1),
            Vec3::new(0.0, 0.008, 0.1),
        ];
        let mut x = from.clone();
        for p in x.iter_mut().skip(1) {
            p.y = 0.0135;
        }
        let depth = [0.014, 0.0135, 0.0135, 0.0135];
        let mut st = pair();
        st.gap = 0.006;
        let moved = open_pairs(&[st], &mut x, (&from, &depth), |_| false);
        assert_eq!(moved, 1);
        assert!((x[0].y - (0.0135 + 0.0015)).abs() < 1e-12, "{:?}", x[0]);
        assert!(
            x.iter().skip(1).all(|p| p.y == 0.0135),
            "the inner layer stays"
        );
    }

    #[test]
    fn a_pair_pushed_through_moves_its_yielding_side_by_at_most_half_its_gap_a_pass() {
        // The inner triangle was pushed 3 cm up, through the vertex 4 mm over it: opening it
        // fully would throw the vertex 27.5 mm. Each pass moves it by half the kept gap (1.5 mm).
        let from = vec![
            Vec3::new(0.0, 0.014, 0.0),
            Vec3::new(-0.1, 0.010, -0.1),
            Vec3::new(0.1, 0.010, -0.1),
            Vec3::new(0.0, 0.010, 0.1),
        ];
        let mut x = from.clone();
        for p in x.iter_mut().skip(1) {
            p.y = 0.040;
        }
        // No body depths: the side that moved less (the vertex) yields.
        let mut st = pair();
        st.gap = 0.004;
        open_pairs(&[st], &mut x, (&from, &[]), |_| false);
        let moved = (x[0].y - 0.014).abs();
        let most = KEEP_PASSES as Real * 0.0015;
        assert!(moved > 0.0 && moved <= most + 1e-12, "moved {moved}");
    }
}
