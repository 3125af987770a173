//! Whether two triangles intersect, by signs of volumes (the referee's narrow phase).
//!
//! Two triangles that are not coplanar intersect exactly when an edge of one passes through the
//! other: their intersection is a segment whose ends lie on the triangles' edges. An edge `pq`
//! passes through triangle `abc` when `p` and `q` lie on opposite sides of its plane and the line
//! `pq` passes inside it (the three volumes `pq` makes with the triangle's edges have one sign).
//! Every sign this takes is read from one determinant; when one is zero or too small to trust (a
//! vertex on the other's plane, an edge through a corner, coplanar triangles), the answer is
//! `None` and the caller asks an exact method (parry's GJK).

use tryon_core::math::{Real, Vec3};

/// Relative size below which a volume's sign is not trusted: a few rounding errors of the
/// products that make it.
const TRUST: Real = 1e-12;

/// The sign of the volume of tetrahedron `abcd` (positive when `d` is on the side of `abc`'s
/// normal), or `None` when it is too small next to the terms it was made from.
fn orient(a: &Vec3, b: &Vec3, c: &Vec3, d: &Vec3) -> Option<bool> {
    let (u, v, w) = (b - a, c - a, d - a);
    let n = u.cross(&v);
    let vol = n.dot(&w);
    let scale = u.norm() * v.norm() * w.norm();
    (vol.abs() > TRUST * scale).then_some(vol > 0.0)
}

/// Whether segment `pq` passes through triangle `t` (`None`: too close to call).
fn edge_through(p: &Vec3, q: &Vec3, t: &[Vec3; 3]) -> Option<bool> {
    let sp = orient(&t[0], &t[1], &t[2], p)?;
    let sq = orient(&t[0], &t[1], &t[2], q)?;
    if sp == sq {
        return Some(false);
    }
    let s0 = orient(p, q, &t[0], &t[1])?;
    let s1 = orient(p, q, &t[1], &t[2])?;
    let s2 = orient(p, q, &t[2], &t[0])?;
    Some(s0 == s1 && s1 == s2)
}

/// Whether triangles `a` and `b` intersect; `None` when a sign on the way is too close to call.
pub fn intersect(a: &[Vec3; 3], b: &[Vec3; 3]) -> Option<bool> {
    for (s, t) in [(a, b), (b, a)] {
        for k in 0..3 {
            if edge_through(&s[k], &s[(k + 1) % 3], t)? {
                return Some(true);
            }
        }
    }
    Some(false)
}

#[cfg(test)]
mod tests {
    use super::*;
    use parry3d_f64::math::{Isometry, Point};
    use parry3d_f64::query::intersection_test;
    use parry3d_f64::shape::Triangle;
    use proptest::prelude::*;

    fn parry(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
        let t =
            |x: &[Vec3; 3]| Triangle::new(Point::from(x[0]), Point::from(x[1]), Point::from(x[2]));
        let id = Isometry::identity();
        intersection_test(&id, &t(a), &id, &t(b)).unwrap()
    }

    fn tri(v: [f64; 9]) -> [Vec3; 3] {
        [
            Vec3::new(v[0], v[1], v[2]),
            Vec3::new(v[3], v[4], v[5]),
            Vec3::new(v[6], v[7], v[8]),
        ]
    }

    #[test]
    fn crossing_touching_and_apart_pairs() {
        let a = tri([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        // Pierces a's middle from below.
        let b = tri([0.2, 0.2, -0.5, 0.3, 0.2, 0.5, 0.2, 0.3, 0.5]);
        assert_eq!(intersect(&a, &b), Some(true));
        // The same, lifted off a.
        let up = b.map(|p| p + Vec3::new(0.0, 0.0, 0.6));
        assert_eq!(intersect(&a, &up), Some(false));
        // A straddling triangle beside a (its plane crossed, a itself missed).
        let side = b.map(|p| p + Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(intersect(&a, &side), Some(false));
        // Coplanar and a vertex on the other's plane: not called.
        let flat = a.map(|p| p + Vec3::new(0.1, 0.1, 0.0));
        assert_eq!(intersect(&a, &flat), None);
        let touch = tri([0.2, 0.2, 0.0, 0.3, 0.2, 0.5, 0.2, 0.3, 0.5]);
        assert_eq!(intersect(&a, &touch), None);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4000))]
        /// Wherever it answers, it answers as parry's GJK does; pairs are drawn near each other
        /// (corners within a unit box) so about half cross.
        #[test]
        fn agrees_with_parry(a in prop::array::uniform9(-1.0f64..1.0),
                             b in prop::array::uniform9(-1.0f64..1.0)) {
            let (a, b) = (tri(a), tri(b));
            if let Some(got) = intersect(&a, &b) {
                prop_assert_eq!(got, parry(&a, &b));
            }
        }

        /// Pairs at the cloth's scale, a millimetre apart or crossing by as little.
        #[test]
        fn agrees_with_parry_on_near_misses(a in prop::array::uniform9(-0.01f64..0.01),
                                            lift in -0.002f64..0.002,
                                            tilt in prop::array::uniform3(-0.3f64..0.3)) {
            let a = tri(a);
            let n = (a[1] - a[0]).cross(&(a[2] - a[0]));
            prop_assume!(n.norm() > 1e-6);
            let n = n.normalize();
            let c = (a[0] + a[1] + a[2]) / 3.0;
            let b = [0, 1, 2].map(|k| {
                let r = a[(k + 1) % 3] - c;
                c + r * 0.9 + n * (lift + tilt[k] * r.norm())
            });
            if let Some(got) = intersect(&a, &b) {
                prop_assert_eq!(got, parry(&a, &b));
            }
        }
    }
}
