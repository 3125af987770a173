//! A spatial hash of the body's vertices (Teschner et al. 2003): cells of a fixed size hashed into
//! a table, the vertices of each bucket stored contiguously. It answers "the nearest vertex within
//! r" exactly, which P1's hill-climbing tracker cannot: a climb stops at a local minimum of the
//! distance, and between two legs the nearest vertex of one leg is such a minimum while the point
//! is already inside the other (makehuman-dress-walk's skirt hem went 43 mm into the right calf
//! while its tracked vertex stayed on the left leg, 145 mm away).

use tryon_core::math::{Real, Vec3};

/// The hashed vertices.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct VertexGrid {
    cell: Real,
    /// Bucket b holds `items[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
}

/// Most cells a query visits along an axis before it looks at every point instead.
const MAX_SPAN: i64 = 8;

/// Floor of `x` as an integer (saturating), without a call to libm's `floor`.
#[inline]
pub(crate) fn floor_i(x: Real) -> i64 {
    let i = x as i64;
    if (i as Real) > x { i - 1 } else { i }
}

#[inline]
pub(crate) fn cell_of(p: &Vec3, inv: Real) -> [i64; 3] {
    [floor_i(p.x * inv), floor_i(p.y * inv), floor_i(p.z * inv)]
}

/// The bucket of a cell; `mask` is the bucket count (a power of two) less one.
#[inline]
pub(crate) fn bucket(c: [i64; 3], mask: usize) -> usize {
    let h = (c[0].wrapping_mul(73_856_093))
        ^ (c[1].wrapping_mul(19_349_663))
        ^ (c[2].wrapping_mul(83_492_791));
    (h as u64 as usize) & mask
}

impl VertexGrid {
    /// Hashes `points` into cells of side `cell` (m).
    pub fn new(points: &[Vec3], cell: Real) -> Self {
        let mut g = VertexGrid {
            cell,
            starts: Vec::new(),
            items: Vec::new(),
        };
        g.rebuild(points);
        g
    }

    /// Hashes the points again (the body moved), reusing the storage.
    pub fn rebuild(&mut self, points: &[Vec3]) {
        let buckets = (2 * points.len()).max(1).next_power_of_two();
        let inv = 1.0 / self.cell;
        let of = |p: &Vec3| {
            if p.iter().all(|c| c.is_finite()) {
                bucket(cell_of(p, inv), buckets - 1)
            } else {
                0
            }
        };
        self.starts.clear();
        self.starts.resize(buckets + 1, 0);
        for p in points {
            self.starts[of(p) + 1] += 1;
        }
        for b in 0..buckets {
            self.starts[b + 1] += self.starts[b];
        }
        self.items.clear();
        self.items.resize(points.len(), 0);
        let mut fill: Vec<u32> = self.starts[..buckets].to_vec();
        for (i, p) in points.iter().enumerate() {
            let b = of(p);
            self.items[fill[b] as usize] = i as u32;
            fill[b] += 1;
        }
    }

    /// The nearest of `points` (the slice the grid was built from) to `p` that is nearer than
    /// `r`, with its squared distance. `r` should not exceed a few cells: every cell the ball
    /// touches is visited.
    pub fn nearest_within(&self, points: &[Vec3], p: &Vec3, r: Real) -> Option<(u32, Real)> {
        self.nearest_within_where(points, p, r, |_| true)
    }

    /// As [`VertexGrid::nearest_within`], among the points `keep` accepts.
    pub fn nearest_within_where(
        &self,
        points: &[Vec3],
        p: &Vec3,
        r: Real,
        keep: impl Fn(u32) -> bool,
    ) -> Option<(u32, Real)> {
        let buckets = self.starts.len().saturating_sub(1);
        if buckets == 0 || !(r > 0.0) || !p.iter().all(|c| c.is_finite()) {
            return None;
        }
        let inv = 1.0 / self.cell;
        let lo = cell_of(&p.add_scalar(-r), inv);
        let hi = cell_of(&p.add_scalar(r), inv);
        let mut best: Option<(u32, Real)> = None;
        let mut limit = r * r;
        if (0..3).any(|a| hi[a].saturating_sub(lo[a]) > MAX_SPAN) {
            // A ball of many cells: every point is fewer to look at.
            for (i, q) in points.iter().enumerate() {
                let d = (q - p).norm_squared();
                if d < limit && keep(i as u32) {
                    limit = d;
                    best = Some((i as u32, d));
                }
            }
            return best;
        }
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    let b = bucket([x, y, z], buckets - 1);
                    let (s, e) = (self.starts[b] as usize, self.starts[b + 1] as usize);
                    for &i in &self.items[s..e] {
                        let d = (points[i as usize] - p).norm_squared();
                        if d < limit && keep(i) {
                            limit = d;
                            best = Some((i, d));
                        }
                    }
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute(points: &[Vec3], p: &Vec3, r: Real) -> Option<Real> {
        brute_where(points, p, r, |_| true)
    }

    fn brute_where(points: &[Vec3], p: &Vec3, r: Real, keep: impl Fn(u32) -> bool) -> Option<Real> {
        points
            .iter()
            .enumerate()
            .filter(|(i, _)| keep(*i as u32))
            .map(|(_, q)| (q - p).norm_squared())
            .filter(|&d| d < r * r)
            .fold(None, |a: Option<Real>, d| Some(a.map_or(d, |a| a.min(d))))
    }

    proptest! {
        #[test]
        fn finds_the_nearest_point_within_r_as_a_search_of_all_would(
            pts in prop::collection::vec((-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64), 1..200),
            q in (-1.2..1.2f64, -1.2..1.2f64, -1.2..1.2f64),
            r in 0.01..0.5f64,
            cell in 0.02..0.3f64,
        ) {
            let points: Vec<Vec3> = pts.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
            let p = Vec3::new(q.0, q.1, q.2);
            let g = VertexGrid::new(&points, cell);
            let got = g.nearest_within(&points, &p, r).map(|(i, d)| {
                assert_eq!(d, (points[i as usize] - p).norm_squared());
                d
            });
            prop_assert_eq!(got, brute(&points, &p, r));
            // Among every third point only.
            let third = |i: u32| i % 3 == 1;
            let got = g.nearest_within_where(&points, &p, r, third).map(|(i, d)| {
                assert!(third(i));
                d
            });
            prop_assert_eq!(got, brute_where(&points, &p, r, third));
        }
    }

    #[test]
    fn non_finite_points_are_neither_found_nor_a_panic() {
        let points = vec![Vec3::new(Real::NAN, 0.0, 0.0), Vec3::new(0.1, 0.0, 0.0)];
        let g = VertexGrid::new(&points, 0.05);
        assert_eq!(
            g.nearest_within(&points, &Vec3::zeros(), 0.2).map(|h| h.0),
            Some(1)
        );
        assert_eq!(
            g.nearest_within(&points, &Vec3::new(Real::INFINITY, 0.0, 0.0), 0.2),
            None
        );
    }
}
