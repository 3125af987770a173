//! mocap-retarget: motion for the body. Procedural clips for the mannequin's skeleton (a walk cycle
//! and an arm raise), and P1.6's retargeting of motion capture onto any known skeleton: name maps
//! ([`names`]), rest-pose alignment, analytic two-bone leg IK ([`ik`]), rotation copy for the upper
//! body, resampling to the scene's rate ([`retarget()`]).

pub mod clearance;
pub mod clips;
pub mod ik;
pub mod lead_in;
pub mod names;
pub mod retarget;
pub mod turns;

pub use clips::{ArmRaise, ClipError, Walk, WalkParams};
pub use ik::{LegSolution, frame_rotation, solve_leg};
pub use lead_in::{LeadIn, blend_poses};
pub use names::{Role, RoleMap, Scheme};
pub use retarget::{Placement, RetargetError, RetargetOptions, Retargeted, Rig, retarget};
