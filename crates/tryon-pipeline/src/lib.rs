//! tryon-pipeline: the only crate that wires stages together: assembly of only the stages a
//! scene enables ([`Pipeline`], its builders in `build`; the scene file is tryon-scene's
//! [`Scene`]), the one frame loop (`pipeline`), whole runs judged by the exact referee
//! ([`RunOutput`], [`Stats`]), exports, checkpoints, live steering, the kimono job and the
//! kimono's dressing driven on the frame loop (`kimono_wear`, its geometry in `kimono::dress`),
//! and the drape fixture (a scene on the same loop) used by tests and benchmarks.
//!
//! Modules depend in one direction: real <- build <- wardrobe <- assemble -> pipeline <- run,
//! export, drape, kimono_wear; timers are a leaf.

pub mod assemble;
pub mod budget;
pub mod build;
pub mod canvas;
pub mod checkpoint;
pub mod drape;
pub mod export;
pub mod folding;
mod garments;
mod judge;
pub mod kimono;
pub mod kimono_wear;
pub mod live;
mod object;
pub mod pipeline;
pub mod real;
pub mod resume;
pub mod run;
/// The scene file (its own crate, re-exported under its old path).
pub use tryon_scene as scene;
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
