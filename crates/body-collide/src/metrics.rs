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
