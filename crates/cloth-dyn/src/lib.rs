//! cloth-dyn: sparse-particle cloth dynamics after P1 section 3 (Oshita & Makinouchi).
//!
//! A [`ClothModel`] is built once from a polygon mesh: asymmetric structural springs on the edges (P1
//! eq. 1: stiff when longer than rest, soft when shorter), shear springs across quad diagonals, and
//! bending springs that skip one vertex across every interior edge (Provot 1995's flexion springs,
//! generalised to meshes of triangles and quads). [`ClothSim`] steps it against any
//! [`tryon_core::stages::Collider`] with an [`Integrator`] (classical RK4 as in P1, or symplectic
//! Euler), Provot's strain limit, Coulomb friction, pins and kinematic handles, and a stability guard
//! that rejects and halves any substep whose state is non-finite or exploding.

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
