//! tryon-pipeline: the only crate that wires stages together. For now: the coarse loop (body
//! following, collision, cloth dynamics), accuracy metrics judged by the exact referee, and the drape
//! scene fixture used by tests and benchmarks.

pub mod coarse;
pub mod drape;
pub mod metrics;

pub use coarse::CoarseLoop;
pub use drape::{DrapeConfig, DrapeError, DrapeReport, DrapeScene, FrameTrace};
