//! tryon-pipeline: the only crate that wires stages together: the scene file ([`Scene`], TOML),
//! assembly of only the stages a scene enables ([`Pipeline`]), the timed frame loop with accuracy
//! metrics judged by the exact referee ([`RunOutput`], [`Stats`]), the coarse loop, and the drape
//! fixture used by tests and benchmarks.

pub mod assemble;
pub mod coarse;
pub mod drape;
pub mod export;
pub mod fine;
pub mod metrics;
pub mod real;
pub mod run;
pub mod scene;

pub use assemble::{AssembleError, BodyDriver, Pipeline, garment_params};
pub use coarse::CoarseLoop;
pub use drape::{DrapeConfig, DrapeError, DrapeReport, DrapeScene, FrameTrace};
pub use export::ExportError;
pub use real::AssetError;
pub use run::{FrameRecord, RunOutput, Stats};
pub use scene::{DEMO_SCENE, Scene, SceneError};
