//! Skeletons and poses: the data a motion source produces and a body model consumes.

use crate::math::{Real, UnitQuat, Vec3};

/// A joint hierarchy with rest offsets (parents come before children).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Skeleton {
    pub names: Vec<String>,
    /// Parent of each joint; `None` for the root.
    pub parents: Vec<Option<usize>>,
    /// Offset of each joint from its parent in the rest pose (m).
    pub rest_offsets: Vec<Vec3>,
}

/// A pose: root translation and each joint's rotation relative to its rest orientation.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pose {
    pub time: Real,
    pub root_translation: Vec3,
    pub local_rotations: Vec<UnitQuat>,
}

impl Pose {
    /// The rest pose of a skeleton with `joints` joints.
    pub fn rest(joints: usize) -> Self {
        Pose {
            time: 0.0,
            root_translation: Vec3::zeros(),
            local_rotations: vec![UnitQuat::identity(); joints],
        }
    }
}

/// The parametric mannequin's joint names, spelled once: body-model builds the skeleton with them
/// and mocap-retarget's clips and name maps find joints by them.
pub mod mannequin_joints {
    pub const PELVIS: &str = "pelvis";
    pub const SPINE1: &str = "spine1";
    pub const SPINE2: &str = "spine2";
    pub const SPINE3: &str = "spine3";
    pub const NECK: &str = "neck";
    pub const HEAD: &str = "head";
    pub const CLAVICLE_L: &str = "clavicle_l";
    pub const UPPERARM_L: &str = "upperarm_l";
    pub const FOREARM_L: &str = "forearm_l";
    pub const HAND_L: &str = "hand_l";
    pub const CLAVICLE_R: &str = "clavicle_r";
    pub const UPPERARM_R: &str = "upperarm_r";
    pub const FOREARM_R: &str = "forearm_r";
    pub const HAND_R: &str = "hand_r";
    pub const THIGH_L: &str = "thigh_l";
    pub const SHIN_L: &str = "shin_l";
    pub const FOOT_L: &str = "foot_l";
    pub const TOE_L: &str = "toe_l";
    pub const THIGH_R: &str = "thigh_r";
    pub const SHIN_R: &str = "shin_r";
    pub const FOOT_R: &str = "foot_r";
    pub const TOE_R: &str = "toe_r";
    /// Every joint, in the skeleton's order (parents first).
    pub const ALL: [&str; 22] = [
        PELVIS, SPINE1, SPINE2, SPINE3, NECK, HEAD, CLAVICLE_L, UPPERARM_L, FOREARM_L, HAND_L,
        CLAVICLE_R, UPPERARM_R, FOREARM_R, HAND_R, THIGH_L, SHIN_L, FOOT_L, TOE_L, THIGH_R, SHIN_R,
        FOOT_R, TOE_R,
    ];
}
