//! tryon-pipeline: the only crate that wires stages together: the scene file ([`Scene`], TOML),
//! assembly of only the stages a scene enables ([`Pipeline`], its builders in `build`), the one
//! frame loop (`pipeline`), whole runs with accuracy metrics judged by the exact referee
//! ([`RunOutput`], [`Stats`]), exports, and the drape fixture (a scene on the same loop) used by
//! tests and benchmarks.
//!
//! Modules depend in one direction: scene <- real <- build <- wardrobe <- assemble -> pipeline <- run,
//! export, drape; timers and metrics are leaves.

pub mod assemble;
pub mod budget;
pub mod build;
pub mod canvas;
pub mod checkpoint;
pub mod drape;
pub mod export;
pub mod folding;
mod garments;
pub mod kimono;
pub mod kimono_wear;
pub mod live;
mod object;
pub mod pipeline;
pub mod real;
pub mod resume;
pub mod run;
pub mod scene;
pub mod stats;
pub mod timers;
pub mod wardrobe;

pub use assemble::AssembleError;
/// The referee's measures, in body-collide (kept under this name for the callers).
pub use body_collide::metrics;
pub use drape::{DrapeConfig, DrapeError, DrapeReport, DrapeScene, FrameTrace};
pub use export::{ExportError, Outputs};
pub use pipeline::{LoopState, Options, Pipeline, Progress};
pub use real::AssetError;
pub use run::{FrameRecord, FrameSink, RunHeader, RunOutput, RunSummary, Stats};
pub use scene::{DEMO_SCENE, Scene, SceneError};
