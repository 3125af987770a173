//! Continuous point-triangle collision: the first time a moving point crosses a moving triangle
//! from its front (the side its outward normal points to) to its back. Every position moves
//! linearly over the interval [0, 1]. A crossing is a root of the cubic
//! f(t) = (p - a) . ((b - a) x (c - a)), zero when the point and the triangle are coplanar
//! (Provot 1997; Bridson, Fedkiw and Anderson 2002): the cubic is split at its turning points into
//! pieces on which it is monotone, each piece where f falls from >= 0 to <= 0 holds one inward
//! crossing of the plane, found by bisection, and the crossing counts when the point is then
//! inside the triangle. Outward crossings (a point leaving the body) are never reported.

use tryon_core::math::{Real, Vec3};

/// Slack on the barycentric coordinates at a crossing: a point crossing exactly on an edge
/// shared by two triangles must be caught by one of them despite rounding.
const BARY_SLACK: Real = 1e-7;

/// Bisection steps: the crossing time to 2^-48 of the interval.
const BISECT: usize = 48;

/// An inward crossing: when (fraction of the interval) and where in the triangle.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Crossing {
    pub t: Real,
    pub bary: [Real; 3],
}

/// A point or a triangle corner moving from `.0` to `.1`.
pub type Path = (Vec3, Vec3);

#[inline]
fn at(p: &Path, t: Real) -> Vec3 {
    p.0 + (p.1 - p.0) * t
}

/// The cubic's coefficients, lowest first.
fn coplanarity(p: &Path, [a, b, c]: &[Path; 3]) -> [Real; 4] {
    let da = a.1 - a.0;
    let p0 = p.0 - a.0;
    let dp = (p.1 - p.0) - da;
    let (e1, d1) = (b.0 - a.0, (b.1 - b.0) - da);
    let (e2, d2) = (c.0 - a.0, (c.1 - c.0) - da);
    let n0 = e1.cross(&e2);
    let n1 = e1.cross(&d2) + d1.cross(&e2);
    let n2 = d1.cross(&d2);
    [
        p0.dot(&n0),
        p0.dot(&n1) + dp.dot(&n0),
        p0.dot(&n2) + dp.dot(&n1),
        dp.dot(&n2),
    ]
}

#[inline]
fn eval(c: &[Real; 4], t: Real) -> Real {
    c[0] + t * (c[1] + t * (c[2] + t * c[3]))
}

/// The turning points of the cubic inside (0, 1), in order (at most two).
fn turning_points(c: &[Real; 4]) -> ([Real; 2], usize) {
    // f'(t) = c1 + 2 c2 t + 3 c3 t^2
    let (qa, qb, qc) = (3.0 * c[3], 2.0 * c[2], c[1]);
    let mut out = [0.0; 2];
    let mut n = 0;
    let mut push = |t: Real| {
        if t > 0.0 && t < 1.0 && t.is_finite() {
            out[n] = t;
            n += 1;
        }
    };
    let scale = qa.abs().max(qb.abs()).max(qc.abs());
    if scale == 0.0 {
        return (out, 0);
    }
    if qa.abs() <= 1e-12 * scale {
        if qb != 0.0 {
            push(-qc / qb);
        }
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            // The numerically stable pair of roots.
            let q = -0.5 * (qb + qb.signum() * disc.sqrt());
            let (r1, r2) = if q != 0.0 {
                (q / qa, qc / q)
            } else {
                (0.0, 0.0)
            };
            let (lo, hi) = if r1 < r2 { (r1, r2) } else { (r2, r1) };
            push(lo);
            if hi != lo {
                push(hi);
            }
        }
    }
    (out, n)
}

/// Barycentric coordinates of `p`'s projection onto the triangle's plane (`None` when the
/// triangle is degenerate).
fn barycentric(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> Option<[Real; 3]> {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
    let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
    let denom = d00 * d11 - d01 * d01;
    if !(denom > 1e-30 * d00 * d11) {
        return None;
    }
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    Some([1.0 - v - w, v, w])
}

/// The first inward crossing of point path `p` through the triangle whose corners move along
/// `tri` (counter-clockwise seen from the front), if any.
pub fn inward_crossing(p: &Path, tri: &[Path; 3]) -> Option<Crossing> {
    let c = coplanarity(p, tri);
    if !c.iter().all(|x| x.is_finite()) {
        return None;
    }
    let (turns, n) = turning_points(&c);
    let mut lo = 0.0;
    for k in 0..=n {
        let hi = if k < n { turns[k] } else { 1.0 };
        let (flo, fhi) = (eval(&c, lo), eval(&c, hi));
        if flo >= 0.0 && fhi <= 0.0 && (flo > 0.0 || fhi < 0.0) {
            let t = falling_root(&c, lo, hi);
            let corners = [at(&tri[0], t), at(&tri[1], t), at(&tri[2], t)];
            if let Some(bary) = barycentric(&at(p, t), &corners[0], &corners[1], &corners[2])
                && bary.iter().all(|&b| b >= -BARY_SLACK)
            {
                return Some(Crossing { t, bary });
            }
        }
        lo = hi;
    }
    None
}

/// The root of the cubic on [lo, hi], where it falls from >= 0 to <= 0: the end of the last
/// bisection bracket, so that the point is at or just past the plane.
fn falling_root(c: &[Real; 4], mut lo: Real, mut hi: Real) -> Real {
    for _ in 0..BISECT {
        let mid = 0.5 * (lo + hi);
        if eval(c, mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn still(v: Vec3) -> Path {
        (v, v)
    }

    /// A unit triangle in z = 0 facing +z.
    fn floor() -> [Path; 3] {
        [
            still(Vec3::new(0.0, 0.0, 0.0)),
            still(Vec3::new(1.0, 0.0, 0.0)),
            still(Vec3::new(0.0, 1.0, 0.0)),
        ]
    }

    #[test]
    fn a_point_falling_through_a_still_triangle_is_caught_where_it_crosses() {
        let p = (Vec3::new(0.2, 0.3, 0.4), Vec3::new(0.2, 0.3, -0.6));
        let hit = inward_crossing(&p, &floor()).expect("crossing");
        assert!((hit.t - 0.4).abs() < 1e-9, "t = {}", hit.t);
        assert!((hit.bary[1] - 0.2).abs() < 1e-9 && (hit.bary[2] - 0.3).abs() < 1e-9);
    }

    #[test]
    fn leaving_through_the_back_and_passing_beside_are_not_crossings() {
        let out = (Vec3::new(0.2, 0.3, -0.4), Vec3::new(0.2, 0.3, 0.6));
        assert_eq!(inward_crossing(&out, &floor()), None);
        let beside = (Vec3::new(0.8, 0.8, 0.4), Vec3::new(0.8, 0.8, -0.6));
        assert_eq!(inward_crossing(&beside, &floor()), None);
    }

    #[test]
    fn a_fast_triangle_sweeping_over_a_still_point_is_caught() {
        // The triangle moves up 10 m in the interval; the point sits 1 m above it at the start.
        let up = Vec3::new(0.0, 0.0, 10.0);
        let tri = floor().map(|(a, _)| (a, a + up));
        let p = still(Vec3::new(0.25, 0.25, 1.0));
        let hit = inward_crossing(&p, &tri).expect("swept over");
        assert!((hit.t - 0.1).abs() < 1e-9, "t = {}", hit.t);
    }

    #[test]
    fn a_tilting_triangle_is_caught_when_its_plane_reaches_the_point() {
        // Two corners rise: the plane tilts up through the still point at t = 0.25.
        let p = still(Vec3::new(0.2, 0.2, 0.05));
        let tri = [
            (Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.0)),
            (Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.5)),
            (Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.5)),
        ];
        let hit = inward_crossing(&p, &tri).expect("the plane rises through the point");
        assert!(hit.t > 0.0 && hit.t < 1.0);
    }

    #[test]
    fn a_crossing_on_a_shared_edge_is_caught_by_one_of_its_triangles() {
        let q = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let t1 = [still(q[0]), still(q[1]), still(q[2])];
        let t2 = [still(q[0]), still(q[2]), still(q[3])];
        let p = (Vec3::new(0.37, 0.37, 0.1), Vec3::new(0.37, 0.37, -0.1));
        assert!(inward_crossing(&p, &t1).is_some() || inward_crossing(&p, &t2).is_some());
    }

    #[test]
    fn non_finite_input_is_no_crossing() {
        let p = (Vec3::new(Real::NAN, 0.0, 0.0), Vec3::zeros());
        assert_eq!(inward_crossing(&p, &floor()), None);
    }

    fn v3() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        /// Checked against dense sampling: wherever the samples see the point go from in front of
        /// the triangle to behind it while inside it, the solver reports a crossing no later.
        #[test]
        fn no_sampled_inward_crossing_is_missed(
            p0 in v3(), p1 in v3(),
            a0 in v3(), b0 in v3(), c0 in v3(),
            da in v3(), db in v3(), dc in v3(),
        ) {
            let tri = [(a0, a0 + da * 0.3), (b0, b0 + db * 0.3), (c0, c0 + dc * 0.3)];
            let p = (p0, p1);
            let c = coplanarity(&p, &tri);
            let got = inward_crossing(&p, &tri);
            let samples = 2000;
            let mut prev = eval(&c, 0.0);
            for s in 1..=samples {
                let t = s as Real / samples as Real;
                let f = eval(&c, t);
                if prev > 0.0 && f < 0.0 {
                    let corners = [at(&tri[0], t), at(&tri[1], t), at(&tri[2], t)];
                    let inside = barycentric(&at(&p, t), &corners[0], &corners[1], &corners[2])
                        .is_some_and(|b| b.iter().all(|&x| x > 1e-3));
                    let corners0 = [at(&tri[0], t - 1.0 / samples as Real), at(&tri[1], t - 1.0 / samples as Real), at(&tri[2], t - 1.0 / samples as Real)];
                    let inside0 = barycentric(&at(&p, t - 1.0 / samples as Real), &corners0[0], &corners0[1], &corners0[2])
                        .is_some_and(|b| b.iter().all(|&x| x > 1e-3));
                    if inside && inside0 {
                        let hit = got.expect("a sampled inward crossing was missed");
                        prop_assert!(hit.t <= t + 1e-9, "reported {} after sampled {}", hit.t, t);
                    }
                }
                prev = f;
            }
            if let Some(hit) = got {
                // What is reported is a real crossing: coplanar there, inside, and in front before.
                prop_assert!(hit.t >= 0.0 && hit.t <= 1.0);
                prop_assert!(hit.bary.iter().all(|&b| b >= -BARY_SLACK));
                prop_assert!(eval(&c, hit.t) <= 0.0);
            }
        }
    }
}
