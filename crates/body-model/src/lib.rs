//! body-model: the bodies garments are worn on (P1 section 6's try-on body).
//!
//! - [`Mannequin`]: a parametric body from measurements (closed mesh, 22-joint skeleton in an
//!   A-pose, skin weights), posed by [`SkinnedBody`] (linear blend skinning, velocities by finite
//!   difference; the frame loop's `BodyModel`); [`girth_at`] measures a mesh by slicing.
//! - [`MakeHumanBody`]: a MakeHuman base mesh skinned by its own weights, morphed toward
//!   measurements.

pub mod girth;
pub mod makehuman;
pub mod mannequin;
pub mod press;
pub mod skin;

pub use girth::girth_at;
pub use makehuman::{Girths, MakeHumanBody, MakeHumanError};
pub use mannequin::{JOINT_NAMES, Mannequin};
pub use press::{Press, Pressed};
pub use skin::{SkinWeights, SkinnedBody, joint_transforms};

#[cfg(test)]
mod mannequin_tests;
