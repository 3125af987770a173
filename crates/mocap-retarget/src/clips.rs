//! Procedural motion clips over named joints: a walk cycle (hip flexion, swing-phase knee bend,
//! pelvis bob and yaw, counter-swinging arms, forward travel) and an arm raise. Both ease in from the
//! rest pose so that a garment placed on the rest pose starts at rest.

use thiserror::Error;
use tryon_core::math::{Real, UnitQuat, Vec3};
use tryon_core::pose::mannequin_joints as J;
use tryon_core::pose::{Pose, Skeleton};
use tryon_core::stages::MotionSource;

/// Why a clip cannot drive a skeleton.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum ClipError {
    #[error(
        "the skeleton has no joint named `{0}` (the built-in clips need the mannequin's joint names)"
    )]
    MissingJoint(&'static str),
    #[error("clip parameter `{name}` = {value} is outside {min}..={max}")]
    BadParameter {
        name: &'static str,
        value: Real,
        min: Real,
        max: Real,
    },
}

fn joint(s: &Skeleton, name: &'static str) -> Result<usize, ClipError> {
    s.names
        .iter()
        .position(|n| n == name)
        .ok_or(ClipError::MissingJoint(name))
}

fn smoothstep(t: Real) -> Real {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

fn rot(axis: Vec3, deg: Real) -> UnitQuat {
    UnitQuat::from_scaled_axis(axis.normalize() * deg.to_radians())
}

/// Joint indices the clips drive.
#[derive(Clone, Debug)]
struct Rig {
    n: usize,
    pelvis: usize,
    spine: usize,
    /// Upper arm and forearm, left then right.
    arm: [[usize; 2]; 2],
    /// Thigh, shin and foot, left then right.
    leg: [[usize; 3]; 2],
    /// Rest direction of each upper arm (from the skeleton's rest offsets of the forearm).
    arm_dir: [Vec3; 2],
}

impl Rig {
    fn new(s: &Skeleton) -> Result<Self, ClipError> {
        let arm = [
            [joint(s, J::UPPERARM_L)?, joint(s, J::FOREARM_L)?],
            [joint(s, J::UPPERARM_R)?, joint(s, J::FOREARM_R)?],
        ];
        let dir = |j: usize| {
            s.rest_offsets
                .get(j)
                .and_then(|v| v.try_normalize(1e-9))
                .unwrap_or(-Vec3::y())
        };
        Ok(Rig {
            n: s.names.len(),
            pelvis: joint(s, J::PELVIS)?,
            spine: joint(s, J::SPINE2)?,
            arm_dir: [dir(arm[0][1]), dir(arm[1][1])],
            arm,
            leg: [
                [
                    joint(s, J::THIGH_L)?,
                    joint(s, J::SHIN_L)?,
                    joint(s, J::FOOT_L)?,
                ],
                [
                    joint(s, J::THIGH_R)?,
                    joint(s, J::SHIN_R)?,
                    joint(s, J::FOOT_R)?,
                ],
            ],
        })
    }

    /// Elbow flexion: the forearm swings forward about the axis across the arm.
    fn elbow(&self, side: usize, deg: Real) -> UnitQuat {
        rot(self.arm_dir[side].cross(&Vec3::z()), deg)
    }
}

/// Settings of the walk cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkParams {
    /// Length of one full cycle (two steps), s.
    pub period: Real,
    /// Hip flexion amplitude, degrees.
    pub hip_deg: Real,
    /// Peak knee flexion in swing, degrees.
    pub knee_deg: Real,
    /// Arm swing amplitude, degrees.
    pub arm_deg: Real,
    /// How far the arms come down from the rest pose toward the body, degrees.
    pub arm_lower_deg: Real,
    /// Time to ease in from the rest pose, s.
    pub ease_in: Real,
    /// Clip length, s.
    pub duration: Real,
    /// Leg length (hip joint to floor), m: sets the stride and speed.
    pub leg_length: Real,
}

impl Default for WalkParams {
    fn default() -> Self {
        WalkParams {
            period: 1.1,
            hip_deg: 22.0,
            knee_deg: 55.0,
            arm_deg: 16.0,
            arm_lower_deg: 10.0,
            ease_in: 0.6,
            duration: 4.0,
            leg_length: 0.82,
        }
    }
}

/// A procedural walk cycle travelling along +Z.
#[derive(Clone, Debug)]
pub struct Walk {
    pub params: WalkParams,
    rig: Rig,
}

impl Walk {
    pub fn new(skeleton: &Skeleton, params: WalkParams) -> Result<Self, ClipError> {
        let check = |name, value: Real, min, max| {
            if value.is_finite() && value >= min && value <= max {
                Ok(())
            } else {
                Err(ClipError::BadParameter {
                    name,
                    value,
                    min,
                    max,
                })
            }
        };
        check("period", params.period, 0.3, 5.0)?;
        check("hip_deg", params.hip_deg, 0.0, 60.0)?;
        check("knee_deg", params.knee_deg, 0.0, 120.0)?;
        check("arm_deg", params.arm_deg, 0.0, 60.0)?;
        check("arm_lower_deg", params.arm_lower_deg, -30.0, 40.0)?;
        check("ease_in", params.ease_in, 0.0, 5.0)?;
        check("duration", params.duration, 0.0, 600.0)?;
        check("leg_length", params.leg_length, 0.3, 1.5)?;
        Ok(Walk {
            params,
            rig: Rig::new(skeleton)?,
        })
    }

    /// Forward speed once the walk is under way (m/s): two steps of length 2 L sin(hip) per cycle.
    pub fn speed(&self) -> Real {
        let p = &self.params;
        2.0 * 2.0 * p.leg_length * p.hip_deg.to_radians().sin() / p.period
    }
}

impl MotionSource for Walk {
    fn duration(&self) -> Real {
        self.params.duration
    }

    fn sample(&self, t: Real, out: &mut Pose) {
        let p = &self.params;
        let r = &self.rig;
        let t = t.clamp(0.0, p.duration);
        *out = Pose::rest(r.n);
        out.time = t;
        let e = if p.ease_in > 0.0 {
            smoothstep(t / p.ease_in)
        } else {
            1.0
        };
        // Distance travelled: the integral of the eased speed.
        let travelled = if p.ease_in <= 0.0 || t >= p.ease_in {
            t - 0.5 * p.ease_in
        } else {
            let u = t / p.ease_in;
            p.ease_in * (u * u * u - 0.5 * u * u * u * u)
        };
        let phi = std::f64::consts::TAU * t / p.period;
        let (s, c) = phi.sin_cos();
        out.root_translation = Vec3::new(0.0, -0.018 * s * s * e, self.speed() * travelled);
        out.local_rotations[r.pelvis] = rot(Vec3::y(), 5.0 * s * e);
        out.local_rotations[r.spine] = rot(Vec3::y(), -7.0 * s * e);
        for side in 0..2 {
            // The left leg leads at phase 0; the right is half a cycle behind.
            let (ls, lc) = if side == 0 { (s, c) } else { (-s, -c) };
            let [thigh, shin, foot] = r.leg[side];
            out.local_rotations[thigh] = rot(-Vec3::x(), p.hip_deg * ls * e);
            let knee = 5.0 + p.knee_deg * lc.max(0.0).powi(2);
            out.local_rotations[shin] = rot(Vec3::x(), knee * e);
            out.local_rotations[foot] = rot(-Vec3::x(), 8.0 * ls * e);
            // Arms swing against the leg on the same side.
            let [ua, fa] = r.arm[side];
            let lower = if side == 0 {
                -p.arm_lower_deg
            } else {
                p.arm_lower_deg
            };
            let swing = -p.arm_deg * ls * e;
            out.local_rotations[ua] = rot(-Vec3::x(), swing) * rot(Vec3::z(), lower * e);
            out.local_rotations[fa] = r.elbow(
                side,
                (12.0 + 10.0 * swing.max(0.0) / p.arm_deg.max(1e-9)) * e,
            );
        }
    }
}

/// Both arms raised sideways from the rest pose and lowered again.
#[derive(Clone, Debug)]
pub struct ArmRaise {
    /// Peak rotation of the upper arms above the rest pose, degrees.
    pub raise_deg: Real,
    /// Time to raise (and again to lower), s.
    pub raise_time: Real,
    /// Time held at the top, s.
    pub hold: Real,
    /// Peak elbow bend, degrees (15% of `raise_deg` unless set by [`ArmRaise::with_elbow`]).
    pub elbow_deg: Real,
    rig: Rig,
}

impl ArmRaise {
    /// How far the arms rise unless a scene says otherwise (degrees from the rest pose).
    pub const DEFAULT_DEG: Real = 100.0;

    pub fn new(skeleton: &Skeleton, raise_deg: Real) -> Result<Self, ClipError> {
        if !(raise_deg.is_finite() && (0.0..=150.0).contains(&raise_deg)) {
            return Err(ClipError::BadParameter {
                name: "raise_deg",
                value: raise_deg,
                min: 0.0,
                max: 150.0,
            });
        }
        Ok(ArmRaise {
            raise_deg,
            raise_time: 1.6,
            hold: 0.6,
            elbow_deg: 0.15 * raise_deg,
            rig: Rig::new(skeleton)?,
        })
    }

    /// The same motion with the elbows bending to `elbow_deg` (0..=150) at the top.
    pub fn with_elbow(mut self, elbow_deg: Real) -> Result<Self, ClipError> {
        if !(elbow_deg.is_finite() && (0.0..=150.0).contains(&elbow_deg)) {
            return Err(ClipError::BadParameter {
                name: "elbow_deg",
                value: elbow_deg,
                min: 0.0,
                max: 150.0,
            });
        }
        self.elbow_deg = elbow_deg;
        Ok(self)
    }
}

impl MotionSource for ArmRaise {
    fn duration(&self) -> Real {
        2.0 * self.raise_time + self.hold + 0.4
    }

    fn sample(&self, t: Real, out: &mut Pose) {
        let r = &self.rig;
        let t = t.clamp(0.0, self.duration());
        *out = Pose::rest(r.n);
        out.time = t;
        let up = smoothstep(t / self.raise_time);
        let down = smoothstep((t - self.raise_time - self.hold) / self.raise_time);
        let a = self.raise_deg * (up - down);
        let bend = self.elbow_deg * (up - down);
        for side in 0..2 {
            let [ua, fa] = r.arm[side];
            let s = if side == 0 { 1.0 } else { -1.0 };
            out.local_rotations[ua] = rot(Vec3::z(), s * a);
            out.local_rotations[fa] = r.elbow(side, bend);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn skeleton() -> Skeleton {
        let names = [
            J::PELVIS,
            J::SPINE2,
            J::UPPERARM_L,
            J::FOREARM_L,
            J::UPPERARM_R,
            J::FOREARM_R,
            J::THIGH_L,
            J::SHIN_L,
            J::FOOT_L,
            J::THIGH_R,
            J::SHIN_R,
            J::FOOT_R,
        ];
        Skeleton {
            names: names.iter().map(|s| s.to_string()).collect(),
            parents: vec![None; names.len()],
            rest_offsets: vec![Vec3::new(0.3, -0.3, 0.0); names.len()],
        }
    }

    #[test]
    fn clips_start_at_rest_and_stay_finite() {
        let s = skeleton();
        let walk = Walk::new(&s, WalkParams::default()).unwrap();
        let raise = ArmRaise::new(&s, 100.0).unwrap();
        let clips: [&dyn MotionSource; 2] = [&walk, &raise];
        for clip in clips {
            let mut pose = Pose::default();
            clip.sample(0.0, &mut pose);
            assert_eq!(pose, Pose::rest(s.names.len()));
            for k in 0..=200 {
                clip.sample(clip.duration() * k as Real / 200.0, &mut pose);
                assert!(pose.root_translation.iter().all(|x| x.is_finite()));
                assert!(
                    pose.local_rotations
                        .iter()
                        .all(|q| q.coords.iter().all(|x| x.is_finite()))
                );
            }
        }
    }

    #[test]
    fn walk_travels_forward_at_its_speed_and_repeats() {
        let walk = Walk::new(&skeleton(), WalkParams::default()).unwrap();
        let (mut a, mut b) = (Pose::default(), Pose::default());
        walk.sample(2.0, &mut a);
        walk.sample(3.0, &mut b);
        let v = b.root_translation.z - a.root_translation.z;
        assert!((v - walk.speed()).abs() < 1e-9 && v > 0.5 && v < 2.0, "{v}");
        walk.sample(2.0 + walk.params.period, &mut b);
        for (qa, qb) in a.local_rotations.iter().zip(&b.local_rotations) {
            assert!(qa.angle_to(qb) < 1e-9);
        }
    }

    /// The elbows bend 15% of the raise unless told, as far as told otherwise; a bend beyond
    /// 150 degrees (or NaN) is refused by name.
    #[test]
    fn arm_raise_bends_the_elbows_as_asked() {
        let s = skeleton();
        let peak = |clip: &ArmRaise| {
            let mut pose = Pose::default();
            clip.sample(clip.raise_time + 0.5 * clip.hold, &mut pose);
            pose.local_rotations[3].angle().to_degrees()
        };
        let clip = ArmRaise::new(&s, 40.0).unwrap();
        assert!((peak(&clip) - 6.0).abs() < 1e-9);
        let bent = clip.with_elbow(90.0).unwrap();
        assert!((peak(&bent) - 90.0).abs() < 1e-9);
        for bad in [151.0, -1.0, Real::NAN] {
            let e = ArmRaise::new(&s, 40.0)
                .unwrap()
                .with_elbow(bad)
                .unwrap_err();
            assert!(e.to_string().contains("elbow_deg"), "{e}");
        }
    }

    #[test]
    fn arm_raise_peaks_and_returns() {
        let s = skeleton();
        let clip = ArmRaise::new(&s, 90.0).unwrap();
        let mut pose = Pose::default();
        clip.sample(clip.raise_time + 0.5 * clip.hold, &mut pose);
        assert!((pose.local_rotations[2].angle().to_degrees() - 90.0).abs() < 1e-9);
        clip.sample(clip.duration(), &mut pose);
        assert!(pose.local_rotations[2].angle() < 1e-9);
        assert!(matches!(
            ArmRaise::new(&s, 400.0),
            Err(ClipError::BadParameter { .. })
        ));
        let mut bad = s.clone();
        bad.names[0] = "hips".into();
        assert!(matches!(
            Walk::new(&bad, WalkParams::default()),
            Err(ClipError::MissingJoint("pelvis"))
        ));
    }
}
