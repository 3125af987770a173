//! Accuracy metrics: edge stretch, penetration and detachment (by the exact referee).

use crate::ExactCollider;
use tryon_core::math::{Real, Vec3};

pub use crate::hold::{Baseline, DETACHED};

/// Signed distance of every point to the referee's body (0 where it cannot say): the baseline
/// [`penetration`] judges detachment against. Each point's query is its own, in parallel, started
/// from the face found for it at the last call (the same answer from any start, to the bit).
pub fn distances(referee: &mut ExactCollider, points: &[Vec3]) -> Vec<Real> {
    referee
        .signed_distances(points)
        .into_iter()
        .map(|d| d.unwrap_or(0.0))
        .collect()
}

/// Smallest, largest and mean ratio of current to rest length over the given edges (1, 0, 0 for
/// none).
pub fn stretch(edges: &[[u32; 2]], rest: &[Real], x: &[Vec3]) -> (Real, Real, Real) {
    let (mut min, mut max): (Real, Real) = (1.0, 0.0);
    let mut sum = 0.0;
    for (e, r) in edges.iter().zip(rest) {
        let ratio = (x[e[0] as usize] - x[e[1] as usize]).norm() / r;
        min = min.min(ratio);
        max = max.max(ratio);
        sum += ratio;
    }
    (
        min,
        max,
        if edges.is_empty() {
            0.0
        } else {
            sum / edges.len() as Real
        },
    )
}

/// Edge stretches counted in bins of [`StretchCounts::BIN`], for a percentile over many frames
/// (the last bin holds everything from [`StretchCounts::TOP`] up, with the largest seen).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StretchCounts {
    bins: Vec<u64>,
    total: u64,
    largest: Real,
}

impl StretchCounts {
    /// Width of a bin.
    pub const BIN: Real = 1e-4;
    /// Stretches from this up share the last bin.
    pub const TOP: Real = 4.0;

    /// Counts one stretch (a non-finite one in the last bin).
    pub fn add(&mut self, ratio: Real) {
        let last = (Self::TOP / Self::BIN) as usize;
        if self.bins.is_empty() {
            self.bins = vec![0; last + 1];
        }
        let bin = if ratio.is_finite() {
            ((ratio.max(0.0) / Self::BIN) as usize).min(last)
        } else {
            last
        };
        self.bins[bin] += 1;
        self.total += 1;
        self.largest = if ratio.is_finite() {
            self.largest.max(ratio)
        } else {
            Real::INFINITY
        };
    }

    /// The stretch below which the share `q` of those counted lie: the upper edge of its bin,
    /// or the largest counted when that is the last bin (0 when nothing was counted).
    pub fn quantile(&self, q: Real) -> Real {
        if self.total == 0 {
            return 0.0;
        }
        let rank = ((q * self.total as Real).ceil() as u64).clamp(1, self.total);
        let mut seen = 0;
        for (b, &n) in self.bins.iter().enumerate() {
            seen += n;
            if seen >= rank {
                return if b + 1 == self.bins.len() {
                    self.largest
                } else {
                    ((b + 1) as Real * Self::BIN).min(self.largest)
                };
            }
        }
        self.largest
    }
}

/// [`stretch`], each edge's ratio also counted into `counts`.
pub fn stretch_counted(
    edges: &[[u32; 2]],
    rest: &[Real],
    x: &[Vec3],
    counts: &mut StretchCounts,
) -> (Real, Real, Real) {
    for (e, r) in edges.iter().zip(rest) {
        counts.add((x[e[0] as usize] - x[e[1] as usize]).norm() / r);
    }
    stretch(edges, rest, x)
}

/// Penetration statistics of a set of points.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Penetration {
    /// Deepest point inside the body (m).
    pub max: Real,
    /// 99th percentile of depth over all points (m).
    pub p99: Real,
    /// Share of points deeper than 1 mm.
    pub share_over_1mm: Real,
    /// Share of points detached from the body by [`Baseline::detached_share`]'s rule: a garment
    /// that slid, tore or fell off reads here while its penetration reads 0 (a flared hem
    /// swinging out from the legs does not).
    pub detached_share: Real,
}

/// Penetration of `points` into the referee's body, and how many are detached compared with
/// `start` (see [`crate::hold`]).
pub fn penetration(referee: &mut ExactCollider, points: &[Vec3], start: &Baseline) -> Penetration {
    penetration_of(&distances(referee, points), start)
}

/// [`penetration`] from the points' signed distances to the body.
pub fn penetration_of(signed: &[Real], start: &Baseline) -> Penetration {
    if signed.is_empty() {
        return Penetration::default();
    }
    let detached = start.detached_share(signed);
    let mut d: Vec<Real> = signed.iter().map(|s| (-s).max(0.0)).collect();
    d.sort_by(|a, b| a.total_cmp(b));
    let k = ((d.len() as Real * 0.99).ceil() as usize).clamp(1, d.len()) - 1;
    Penetration {
        max: d[d.len() - 1],
        p99: d[k],
        share_over_1mm: d.iter().filter(|x| **x > 1e-3).count() as Real / d.len() as Real,
        detached_share: detached,
    }
}

/// Median of a list (0 for an empty one).
pub fn median(xs: &[Real]) -> Real {
    if xs.is_empty() {
        return 0.0;
    }
    let mut v = xs.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_counted_percentile_is_the_sorted_one_to_a_bin() {
        // 1,000 stretches spread over 0.9..1.4 in a scrambled order, and two torn edges.
        let mut values: Vec<Real> = (0..1000)
            .map(|k| 0.9 + ((k * 613) % 1000) as Real * 5e-4)
            .collect();
        values.extend([7.5, 24.0]);
        let mut counts = StretchCounts::default();
        values.iter().for_each(|&v| counts.add(v));
        values.sort_by(|a, b| a.total_cmp(b));
        for q in [0.5, 0.9, 0.99] {
            let sorted = values[((q * values.len() as Real).ceil() as usize) - 1];
            let counted = counts.quantile(q);
            assert!(
                counted >= sorted && counted <= sorted + StretchCounts::BIN,
                "q {q}: {counted} vs {sorted}"
            );
        }
        // Beyond the top bin, the largest counted.
        assert_eq!(counts.quantile(1.0), 24.0);
        assert_eq!(StretchCounts::default().quantile(0.99), 0.0);
    }
    use tryon_core::shapes::icosphere;

    #[test]
    fn stretch_and_median() {
        let x = vec![
            Vec3::zeros(),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
        ];
        let (min, max, mean) = stretch(&[[0, 1], [1, 2]], &[1.0, 1.0], &x);
        assert_eq!((min, max, mean), (1.0, 2.0, 1.5));
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }

    #[test]
    fn penetration_counts_only_inside_points() {
        let mut referee = ExactCollider::new(&icosphere(0.5, 4, Vec3::zeros()), 0.0).unwrap();
        let pts: Vec<Vec3> = (0..100)
            .map(|i| Vec3::new(0.0, if i < 5 { 0.49 } else { 0.6 }, 0.0))
            .collect();
        let none = Baseline::default();
        let p = penetration(&mut referee, &pts, &none);
        assert!(p.max > 0.009 && p.max < 0.0105, "{p:?}");
        assert_eq!(p.share_over_1mm, 0.05);
        assert!(
            p.p99 > 0.009,
            "99th percentile of 5% inside is inside: {p:?}"
        );
        // 0.6 is 0.1 m out: not detached; 0.65 is, unless it started 0.1 m out or more.
        assert_eq!(p.detached_share, 0.0);
        let far: Vec<Vec3> = (0..10)
            .map(|i| Vec3::new(0.0, if i < 3 { 0.65 } else { 0.55 }, 0.0))
            .collect();
        assert!((penetration(&mut referee, &far, &none).detached_share - 0.3).abs() < 1e-12);
        let started = Baseline::without_mesh(vec![0.12, 0.12, 0.0]);
        assert!((penetration(&mut referee, &far, &started).detached_share - 0.1).abs() < 1e-12);
        assert!((distances(&mut referee, &far)[0] - 0.15).abs() < 1e-3);
    }
}
