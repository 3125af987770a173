//! Accuracy metrics: edge stretch and penetration (by the exact referee).

use body_collide::{ExactCollider, penetration_depths};
use tryon_core::math::{Real, Vec3};

/// Largest and mean ratio of current to rest length over the given edges.
pub fn stretch(edges: &[[u32; 2]], rest: &[Real], x: &[Vec3]) -> (Real, Real) {
    let mut max: Real = 0.0;
    let mut sum = 0.0;
    for (e, r) in edges.iter().zip(rest) {
        let ratio = (x[e[0] as usize] - x[e[1] as usize]).norm() / r;
        max = max.max(ratio);
        sum += ratio;
    }
    (
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
}

/// Penetration of `points` into the referee's body.
pub fn penetration(referee: &ExactCollider, points: &[Vec3]) -> Penetration {
    let mut d = penetration_depths(referee, points);
    if d.is_empty() {
        return Penetration::default();
    }
    d.sort_by(|a, b| a.total_cmp(b));
    let k = ((d.len() as Real * 0.99).ceil() as usize).clamp(1, d.len()) - 1;
    Penetration {
        max: d[d.len() - 1],
        p99: d[k],
        share_over_1mm: d.iter().filter(|x| **x > 1e-3).count() as Real / d.len() as Real,
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
        let (max, mean) = stretch(&[[0, 1], [1, 2]], &[1.0, 1.0], &x);
        assert_eq!((max, mean), (2.0, 1.5));
        assert_eq!(median(&[3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), 2.5);
    }

    #[test]
    fn penetration_counts_only_inside_points() {
        let referee = ExactCollider::new(&icosphere(0.5, 4, Vec3::zeros()), 0.0).unwrap();
        let pts: Vec<Vec3> = (0..100)
            .map(|i| Vec3::new(0.0, if i < 5 { 0.49 } else { 0.6 }, 0.0))
            .collect();
        let p = penetration(&referee, &pts);
        assert!(p.max > 0.009 && p.max < 0.0105, "{p:?}");
        assert_eq!(p.share_over_1mm, 0.05);
        assert!(
            p.p99 > 0.009,
            "99th percentile of 5% inside is inside: {p:?}"
        );
    }
}
