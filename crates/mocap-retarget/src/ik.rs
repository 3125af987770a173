//! Analytic two-bone IK for a leg (P1.6): hip fixed, thigh and shin lengths fixed, ankle toward a
//! target, knee in the plane given by a pole direction. Unreachable targets give a straight leg
//! pointing at the target (never NaN at full extension); targets too close give a fully bent leg.

use tryon_core::math::{Mat3, Real, Vec3};

/// A solved leg: knee and ankle positions, and whether the target was reached.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LegSolution {
    pub knee: Vec3,
    pub ankle: Vec3,
    pub reached: bool,
}

/// Any unit vector perpendicular to `u`.
fn any_perpendicular(u: &Vec3) -> Vec3 {
    let a = if u.x.abs() < 0.9 {
        Vec3::x()
    } else {
        Vec3::y()
    };
    u.cross(&a).normalize()
}

/// Places the knee and ankle for a hip at `hip`, bone lengths `l1` (thigh) and `l2` (shin), ankle
/// target `target`, knee toward `pole` (any vector; only its part across the hip-target line counts).
pub fn solve_leg(hip: Vec3, target: Vec3, l1: Real, l2: Real, pole: Vec3) -> LegSolution {
    let to = target - hip;
    let dist = to.norm();
    let u = if dist > 1e-12 { to / dist } else { -Vec3::y() };
    let mut side = pole - u * pole.dot(&u);
    side = match side.try_normalize(1e-9) {
        Some(s) => s,
        None => any_perpendicular(&u),
    };
    let reach = l1 + l2;
    let near = (l1 - l2).abs();
    let d = dist.clamp(near, reach);
    // Knee: along u by a, across by h (law of cosines), clamped so that full extension gives h = 0.
    let a = if d > 1e-12 {
        (l1 * l1 - l2 * l2 + d * d) / (2.0 * d)
    } else {
        0.0
    };
    let h = (l1 * l1 - a * a).max(0.0).sqrt();
    let knee = hip + u * a + side * h;
    let ankle = hip + u * d;
    LegSolution {
        knee,
        ankle,
        reached: (dist - d).abs() <= 1e-12 * reach.max(1.0),
    }
}

/// The rotation taking the frame (`d0`, `n0`) to (`d1`, `n1`): directions are matched exactly, the
/// normals after projection across them.
pub fn frame_rotation(d0: Vec3, n0: Vec3, d1: Vec3, n1: Vec3) -> Mat3 {
    let frame = |d: Vec3, n: Vec3| {
        let d = d.normalize();
        let n = (n - d * n.dot(&d))
            .try_normalize(1e-12)
            .unwrap_or_else(|| any_perpendicular(&d));
        Mat3::from_columns(&[d, n, d.cross(&n)])
    };
    frame(d1, n1) * frame(d0, n0).transpose()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn v3() -> impl Strategy<Value = Vec3> {
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn reaches_every_reachable_target(
            hip in v3(), dir in v3(), pole in v3(),
            l1 in 0.2..0.6f64, l2 in 0.2..0.6f64, f in 0.0..1.0f64,
        ) {
            prop_assume!(dir.norm() > 1e-3);
            let near = (l1 - l2).abs() + 1e-6;
            let far = l1 + l2;
            let d = near + (far - near) * f;
            let target = hip + dir.normalize() * d;
            let s = solve_leg(hip, target, l1, l2, pole);
            prop_assert!((s.ankle - target).norm() < 1e-6);
            prop_assert!(((s.knee - hip).norm() - l1).abs() < 1e-9);
            prop_assert!(((s.ankle - s.knee).norm() - l2).abs() < 1e-9);
            prop_assert!(s.reached);
        }

        #[test]
        fn unreachable_targets_give_a_straight_leg_toward_them(
            hip in v3(), dir in v3(), pole in v3(),
            l1 in 0.2..0.6f64, l2 in 0.2..0.6f64, extra in 0.0..2.0f64,
        ) {
            prop_assume!(dir.norm() > 1e-3);
            let u = dir.normalize();
            let target = hip + u * (l1 + l2 + extra);
            let s = solve_leg(hip, target, l1, l2, pole);
            prop_assert!(s.knee.iter().chain(s.ankle.iter()).all(|x| x.is_finite()));
            prop_assert!((s.knee - (hip + u * l1)).norm() < 1e-6);
            prop_assert!((s.ankle - (hip + u * (l1 + l2))).norm() < 1e-9);
        }
    }

    #[test]
    fn knee_bends_toward_the_pole() {
        let s = solve_leg(
            Vec3::zeros(),
            Vec3::new(0.0, -0.7, 0.0),
            0.4,
            0.4,
            Vec3::z(),
        );
        assert!(s.knee.z > 0.1 && s.knee.x.abs() < 1e-12);
        // The pole along the leg gives no side: still a valid, finite knee.
        let s = solve_leg(
            Vec3::zeros(),
            Vec3::new(0.0, -0.7, 0.0),
            0.4,
            0.4,
            -Vec3::y(),
        );
        assert!(((s.knee).norm() - 0.4).abs() < 1e-12);
    }

    #[test]
    fn frame_rotation_maps_direction_and_normal() {
        let r = frame_rotation(-Vec3::y(), -Vec3::x(), Vec3::z(), -Vec3::x());
        assert!((r * -Vec3::y() - Vec3::z()).norm() < 1e-12);
        assert!((r * -Vec3::x() + Vec3::x()).norm() < 1e-12);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
    }
}
