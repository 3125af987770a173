//! Closest points between a point and a triangle, and between two segments (Ericson,
//! Real-Time Collision Detection, 5.1.5 and 5.1.9), as weights of the primitives' vertices.

use tryon_core::math::{Real, Vec3};

/// Barycentric weights of the point of triangle `(a, b, c)` nearest to `p`.
pub fn point_triangle(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> [Real; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(&ap), ac.dot(&ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(&bp), ac.dot(&bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(&cp), ac.dot(&cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let denom = va + vb + vc;
    if !(denom > 0.0) {
        // Degenerate (collapsed) triangle: its first corner.
        return [1.0, 0.0, 0.0];
    }
    let (v, w) = (vb / denom, vc / denom);
    [1.0 - v - w, v, w]
}

/// Parameters `(s, t)` in [0, 1] of the nearest points `p1 + s (q1 - p1)` and `p2 + t (q2 - p2)`
/// of two segments.
pub fn segment_segment(p1: &Vec3, q1: &Vec3, p2: &Vec3, q2: &Vec3) -> (Real, Real) {
    const EPS: Real = 1e-20;
    let (d1, d2, r) = (q1 - p1, q2 - p2, p1 - p2);
    let (a, e, f) = (d1.norm_squared(), d2.norm_squared(), d2.dot(&r));
    if a <= EPS && e <= EPS {
        return (0.0, 0.0);
    }
    if a <= EPS {
        return (0.0, (f / e).clamp(0.0, 1.0));
    }
    let c = d1.dot(&r);
    if e <= EPS {
        return ((-c / a).clamp(0.0, 1.0), 0.0);
    }
    let b = d1.dot(&d2);
    let denom = a * e - b * b;
    let mut s = if denom > EPS * a * e {
        ((b * f - c * e) / denom).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (s, t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v(a: [Real; 3]) -> Vec3 {
        Vec3::new(a[0], a[1], a[2])
    }

    fn coord() -> impl Strategy<Value = [Real; 3]> {
        [-1.0..1.0, -1.0..1.0, -1.0..1.0]
    }

    proptest! {
        /// No point of the triangle on a fine barycentric lattice is nearer than the one found.
        #[test]
        fn the_nearest_point_of_a_triangle_is_nearest(
            p in coord(), a in coord(), b in coord(), c in coord()
        ) {
            let (p, a, b, c) = (v(p), v(a), v(b), v(c));
            let w = point_triangle(&p, &a, &b, &c);
            prop_assert!(w.iter().all(|x| (-1e-12..=1.0 + 1e-12).contains(x)));
            prop_assert!((w.iter().sum::<Real>() - 1.0).abs() < 1e-9);
            let found = (p - (a * w[0] + b * w[1] + c * w[2])).norm();
            let n = 40;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, s) = (i as Real / n as Real, j as Real / n as Real);
                    let q = a * (1.0 - u - s) + b * u + c * s;
                    prop_assert!(found <= (p - q).norm() + 1e-9);
                }
            }
        }

        /// No pair of points on a lattice of the two segments is nearer than the pair found.
        #[test]
        fn the_nearest_points_of_two_segments_are_nearest(
            p1 in coord(), q1 in coord(), p2 in coord(), q2 in coord()
        ) {
            let (p1, q1, p2, q2) = (v(p1), v(q1), v(p2), v(q2));
            let (s, t) = segment_segment(&p1, &q1, &p2, &q2);
            prop_assert!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t));
            let found = (p1 + (q1 - p1) * s - p2 - (q2 - p2) * t).norm();
            let n = 60;
            for i in 0..=n {
                for j in 0..=n {
                    let (u, w) = (i as Real / n as Real, j as Real / n as Real);
                    let d = (p1 + (q1 - p1) * u - p2 - (q2 - p2) * w).norm();
                    prop_assert!(found <= d + 1e-9);
                }
            }
        }
    }

    #[test]
    fn parallel_and_collapsed_segments_are_handled() {
        let z = Vec3::zeros();
        let x = Vec3::x();
        let (s, t) = segment_segment(&z, &x, &(z + Vec3::y()), &(x + Vec3::y()));
        assert!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t));
        assert_eq!(segment_segment(&z, &z, &x, &x), (0.0, 0.0));
        assert_eq!(point_triangle(&x, &z, &z, &z), [1.0, 0.0, 0.0]);
    }
}
