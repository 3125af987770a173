//! What holds a garment vertex to the body: the baseline detachment is judged against.
//!
//! A vertex far from the body is not detached by itself: a flared hem swings more than 10 cm
//! farther from the legs than where it started on every stride of a walk. It is detached when
//! nothing explains the distance, that is when it is [`DETACHED`] farther from the body than at
//! the start and either
//! - the cloth between it and the nearest cloth touching the body is too short to hang it there
//!   (a tear, or no cloth connected to it touches at all): its distance exceeds [`SLACK`] times
//!   that path's length at the start plus [`TOUCH`], or
//! - the cloth touching the body nearest to it is [`DETACHED`] farther along the garment than at
//!   the start (it slipped off what held it: a jacket off a shoulder, trousers off the hips).
//!
//! Paths run over the output mesh's edges at their lengths in the first frame.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use tryon_core::math::{Real, Vec3};

/// A garment vertex this much farther from the body than it started may be detached (m).
pub const DETACHED: Real = 0.1;
/// Cloth within this distance of the body touches it (m).
pub const TOUCH: Real = 0.01;
/// How far a path of cloth may stretch while it holds a hanging vertex: the stretch target.
pub const SLACK: Real = 1.1;

/// Each output vertex's distance to the body at the start and its path to the cloth then
/// touching the body, and the output mesh's edges with their lengths at the start.
#[derive(Clone, Debug, Default)]
pub struct Baseline {
    /// Signed distance to the body at the start (m); missing entries count as 0.
    pub distance: Vec<Real>,
    /// Path length over the garment to the nearest vertex touching the body at the start (m;
    /// infinite where none is connected).
    pub reach: Vec<Real>,
    /// Neighbours of vertex `i`: `edges[first[i]..first[i + 1]]`, with the edge's length.
    first: Vec<usize>,
    edges: Vec<(u32, Real)>,
}

impl Baseline {
    /// The baseline of a garment whose output vertices start at `positions` with signed
    /// distances `distance`, meshed by `triangles` (indices out of range are passed over).
    pub fn new(distance: Vec<Real>, triangles: &[[u32; 3]], positions: &[Vec3]) -> Baseline {
        let n = positions.len();
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(triangles.len() * 6);
        for t in triangles {
            if t.iter().any(|&v| v as usize >= n) {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b {
                    pairs.push((a, b));
                    pairs.push((b, a));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut first = vec![0usize; n + 1];
        for &(a, _) in &pairs {
            first[a as usize + 1] += 1;
        }
        for i in 0..n {
            first[i + 1] += first[i];
        }
        let edges = pairs
            .iter()
            .map(|&(a, b)| (b, (positions[a as usize] - positions[b as usize]).norm()))
            .collect();
        let mut base = Baseline {
            distance,
            reach: Vec::new(),
            first,
            edges,
        };
        base.reach = base.reach_from(&base.distance);
        base
    }

    /// A baseline of distances alone, with no mesh (no paths): every vertex [`DETACHED`] farther
    /// from the body than it started is detached.
    pub fn without_mesh(distance: Vec<Real>) -> Baseline {
        Baseline {
            distance,
            ..Baseline::default()
        }
    }

    /// Path length over the start's edge lengths from every vertex to the nearest vertex whose
    /// signed distance in `signed` is under [`TOUCH`] (Dijkstra from all of them at once).
    pub fn reach_from(&self, signed: &[Real]) -> Vec<Real> {
        let n = signed.len();
        let mut reach = vec![Real::INFINITY; n];
        let mut heap = BinaryHeap::new();
        for (i, &d) in signed.iter().enumerate() {
            if d < TOUCH {
                reach[i] = 0.0;
                heap.push(Reverse((Key(0.0), i as u32)));
            }
        }
        while let Some(Reverse((Key(r), i))) = heap.pop() {
            let i = i as usize;
            if r > reach[i] || i + 1 >= self.first.len() {
                continue;
            }
            for &(j, len) in &self.edges[self.first[i]..self.first[i + 1]] {
                let j = j as usize;
                let rj = r + len;
                if j < n && rj < reach[j] {
                    reach[j] = rj;
                    heap.push(Reverse((Key(rj), j as u32)));
                }
            }
        }
        reach
    }

    /// Share of vertices detached at signed distances `signed` (see the module's rule).
    pub fn detached_share(&self, signed: &[Real]) -> Real {
        if signed.is_empty() {
            return 0.0;
        }
        let start = |i: usize| self.distance.get(i).copied().unwrap_or(0.0).max(0.0);
        let far: Vec<usize> = (0..signed.len())
            .filter(|&i| signed[i] > start(i) + DETACHED)
            .collect();
        if far.is_empty() {
            return 0.0;
        }
        let reach = self.reach_from(signed);
        let detached = far
            .iter()
            .filter(|&&i| {
                let unheld = !reach[i].is_finite() || signed[i] > SLACK * reach[i] + TOUCH;
                let before = self.reach.get(i).copied().unwrap_or(0.0);
                unheld || reach[i] > before + DETACHED
            })
            .count();
        detached as Real / signed.len() as Real
    }
}

/// A path length ordered for the heap (lengths are finite and not NaN).
#[derive(Clone, Copy, PartialEq)]
struct Key(Real);

impl Eq for Key {}

impl PartialOrd for Key {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Key {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed distances to a ball of radius 0.5 at the origin.
    fn ball(x: &[Vec3]) -> Vec<Real> {
        x.iter().map(|p| p.norm() - 0.5).collect()
    }

    fn at_angle(a: Real) -> Vec3 {
        Vec3::new(0.505 * a.sin(), 0.505 * a.cos(), 0.0)
    }

    #[test]
    fn a_hem_swung_out_on_cloth_long_enough_to_hold_it_is_not_detached() {
        // A 0.2 m strip from a touching vertex; its end swings from beside the ball to straight
        // out, 0.16 m farther than it started.
        let start = [Vec3::new(0.0, 0.505, 0.0), Vec3::new(0.2, 0.505, 0.0)];
        let base = Baseline::new(ball(&start), &[[0, 1, 1]], &start);
        let swung = [start[0], Vec3::new(0.0, 0.705, 0.0)];
        assert!(ball(&swung)[1] > ball(&start)[1] + DETACHED);
        assert_eq!(base.detached_share(&ball(&swung)), 0.0);
    }

    #[test]
    fn a_vertex_farther_than_its_cloth_can_hang_is_detached() {
        // The same strip's end 0.4 m out: twice the strip's length (a tear).
        let start = [Vec3::new(0.0, 0.505, 0.0), Vec3::new(0.2, 0.505, 0.0)];
        let base = Baseline::new(ball(&start), &[[0, 1, 1]], &start);
        let torn = [start[0], Vec3::new(0.0, 0.9, 0.0)];
        assert_eq!(base.detached_share(&ball(&torn)), 0.5);
        // With nothing touching, nothing holds it.
        let fallen = [Vec3::new(0.0, 0.9, 0.0), Vec3::new(0.0, 1.1, 0.0)];
        assert_eq!(base.detached_share(&ball(&fallen)), 1.0);
        // Without a mesh (no paths), every vertex 10 cm farther is detached.
        let bare = Baseline::without_mesh(ball(&start));
        assert_eq!(bare.detached_share(&ball(&torn)), 0.5);
    }

    #[test]
    fn cloth_that_slid_off_what_held_it_is_detached_though_still_connected() {
        // Three vertices lying on the ball at the start; then only the first touches and the
        // others hang straight out from it, as far as their cloth reaches.
        let start = [at_angle(0.0), at_angle(0.3), at_angle(0.6)];
        let base = Baseline::new(ball(&start), &[[0, 1, 2]], &start);
        assert_eq!(base.reach, vec![0.0; 3]);
        let chord = (start[0] - start[1]).norm();
        let hung = [
            start[0],
            Vec3::new(0.0, 0.505 + chord, 0.0),
            Vec3::new(0.0, 0.505 + 1.95 * chord, 0.0),
        ];
        let signed = ball(&hung);
        assert!(
            signed[2] < SLACK * base.reach_from(&signed)[2] + TOUCH,
            "held by length"
        );
        assert!((base.detached_share(&signed) - 2.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn paths_take_the_shortest_way_and_skip_bad_indices() {
        let x = [
            Vec3::new(0.0, 0.505, 0.0),
            Vec3::new(0.1, 0.6, 0.0),
            Vec3::new(0.0, 0.8, 0.0),
        ];
        let base = Baseline::new(ball(&x), &[[0, 1, 2], [0, 1, 9]], &x);
        let r = base.reach_from(&ball(&x));
        assert_eq!(r[0], 0.0);
        assert!((r[1] - (0.01f64 + 0.095 * 0.095).sqrt()).abs() < 1e-12);
        assert!(
            (r[2] - 0.295).abs() < 1e-12,
            "the direct edge 0-2, not via 1: {r:?}"
        );
        // A sheet that never touched and then fell is detached: nothing holds it.
        let above = [x[1], x[2], Vec3::new(0.0, 0.9, 0.0)];
        let fell = Baseline::new(ball(&above), &[[0, 1, 2]], &above);
        let below: Vec<Vec3> = above.iter().map(|p| -p * 2.0).collect();
        assert_eq!(fell.detached_share(&ball(&below)), 1.0);
    }
}
