//! P2 (../shared/PAPERS.md, P2; Kagaya et al.): a kimono that fits a wearer from body measurements.
//!
//! 1. `dims`: tailoring dimensions from the measurements by the standard-dimension formulas.
//! 2. `mesh`: the kimono built from the eight straight-cut parts of one bolt, on rows fixed by a
//!    `levels::Layout` so every size shares one topology; its sub-meshes, its dimension edge sets
//!    and its bolt UVs.
//! 3. `fit`: eq. (1), blend weights per sub-mesh, then the sub-meshes moved so they meet.
//! 4. `print`: the print correction, the dimension sets' UVs scaled, then eq. (2) outward.
//! 5. `dress`: the kimono put on the mannequin (placed around the squashed body, the body
//!    inflated, the rows tied), for a driver that steps the cloth.

pub mod bolt;
mod builder;
mod collar;
pub mod dims;
pub mod dress;
pub mod family;
pub mod fit;
pub mod levels;
pub mod mesh;
mod orient;
mod panels;
pub mod print;
#[cfg(test)]
mod tests;

pub use dims::{Dimensions, TABLE_1, TailorError, Wearer, tailor};
pub use fit::{Fit, FitError, FitParams, blend, fit};
pub use levels::{Layout, LevelError, Levels};
pub use mesh::{DimensionSet, KimonoMesh, Part, build};
pub use print::{PrintAspect, PrintError, PrintParams, correct_print, print_aspect};
