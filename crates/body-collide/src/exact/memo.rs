//! What the exact collider found for recent point sets, and its queries over a point set.

use super::{ExactCollider, NONE, PAR_CHUNK, Projection};
use rayon::prelude::*;
use tryon_core::math::{Real, Vec3};

/// What was found is kept for this many point sets (told apart by their length): a scene probes
/// its coarse particles and its fine vertices in turn, and each keeps its own.
const MEMO_SETS: usize = 4;

/// A query's answer ([`ExactCollider::search`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Near {
    /// The nearest point on the body.
    Found(Projection),
    /// Outside, with no body surface nearer than this.
    Beyond(Real),
    /// A non-finite point, or a body with no triangle.
    Invalid,
}

/// What was found for the points of one set: per point, where it was last asked, on which shape
/// of the body ([`ExactCollider::shape`]), what that established (`clear` 0: `found` is the
/// answer there; over 0: no surface within `clear`, outside), and the last projection found,
/// whose face starts the next search. A point asked again where it was, on the same shape, gets
/// the same answer without a search (the cloth solver probes its particles where the last step's
/// fail-safe left them).
#[derive(Clone, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct Memo {
    pub at: Vec<Vec3>,
    shape: Vec<u64>,
    clear: Vec<Real>,
    pub found: Vec<Option<Projection>>,
}

impl Memo {
    fn new(n: usize) -> Self {
        Memo {
            at: vec![Vec3::repeat(Real::NAN); n],
            shape: vec![u64::MAX; n],
            clear: vec![0.0; n],
            found: vec![None; n],
        }
    }

    /// The answer kept for point `k` at `p` on `shape`, if it answers a query with `cutoff`:
    /// asked again where it was, what was found there; moved on the same shape, a point that was
    /// outside with no surface within some distance is still outside with none within that
    /// distance less its move (the distance to a still surface changes no faster than the point
    /// moves), which answers a query whose cutoff is no farther.
    fn reuse(&self, k: usize, p: &Vec3, shape: u64, cutoff: Real) -> Option<Near> {
        if self.shape[k] != shape {
            return None;
        }
        let same = (0..3).all(|a| p[a].to_bits() == self.at[k][a].to_bits());
        if same {
            return match (self.clear[k], self.found[k]) {
                (c, _) if c > 0.0 => (c >= cutoff).then_some(Near::Beyond(c)),
                (_, Some(pr)) => Some(Near::Found(pr)),
                (_, None) => Some(Near::Invalid),
            };
        }
        let clear = match (self.clear[k], self.found[k]) {
            (c, _) if c > 0.0 => c,
            (_, Some(pr)) if pr.distance > 0.0 => pr.distance,
            _ => return None,
        };
        let clear = clear - (p - self.at[k]).norm();
        (clear >= cutoff && clear.is_finite()).then_some(Near::Beyond(clear))
    }

    fn keep(&mut self, k: usize, p: Vec3, shape: u64, near: Near) {
        (self.at[k], self.shape[k]) = (p, shape);
        match near {
            Near::Found(pr) => (self.clear[k], self.found[k]) = (0.0, Some(pr)),
            // The last face found stays, as the next search's start.
            Near::Beyond(c) => self.clear[k] = c,
            Near::Invalid => (self.clear[k], self.found[k]) = (0.0, None),
        }
    }
}

impl ExactCollider {
    /// The memo of point sets of `n` points, taken out (put back with `put_memo`); a new set
    /// has none, and the oldest is dropped when [`MEMO_SETS`] are kept.
    pub(super) fn take_memo(&mut self, n: usize) -> Memo {
        match self.memos.iter().position(|m| m.at.len() == n) {
            Some(k) => self.memos.remove(k),
            None => Memo::new(n),
        }
    }

    pub(super) fn put_memo(&mut self, memo: Memo) {
        if self.memos.len() >= MEMO_SETS {
            self.memos.remove(0);
        }
        self.memos.push(memo);
    }

    /// Each listed point's answer (all points for `None`) for a caller that needs the surface
    /// nearer than `cutoff` (infinite: the whole search), in parallel: the memo's answer for a
    /// point asked at the same place on the same shape, else a search from the face found for it
    /// last time (the same answer from any start, to the bit: `on_lower_face`).
    pub(super) fn project_all(
        &mut self,
        points: &[Vec3],
        which: Option<&[u32]>,
        cutoff: Real,
    ) -> Vec<Near> {
        let mut memo = self.take_memo(points.len());
        let (this, m) = (&*self, &memo);
        let one = |k: usize| {
            let p = &points[k];
            m.reuse(k, p, this.shape, cutoff)
                .unwrap_or_else(|| this.search(p, m.found[k].map_or(NONE, |f| f.face), cutoff))
        };
        let found: Vec<Near> = match which {
            Some(w) => w
                .par_iter()
                .with_min_len(PAR_CHUNK)
                .map(|&k| one(k as usize))
                .collect(),
            None => (0..points.len())
                .into_par_iter()
                .with_min_len(PAR_CHUNK)
                .map(one)
                .collect(),
        };
        let mut answers = Vec::with_capacity(found.len());
        for (j, near) in found.into_iter().enumerate() {
            let k = which.map_or(j, |w| w[j] as usize);
            memo.keep(k, points[k], self.shape, near);
            answers.push(near);
        }
        self.put_memo(memo);
        answers
    }

    /// Signed distances of all `points` (`None` where there is none), as
    /// [`tryon_core::stages::Collider::signed_distance`] gives them, found from the faces of the
    /// last call for a set of this length: the referee's per-frame query.
    pub fn signed_distances(&mut self, points: &[Vec3]) -> Vec<Option<Real>> {
        self.project_all(points, None, Real::INFINITY)
            .into_iter()
            .map(|near| match near {
                Near::Found(pr) => Some(pr.distance),
                _ => None,
            })
            .collect()
    }
}
