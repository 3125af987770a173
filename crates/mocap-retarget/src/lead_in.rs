//! A lead-in from another pose: a garment shaped on the body in one pose (a kimono put on with the
//! arms raised) starts there, and the body moves into the clip's first pose over `lead` seconds
//! before the clip plays.

use tryon_core::math::{Real, UnitQuat};
use tryon_core::measure::smoothstep;
use tryon_core::pose::Pose;
use tryon_core::stages::MotionSource;

/// `inner` delayed by `lead` seconds, which the body spends moving from `from` to `inner`'s first
/// pose (joint rotations slerped, the root's translation lerped, eased in and out).
pub struct LeadIn {
    pub from: Pose,
    pub lead: Real,
    pub inner: Box<dyn MotionSource>,
}

impl std::fmt::Debug for LeadIn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LeadIn").field("lead", &self.lead).finish()
    }
}

/// `a` to `b` at `s` in [0, 1]: each joint's rotation slerped, the root translation lerped. Joints
/// `a` lacks are taken from `b`.
pub fn blend_poses(a: &Pose, b: &Pose, s: Real) -> Pose {
    let slerp = |x: &UnitQuat, y: &UnitQuat| {
        x.try_slerp(y, s, 1e-9)
            .unwrap_or(if s < 0.5 { *x } else { *y })
    };
    Pose {
        time: b.time,
        root_translation: a.root_translation + (b.root_translation - a.root_translation) * s,
        local_rotations: b
            .local_rotations
            .iter()
            .enumerate()
            .map(|(j, q)| a.local_rotations.get(j).map_or(*q, |p| slerp(p, q)))
            .collect(),
    }
}

impl MotionSource for LeadIn {
    fn duration(&self) -> Real {
        self.lead + self.inner.duration()
    }

    fn sample(&self, t: Real, out: &mut Pose) {
        if t >= self.lead || !(self.lead > 0.0) {
            self.inner.sample(t - self.lead.max(0.0), out);
            out.time = t;
            return;
        }
        let mut first = Pose::default();
        self.inner.sample(0.0, &mut first);
        *out = blend_poses(&self.from, &first, smoothstep((t / self.lead).max(0.0)));
        out.time = t;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::math::Vec3;
    use tryon_core::stages::StillMotion;

    fn raised() -> Pose {
        let mut p = Pose::rest(3);
        p.local_rotations[1] = UnitQuat::from_scaled_axis(Vec3::z() * 0.8);
        p.root_translation = Vec3::new(0.0, 0.1, 0.0);
        p
    }

    #[test]
    fn the_lead_in_starts_at_its_pose_and_ends_at_the_clips_first() {
        let m = LeadIn {
            from: raised(),
            lead: 1.0,
            inner: Box::new(StillMotion {
                joints: 3,
                duration: 2.0,
            }),
        };
        assert_eq!(m.duration(), 3.0);
        let mut p = Pose::default();
        m.sample(0.0, &mut p);
        assert!((p.local_rotations[1].angle() - 0.8).abs() < 1e-12);
        assert!((p.root_translation.y - 0.1).abs() < 1e-12);
        m.sample(0.5, &mut p);
        assert!(
            (p.local_rotations[1].angle() - 0.4).abs() < 1e-9,
            "{}",
            p.local_rotations[1].angle()
        );
        m.sample(1.0, &mut p);
        assert!(p.local_rotations[1].angle() < 1e-12 && p.root_translation.norm() < 1e-12);
        assert_eq!(p.time, 1.0);
    }
}
