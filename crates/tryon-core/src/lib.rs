//! tryon-core: the vocabulary every stage shares — math aliases, polygon meshes with their topology,
//! the plain-data frames passed between stages, and the object-safe stage traits with trivial
//! implementations so each stage can be tested alone.

pub mod assets;
pub mod capabilities;
pub mod frames;
pub mod interact;
pub mod length;
pub mod math;
pub mod measure;
pub mod mesh;
pub mod pose;
pub mod shapes;
pub mod stages;
pub mod state;
pub mod topology;

pub use frames::{BodyFrame, CoarseFrame, Contact, FineSurface, FineVertexSource, StepReport};
pub use math::{Real, Vec3};
pub use measure::{Landmarks, MeasureError, Measurements};
pub use mesh::{Face, MeshError, PolyMesh};
pub use topology::{Topology, TopologyError};
