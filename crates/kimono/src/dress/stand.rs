//! The wearer's mannequin as the kimono is put on it: the measured mannequin with its upper arms
//! raised to the horizontal (the flat kimono's sleeves lie along them), and the plane through
//! the torso's middle where the flat kimono's front and back layers meet.

use super::DressError;
use tryon_core::math::{Real, UnitQuat, Vec3};
use tryon_core::measure::Measurements;
use tryon_core::pose::{Pose, Skeleton, mannequin_joints as j};

/// The standing wearer.
#[derive(Clone, Debug)]
pub struct Stand {
    pub m: Measurements,
    /// The body's vertices with the arms raised.
    pub posed: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// The torso's middle plane (z) at the armpits.
    pub zc: Real,
    /// The shoulders' top (y) beside the neck.
    pub top: Real,
}

/// The rotation that raises each upper arm from the mannequin's rest pose to the horizontal.
const ARM_RAISE_DEG: Real = 45.0;

/// The pose a kimono is put on in: the rest pose with the upper arms raised to the horizontal (a
/// skeleton without the mannequin's upper arms keeps its rest pose).
pub fn dress_pose(skeleton: &Skeleton) -> Pose {
    let mut pose = Pose::rest(skeleton.names.len());
    for (ua, s) in [(j::UPPERARM_L, 1.0), (j::UPPERARM_R, -1.0)] {
        if let Some(k) = skeleton.names.iter().position(|x| x == ua) {
            pose.local_rotations[k] =
                UnitQuat::from_scaled_axis(Vec3::z() * (s * ARM_RAISE_DEG).to_radians());
        }
    }
    pose
}

/// The measurements of `w`'s mannequin: shoulder width, arm length and inseam follow the height
/// as on the 1.65 m mannequin.
pub fn measurements(w: &crate::Wearer) -> Measurements {
    let sc = w.height / 1.65;
    Measurements {
        height: w.height,
        bust: w.bust,
        waist: w.waist,
        hip: w.hip,
        shoulder_width: 0.38 * sc,
        arm_length: 0.56 * sc,
        inseam: 0.76 * sc,
    }
}

impl Stand {
    /// The wearer of measurements `m` standing as `posed` (the mannequin's vertices in
    /// [`dress_pose`]) over `triangles`.
    pub fn new(
        m: Measurements,
        posed: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Stand, DressError> {
        let lm = m.landmarks();
        let near = |v: &&Vec3| (v.y - lm.armpit).abs() < 0.03 && v.x.abs() < 0.05;
        let (lo, hi) = posed
            .iter()
            .filter(near)
            .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), v| {
                (a.min(v.z), b.max(v.z))
            });
        let top = posed
            .iter()
            .filter(|v| (0.1..0.3).contains(&v.x.abs()))
            .map(|v| v.y)
            .fold(Real::NEG_INFINITY, Real::max);
        if !(lo.is_finite() && hi.is_finite() && top.is_finite()) {
            return Err(DressError::NoTorso);
        }
        Ok(Stand {
            m,
            posed,
            triangles,
            zc: 0.5 * (lo + hi),
            top,
        })
    }
    /// The body squashed toward the middle plane to `s` of its depth.
    pub fn squashed(&self, s: Real) -> Vec<Vec3> {
        let zc = self.zc;
        self.posed
            .iter()
            .map(|v| Vec3::new(v.x, v.y, zc + s * (v.z - zc)))
            .collect()
    }
}
