//! Skeletons and poses: the data a motion source produces and a body model consumes.

use crate::math::{Real, UnitQuat, Vec3};

/// A joint hierarchy with rest offsets (parents come before children).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skeleton {
    pub names: Vec<String>,
    /// Parent of each joint; `None` for the root.
    pub parents: Vec<Option<usize>>,
    /// Offset of each joint from its parent in the rest pose (m).
    pub rest_offsets: Vec<Vec3>,
}

/// A pose: root translation and each joint's rotation relative to its rest orientation.
#[derive(Clone, Debug, Default, PartialEq)]
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
