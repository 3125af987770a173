//! A plausibility check of retargeted motion: how fast any joint turns. A retargeting fault (a
//! flipped swing, a wrapped angle, a knot in an arm) shows as a joint turning far faster than a
//! person can between two frames; a real body's fastest segments (a pitcher's forearm) reach
//! about 2,000 degrees per second, a walk or a run a few hundred. [`limit_turns`] flattens such
//! glitches in the data.

use crate::clearance::forward;
use tryon_core::math::{Real, Vec3};
use tryon_core::pose::{Pose, Skeleton};

/// Fastest turn that motion data may show (degrees per second) before it is taken as a fault.
pub const PLAUSIBLE_DEG_PER_S: Real = 2000.0;
/// The turn rate retargeted motion is limited to unless a scene says otherwise (degrees per
/// second): above a run's fastest limbs (CMU 10_04's toes reach 1,044), below a glitch's (131_01's
/// right wrist spins 7,760 degrees per second for two frames at 1.97 s, the upper arm 2,000).
pub const DEFAULT_LIMIT_DEG_PER_S: Real = 1500.0;

/// The fastest turn of any joint's world orientation between consecutive poses.
#[derive(Clone, Debug, PartialEq)]
pub struct Turn {
    pub deg_per_s: Real,
    pub joint: String,
    /// The later pose of the two.
    pub frame: usize,
}

/// The fastest turn over `poses`, spaced `dt` apart, on `skeleton` with rest joint positions
/// `rest`; `None` with fewer than two poses or a non-positive step.
pub fn fastest_turn(skeleton: &Skeleton, rest: &[Vec3], poses: &[Pose], dt: Real) -> Option<Turn> {
    if poses.len() < 2 || !(dt > 0.0) {
        return None;
    }
    let mut best: Option<Turn> = None;
    let mut prev = forward(skeleton, rest, &poses[0]).0;
    for (k, pose) in poses.iter().enumerate().skip(1) {
        let g = forward(skeleton, rest, pose).0;
        for (j, (a, b)) in prev.iter().zip(&g).enumerate() {
            let deg = a.angle_to(b).to_degrees() / dt;
            if best.as_ref().is_none_or(|t| deg > t.deg_per_s) {
                best = Some(Turn {
                    deg_per_s: deg,
                    joint: skeleton.names[j].clone(),
                    frame: k,
                });
            }
        }
        prev = g;
    }
    best
}

/// Limits every joint's world turn between consecutive poses to `max_deg_per_s` (poses `dt`
/// apart): a joint that would turn faster turns at the limit toward where the data puts it, so a
/// glitch of a few frames is flattened and the motion catches up after it. Returns how many
/// joint-frames were limited.
pub fn limit_turns(
    skeleton: &Skeleton,
    rest: &[Vec3],
    poses: &mut [Pose],
    dt: Real,
    max_deg_per_s: Real,
) -> usize {
    let max = (max_deg_per_s * dt).to_radians();
    if poses.len() < 2 || !(max > 0.0) {
        return 0;
    }
    let mut limited = 0;
    let mut prev = forward(skeleton, rest, &poses[0]).0;
    for pose in poses.iter_mut().skip(1) {
        let mut g = forward(skeleton, rest, pose).0;
        for (j, gj) in g.iter_mut().enumerate() {
            let angle = prev[j].angle_to(gj);
            if angle > max {
                *gj = prev[j].try_slerp(gj, max / angle, 1e-9).unwrap_or(*gj);
                limited += 1;
            }
        }
        for j in 0..g.len() {
            pose.local_rotations[j] = match skeleton.parents[j] {
                Some(q) => g[q].inverse() * g[j],
                None => g[j],
            };
        }
        prev = g;
    }
    limited
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::math::UnitQuat;

    #[test]
    fn the_fastest_joint_and_frame_are_found() {
        let s = Skeleton {
            names: vec!["root".into(), "arm".into()],
            parents: vec![None, Some(0)],
            rest_offsets: vec![Vec3::zeros(), Vec3::x()],
        };
        let rest = [Vec3::zeros(), Vec3::x()];
        let mut poses = vec![Pose::rest(2); 4];
        // The arm turns 10 degrees per frame relative to the root, the root 3; at frame 2 the arm
        // jumps by 40 more.
        for (k, p) in poses.iter_mut().enumerate() {
            let extra = if k >= 2 { 40.0 } else { 0.0 };
            p.local_rotations[0] =
                UnitQuat::from_axis_angle(&Vec3::z_axis(), (3.0 * k as Real).to_radians());
            p.local_rotations[1] =
                UnitQuat::from_axis_angle(&Vec3::z_axis(), (10.0 * k as Real + extra).to_radians());
        }
        let t = fastest_turn(&s, &rest, &poses, 0.1).unwrap();
        assert_eq!((t.joint.as_str(), t.frame), ("arm", 2));
        assert!((t.deg_per_s - 530.0).abs() < 1e-6, "{}", t.deg_per_s);
        assert!(fastest_turn(&s, &rest, &poses[..1], 0.1).is_none());
        assert!(fastest_turn(&s, &rest, &poses, 0.0).is_none());
        // Limited to 200 degrees per second (20 per frame). The arm's world angle is 13 k (+ 40
        // from frame 2): 13, 66, 79. Limited: 13, 33, 53, so frame 3 is 26 degrees behind.
        let mut lim = poses.clone();
        let n = limit_turns(&s, &rest, &mut lim, 0.1, 200.0);
        let t = fastest_turn(&s, &rest, &lim, 0.1).unwrap();
        assert!(t.deg_per_s <= 200.0 + 1e-9, "{t:?}");
        assert_eq!(n, 2, "frame 2 and 3 of the arm");
        let arm = |p: &[Pose], k: usize| forward(&s, &rest, &p[k]).0[1];
        assert!((arm(&lim, 3).angle_to(&arm(&poses, 3)).to_degrees() - 26.0).abs() < 1e-6);
        // The root was never over the limit and is untouched.
        assert_eq!(lim[3].local_rotations[0], poses[3].local_rotations[0]);
    }
}
