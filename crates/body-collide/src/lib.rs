//! body-collide: the body as a collision object (P1 sections 3.3-3.4). The bodies themselves
//! (mannequin, MakeHuman, skinning) are in body-model.
//!
//! - [`NearestVertexCollider`]: P1's collider. Each point keeps its nearest body vertex, updated by a
//!   local hill-climb from last step's vertex over the body's vertex graph; a point is inside when
//!   it is behind every face incident to that vertex, and is then moved onto the nearest of those
//!   faces. Its probes (the contact planes of the VBD solver) check the climb against a spatial hash
//!   of the body's vertices ([`grid::VertexGrid`]), so no point near the body is left at a local
//!   minimum on another limb.
//! - [`SdfCollider`]: P3's signed distance field on a regular grid (trilinear), rebuilt from the
//!   deformed body at every update (narrow band plus flood fill).
//! - [`DepthMapCollider`]: P4's six orthographic depth and normal maps of the body, on the CPU.
//! - [`ExactCollider`]: closest point on the whole triangle mesh (a [`facetree::FaceTree`] built
//!   once and refitted to each shape, with pseudo-normal inside tests): the referee that measures
//!   every other collider.
//! - [`BodyFollower`]: P1.3.4, points keep their coordinates relative to their nearest body face when
//!   the body moves; as the frame loop's `Follower` it first carries the whole cloth with the root.
//! - [`Bands`]: garment vertices bound to the body's surface (waistbands, collars, cuffs).

pub mod bands;
pub mod body;
pub mod carry;
pub mod carry_edges;
pub mod ccd;
pub mod crossings;
pub mod depth;
pub mod exact;
pub mod facetree;
pub mod follow;
pub mod grid;
pub mod hold;
pub mod metrics;
pub mod sdf;
pub mod sdf_band;
pub mod swept;
pub mod tracker;
mod tritri;

pub use bands::Bands;
pub use body::{BodyError, BodyMesh};
pub use carry::{RootCarry, RootDelta, root_transform};
pub use depth::DepthMapCollider;
pub use exact::{ExactCollider, penetration_depths};
pub use follow::{BodyFollower, FollowParams, SurfaceBinding};
pub use sdf::SdfCollider;
pub use tracker::NearestVertexCollider;

#[cfg(test)]
mod exact_tests;
#[cfg(test)]
mod sdf_focus_tests;
#[cfg(test)]
mod swept_tests;
#[cfg(test)]
mod tests;
