//! pnt-surface: P1 section 4.1, the reference surface. Every coarse triangle becomes a curved PN
//! triangle (Vlachos, Peters, Boyd and Mitchell 2001): a cubic Bezier triangle from its corner
//! positions and normals, with a quadratic normal field. Quads are split along their 0-2 diagonal
//! (the coarse mesh's triangulated view); the two halves share the diagonal's curve, which depends
//! only on its two end positions and normals, so the split costs no crack (it can show a slight
//! asymmetry on a strongly curved quad, which a PN-quad scheme would avoid).
//!
//! Tessellation level `L` gives `2^L` segments per coarse edge (`L = 0` is the coarse mesh itself).
//! Levels nest: a fine vertex's level is the first `l` at which it is a lattice point of the
//! `2^l`-segment lattice, which the hierarchical fine collision (P1.4.2) descends by. Vertices on a
//! coarse edge are created once and shared by both triangles; the topology is built once and a
//! frame only evaluates positions and normals.

pub mod pn;
pub mod refine;
pub mod stage;

pub use pn::PnPatch;
pub use refine::{PnRefiner, RefineError, fine_vertex_count};
pub use stage::PnStage;

#[cfg(test)]
mod tests;
