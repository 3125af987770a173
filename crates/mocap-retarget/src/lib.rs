//! mocap-retarget: motion for the body. Today: procedural clips for the mannequin's skeleton (a walk
//! cycle and an arm raise), found by joint name so that any skeleton using the same names works.

pub mod clips;

pub use clips::{ArmRaise, ClipError, Walk, WalkParams};
