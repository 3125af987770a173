//! cloth-dyn: the garment solvers and the cloth model they share (P1 section 3, and the solvers
//! added after it). Every solver implements `tryon_core::stages::ClothSolver`, steps against any
//! `Collider`, never fails (a bad step is retried smaller, then rolled back, and reported) and hands
//! the frame its springs' forces (`CoarseFrame::elastic_force`, which the wrinkle stage reads).
//!
//! - The model, [`ClothModel`], built once from a polygon mesh: asymmetric structural springs on
//!   the edges (P1 eq. 1: stiff when longer than rest, soft when shorter), shear springs across
//!   quad diagonals, flexion springs that skip one vertex across every interior edge (Provot 1995,
//!   generalised to triangles and quads), packed as structure-of-arrays; `bends` changes bend
//!   springs after the build (P3's fold-keeping springs); `hinges` (Bergou's quadratic bending);
//!   `wear` (several garments in one model: particle ranges with layer, density and stiffness);
//!   material `presets`.
//! - [`ClothSim`] (`solver = "p1"`): P1's particle cloth, an [`Integrator`] (RK4 as in P1,
//!   symplectic Euler, implicit Euler by CG), Provot's strain limit and long-range lines
//!   (`strain`, `lines`), Coulomb friction, pins and handles, and a guard that halves any substep
//!   whose state is non-finite or exploding.
//! - [`VbdSim`] (`solver = "vbd"`, `vbd/`): vertex block descent (Chen et al. 2024). The implicit
//!   step's energy with body contact and friction inside it, minimised by sweeps of one Newton
//!   step per vertex, a colour at a time in parallel (bitwise the same on any thread count); a
//!   sliver's short edge solved as a pair (`pairs.rs`); the fail-safe sweeps each path through the
//!   collider and keeps a particle on its contact plane's side, or between two planes across a
//!   pinch (`contact.rs`); dihedral bending (`bending.rs`) and a Provot limit for free-hanging
//!   sheets.
//! - [`XpbdSim`] (`solver = "xpbd"`, `xpbd/`): small-step position-based dynamics, coloured
//!   distance and dihedral constraints eight at a time in f32 lanes (`lanes.rs`, tested against
//!   the f64 constraints), or the model's bend springs as compliant constraints (`springs.rs`).
//! - `self_contact`: the cloth against itself and other garments: the starting shape untangled,
//!   vertex-triangle and edge-edge pairs through a refitted BVH or a spatial hash, per-vertex
//!   bounds that keep a step from making two apart primitives cross (Chen et al. 2025), penalty
//!   and lagged friction energies, reopening after moves outside the solve (`keep.rs`), and
//!   `stage::FineLayers`, the surface stage that untangles the refined garments.
//! - `retry`: the frame loop XPBD and VBD share (retries at twice the steps, then rollback).

pub mod bends;
pub mod forces;
pub mod hinges;
pub mod integrator;
pub mod lines;
pub mod model;
pub mod params;
pub mod presets;
pub mod retry;
pub mod self_contact;
pub mod solver;
pub mod strain;
pub mod vbd;
pub mod wear;
pub mod xpbd;

pub use integrator::{Derivative, Integrator, IntegratorKind, Rk4, SymplecticEuler};
pub use model::{BuildClothError, ClothModel, Handle, SpringKind, SpringSet};
pub use params::ClothParams;
pub use solver::ClothSim;
pub use vbd::{VbdParams, VbdSim};
pub use xpbd::{XpbdBending, XpbdParams, XpbdSim};

#[cfg(test)]
mod solver_tests;
