//! `tryon run --resume DIR`: a killed run goes on from the checkpoint in its output folder. The
//! checkpoint keeps how the run was asked for ([`Invocation`]), so the same scene, overrides,
//! frame count and limits build the same pipeline again.

use crate::report::{Start, run};
use crate::{BudgetFlags, Failure, assemble, demo_scene, load};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use tryon_pipeline::Scene;
use tryon_pipeline::checkpoint::{Checkpoint, FILE};
use tryon_pipeline::resume::Checkpointing;

/// How a run was asked for on the command line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Invocation {
    /// The scene file (absolute), or `None` for the embedded demo.
    pub scene: Option<PathBuf>,
    pub sets: Vec<String>,
    pub frames: Option<usize>,
    pub limits: Vec<String>,
    /// Frames between checkpoints.
    pub every: usize,
}

impl Invocation {
    /// The checkpoints of a run asked for this way.
    pub fn checkpointing(&self) -> Checkpointing {
        Checkpointing {
            every: self.every,
            invocation: serde_json::to_string(self).unwrap_or_default(),
        }
    }

    /// The scene it names, overrides applied.
    fn scene(&self) -> Result<Scene, Failure> {
        match &self.scene {
            Some(path) => load(path, &self.sets),
            None => demo_scene(&self.sets),
        }
    }
}

/// Goes on with the run whose output folder is `dir`.
pub(crate) fn resume(dir: &Path, quiet: bool) -> Result<bool, Failure> {
    let checkpoint = Checkpoint::read(dir).map_err(|e| match e {
        tryon_pipeline::checkpoint::CheckpointError::Io { source, .. }
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            Failure::BadInput(format!(
                "{}: no checkpoint: the run finished, or wrote none before it stopped \
                 (`--checkpoint-every`)",
                dir.join(FILE).display()
            ))
        }
        e => Failure::BadInput(e.to_string()),
    })?;
    let inv: Invocation = serde_json::from_str(&checkpoint.invocation).map_err(|e| {
        Failure::BadInput(format!(
            "{}: does not say how its run was asked for ({e}); was it written by `tryon run`?",
            dir.join(FILE).display()
        ))
    })?;
    let file = inv
        .scene
        .as_ref()
        .map_or("<embedded demo>".into(), |p| p.display().to_string());
    let budget = BudgetFlags {
        limits: inv.limits.clone(),
    };
    for l in &budget.limits {
        tryon_pipeline::budget::Limits::default()
            .set(l)
            .map_err(|e| Failure::BadInput(format!("{}: {e}", dir.join(FILE).display())))?;
    }
    let p = assemble(inv.scene()?, &file, quiet, &budget, inv.frames)?;
    if !quiet {
        eprintln!(
            "resuming {} after frame {} of {}",
            file, checkpoint.frame, checkpoint.run.stats.frames
        );
    }
    let every = inv.every;
    run(
        p,
        dir,
        Start::Resume {
            checkpoint: Box::new(checkpoint),
            every,
        },
        quiet,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_invocation_survives_the_checkpoint() {
        let inv = Invocation {
            scene: Some(PathBuf::from("/a/b.toml")),
            sets: vec!["effects.wrinkles=true".into()],
            frames: Some(12),
            limits: vec!["hours=9".into()],
            every: 4,
        };
        let c = inv.checkpointing();
        assert_eq!(c.every, 4);
        let back: Invocation = serde_json::from_str(&c.invocation).unwrap();
        assert_eq!(back, inv);
    }

    #[test]
    fn a_folder_without_a_checkpoint_is_named() {
        let dir = std::env::temp_dir().join(format!("tryon-cli-nockpt-{}", std::process::id()));
        let Err(Failure::BadInput(m)) = resume(&dir, true) else {
            panic!("a folder without a checkpoint is bad input");
        };
        assert!(
            m.contains("checkpoint.tryon") && m.contains("no checkpoint"),
            "{m}"
        );
    }
}
