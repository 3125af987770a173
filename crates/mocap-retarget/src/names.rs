//! Joint roles and the name maps of the skeletons this project meets: the two CMU BVH schemes
//! (10_04's LeftUpLeg/LeftLeg/Spine... and 131_01's LeftHip/LeftKnee/Chest...), MakeHuman's cmu_mb rig
//! (CMU names), MakeHuman's default rig, and the parametric mannequin.

use tryon_core::pose::Skeleton;
use tryon_core::pose::mannequin_joints as J;

/// A joint's role in a humanoid, independent of naming.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(usize)]
pub enum Role {
    Hips,
    Spine,
    Spine1,
    Spine2,
    Neck,
    Neck1,
    Head,
    LClavicle,
    LUpperArm,
    LForearm,
    LHand,
    RClavicle,
    RUpperArm,
    RForearm,
    RHand,
    LThigh,
    LShin,
    LFoot,
    LToe,
    RThigh,
    RShin,
    RFoot,
    RToe,
}

/// Number of roles.
pub const ROLES: usize = 23;

/// Every role, in declaration order.
pub const ALL_ROLES: [Role; ROLES] = [
    Role::Hips,
    Role::Spine,
    Role::Spine1,
    Role::Spine2,
    Role::Neck,
    Role::Neck1,
    Role::Head,
    Role::LClavicle,
    Role::LUpperArm,
    Role::LForearm,
    Role::LHand,
    Role::RClavicle,
    Role::RUpperArm,
    Role::RForearm,
    Role::RHand,
    Role::LThigh,
    Role::LShin,
    Role::LFoot,
    Role::LToe,
    Role::RThigh,
    Role::RShin,
    Role::RFoot,
    Role::RToe,
];

/// Roles every retargeting needs.
pub const REQUIRED: [Role; 7] = [
    Role::Hips,
    Role::LThigh,
    Role::LShin,
    Role::LFoot,
    Role::RThigh,
    Role::RShin,
    Role::RFoot,
];

/// Chains along which a role's bone direction points (to the next role of the chain present).
pub const CHAINS: [&[Role]; 5] = [
    &[
        Role::Hips,
        Role::Spine,
        Role::Spine1,
        Role::Spine2,
        Role::Neck,
        Role::Neck1,
        Role::Head,
    ],
    &[
        Role::LClavicle,
        Role::LUpperArm,
        Role::LForearm,
        Role::LHand,
    ],
    &[
        Role::RClavicle,
        Role::RUpperArm,
        Role::RForearm,
        Role::RHand,
    ],
    &[Role::LThigh, Role::LShin, Role::LFoot, Role::LToe],
    &[Role::RThigh, Role::RShin, Role::RFoot, Role::RToe],
];

/// A naming scheme: the joint name of each role (empty: the scheme has no such joint).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Scheme {
    pub name: &'static str,
    pub names: [&'static str; ROLES],
}

/// CMU clips like 10_04 and MakeHuman's cmu_mb rig.
pub const CMU: Scheme = Scheme {
    name: "CMU (LeftUpLeg/LeftLeg)",
    names: [
        "Hips",
        "LowerBack",
        "Spine",
        "Spine1",
        "Neck",
        "Neck1",
        "Head",
        "LeftShoulder",
        "LeftArm",
        "LeftForeArm",
        "LeftHand",
        "RightShoulder",
        "RightArm",
        "RightForeArm",
        "RightHand",
        "LeftUpLeg",
        "LeftLeg",
        "LeftFoot",
        "LeftToeBase",
        "RightUpLeg",
        "RightLeg",
        "RightFoot",
        "RightToeBase",
    ],
};

/// CMU clips like 131_01.
pub const CMU_HIP_KNEE: Scheme = Scheme {
    name: "CMU (LeftHip/LeftKnee)",
    names: [
        "Hips",
        "lowerback",
        "Chest",
        "Chest2",
        "lowerneck",
        "Neck",
        "Head",
        "LeftCollar",
        "LeftShoulder",
        "LeftElbow",
        "LeftWrist",
        "RightCollar",
        "RightShoulder",
        "RightElbow",
        "RightWrist",
        "LeftHip",
        "LeftKnee",
        "LeftAnkle",
        "LeftToe",
        "RightHip",
        "RightKnee",
        "RightAnkle",
        "RightToe",
    ],
};

/// MakeHuman's default rig.
pub const MAKEHUMAN: Scheme = Scheme {
    name: "MakeHuman default",
    names: [
        "root",
        "spine04",
        "spine02",
        "spine01",
        "neck01",
        "neck02",
        "head",
        "clavicle.L",
        "upperarm01.L",
        "lowerarm01.L",
        "wrist.L",
        "clavicle.R",
        "upperarm01.R",
        "lowerarm01.R",
        "wrist.R",
        "upperleg01.L",
        "lowerleg01.L",
        "foot.L",
        "toe3-1.L",
        "upperleg01.R",
        "lowerleg01.R",
        "foot.R",
        "toe3-1.R",
    ],
};

/// The parametric mannequin (body-collide).
pub const MANNEQUIN: Scheme = Scheme {
    name: "mannequin",
    names: [
        J::PELVIS,
        J::SPINE1,
        J::SPINE2,
        J::SPINE3,
        J::NECK,
        "",
        J::HEAD,
        J::CLAVICLE_L,
        J::UPPERARM_L,
        J::FOREARM_L,
        J::HAND_L,
        J::CLAVICLE_R,
        J::UPPERARM_R,
        J::FOREARM_R,
        J::HAND_R,
        J::THIGH_L,
        J::SHIN_L,
        J::FOOT_L,
        J::TOE_L,
        J::THIGH_R,
        J::SHIN_R,
        J::FOOT_R,
        J::TOE_R,
    ],
};

/// Every known scheme.
pub const SCHEMES: [Scheme; 4] = [CMU, CMU_HIP_KNEE, MAKEHUMAN, MANNEQUIN];

/// A skeleton's joints by role.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RoleMap {
    pub scheme: &'static str,
    pub joints: [Option<usize>; ROLES],
}

impl RoleMap {
    /// The joint playing `role`.
    pub fn get(&self, role: Role) -> Option<usize> {
        self.joints[role as usize]
    }

    /// The scheme that names all required roles and the most others; `None` when none fits.
    pub fn detect(s: &Skeleton) -> Option<RoleMap> {
        SCHEMES
            .iter()
            .map(|sc| Self::with_scheme(s, sc))
            .filter(|m| REQUIRED.iter().all(|r| m.get(*r).is_some()))
            .max_by_key(|m| m.joints.iter().filter(|j| j.is_some()).count())
    }

    /// Joints of `s` named as `scheme` names them.
    pub fn with_scheme(s: &Skeleton, scheme: &Scheme) -> RoleMap {
        let mut joints = [None; ROLES];
        for (k, name) in scheme.names.iter().enumerate() {
            if !name.is_empty() {
                joints[k] = s.names.iter().position(|n| n == name);
            }
        }
        RoleMap {
            scheme: scheme.name,
            joints,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn skel(names: &[&str]) -> Skeleton {
        Skeleton {
            names: names.iter().map(|s| s.to_string()).collect(),
            parents: vec![None; names.len()],
            rest_offsets: vec![Default::default(); names.len()],
        }
    }

    #[test]
    fn roles_are_in_declaration_order() {
        for (k, r) in ALL_ROLES.iter().enumerate() {
            assert_eq!(*r as usize, k);
        }
    }

    #[test]
    fn each_scheme_is_detected_from_its_own_names() {
        for sc in SCHEMES {
            let names: Vec<&str> = sc.names.iter().copied().filter(|n| !n.is_empty()).collect();
            let m = RoleMap::detect(&skel(&names)).unwrap();
            assert_eq!(m.scheme, sc.name);
        }
        assert!(RoleMap::detect(&skel(&["Hips", "LeftUpLeg"])).is_none());
    }
}
