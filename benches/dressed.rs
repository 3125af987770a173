//! The dress of makehuman-dress-walk a number of frames into its walk, for the benches that
//! measure one stage's work on a real frame (`collider.rs`, `referee.rs`); `None` without the
//! shared assets.

use std::path::Path;
use tryon_pipeline::run::Timers;
use tryon_pipeline::{LoopState, Pipeline, Scene};

/// The pipeline and its loop state after `warm` frames (2 under `--test` or a debug build).
pub fn dressed(bench: &str, warm: usize) -> Option<(Pipeline, LoopState)> {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes/makehuman-dress-walk.toml");
    let scene = Scene::load_with_overrides(&path, &[])
        .map_err(|e| eprintln!("{bench}: skipped: {e}"))
        .ok()?;
    let mut p = Pipeline::new(scene).ok()?;
    let mut st = p.start();
    let mut timers = Timers::default();
    let warm = if cfg!(debug_assertions) || std::env::args().any(|a| a == "--test") {
        2
    } else {
        warm
    };
    for k in 1..warm {
        p.advance(&mut st, p.frame_time(k), &mut timers);
    }
    Some((p, st))
}
