//! Test fixtures shared by this crate's unit tests.

use tryon_core::math::{Real, Vec3};
use tryon_core::stages::Collider;

/// The half-space y < 0 as a body: distance y, normal +y.
pub(crate) struct Floor;

impl Collider for Floor {
    fn name(&self) -> &'static str {
        "floor"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities::NONE
    }
    fn update(&mut self, _: &tryon_core::frames::BodyFrame) {}
    fn resolve(&mut self, _: &mut [Vec3], _: &mut Vec<tryon_core::frames::Contact>) {}
    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        Some(p.y)
    }
}
