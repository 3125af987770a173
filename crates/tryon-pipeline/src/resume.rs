//! Runs that write checkpoints, and runs that go on from one (`tryon run --resume DIR`): the
//! drivers around the frame loop of `run` and the outputs of `export` (the checkpoint itself is
//! `checkpoint`).

use crate::checkpoint::{Checkpoint, CheckpointError, FILE};
use crate::export::{ExportError, Outputs};
use crate::pipeline::Pipeline;
use crate::run::{FrameSink, RunState, Stats};
use std::path::{Path, PathBuf};
use thiserror::Error;

/// How a run writes checkpoints.
#[derive(Clone, Debug, Default)]
pub struct Checkpointing {
    /// Frames between two checkpoints (0: none).
    pub every: usize,
    /// How the run was made, kept in the checkpoint for whoever resumes it (the command line
    /// writes its arguments).
    pub invocation: String,
}

/// Why a run could not go on from its checkpoint.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ResumeError {
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error(transparent)]
    Export(#[from] ExportError),
}

/// What a checkpointed run wrote.
#[derive(Debug)]
pub struct Written {
    pub stats: Stats,
    pub files: Vec<PathBuf>,
    /// Why no checkpoint was written, when checkpoints were asked for and none could be.
    pub no_checkpoints: Option<String>,
}

impl Pipeline {
    /// [`Pipeline::run_to`] writing a checkpoint into `dir` every `c.every` frames (none when
    /// a stage cannot be checkpointed: `Written::no_checkpoints` says which). The checkpoint is
    /// removed once the outputs are written.
    pub fn run_checkpointed(
        &mut self,
        dir: &Path,
        frames: Option<usize>,
        c: &Checkpointing,
        progress: impl FnMut(usize, usize),
    ) -> Result<Written, ExportError> {
        let frames = frames.unwrap_or(self.frames);
        let mut no_checkpoints = None;
        let every = match c.every {
            0 => 0,
            n => match self.save_stages() {
                Ok(_) => n,
                Err(stage) => {
                    no_checkpoints = Some(format!("the {stage} cannot be checkpointed"));
                    0
                }
            },
        };
        let fingerprint = if every > 0 {
            self.fingerprint(frames)
        } else {
            0
        };
        let mut out = Outputs::new(dir, &self.scene.output)?;
        let (ctx, state) = self.prepare(Some(frames));
        self.begin_sink(&ctx, &state, &mut out);
        let mut writer = CheckpointWriter {
            dir,
            every,
            invocation: &c.invocation,
            fingerprint,
            failed: None,
        };
        let summary = self.run_from(ctx, state, progress, &mut out, &mut |p, st, sink, k| {
            writer.maybe_write(p, st, sink, k)
        });
        let files = out.finish(self, &summary.stats)?;
        let _ = std::fs::remove_file(dir.join(FILE));
        Ok(Written {
            stats: summary.stats,
            files,
            no_checkpoints: no_checkpoints.or(writer.failed),
        })
    }

    /// Goes on with the run whose checkpoint `ck` was read from `dir`, on a pipeline built the
    /// same way, writing checkpoints as the run did (every `every` frames).
    pub fn resume_from(
        &mut self,
        dir: &Path,
        ck: Checkpoint,
        every: usize,
        progress: impl FnMut(usize, usize),
    ) -> Result<Written, ResumeError> {
        let path = dir.join(FILE);
        let frames = ck.run.stats.frames;
        if self.fingerprint(frames) != ck.fingerprint {
            return Err(CheckpointError::SceneChanged { path }.into());
        }
        let (ctx, _) = self.prepare(Some(frames));
        self.restore_stages(ck.stages, &path)?;
        remove_half_written(dir);
        let mut out = Outputs::resume(dir, &self.scene.output, &self.header(&ctx), &ck.sink)?;
        let mut writer = CheckpointWriter {
            dir,
            every,
            invocation: &ck.invocation,
            fingerprint: ck.fingerprint,
            failed: None,
        };
        let summary = self.run_from(ctx, ck.run, progress, &mut out, &mut |p, st, sink, k| {
            writer.maybe_write(p, st, sink, k)
        });
        let files = out.finish(self, &summary.stats)?;
        let _ = std::fs::remove_file(&path);
        Ok(Written {
            stats: summary.stats,
            files,
            no_checkpoints: writer.failed,
        })
    }
}

/// Removes what a killed run left half written in `dir`: the temporary files of a checkpoint
/// or of an OBJ frame being written atomically when it was killed (`.NAME.PID.tmp`).
fn remove_half_written(dir: &Path) {
    for folder in [dir.to_path_buf(), dir.join("garment-obj")] {
        let Ok(entries) = std::fs::read_dir(&folder) else {
            continue;
        };
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            let ours = name.starts_with(&format!(".{FILE}.")) || name.starts_with(".garment_");
            if ours && name.ends_with(".tmp") {
                let _ = std::fs::remove_file(e.path());
            }
        }
    }
}

/// Writes a checkpoint after each frame that is due.
struct CheckpointWriter<'a> {
    dir: &'a Path,
    every: usize,
    invocation: &'a str,
    fingerprint: u64,
    /// The first failure to write one (the run goes on without).
    failed: Option<String>,
}

impl CheckpointWriter<'_> {
    fn maybe_write(&mut self, p: &Pipeline, st: &RunState, sink: &mut dyn FrameSink, k: usize) {
        if self.every == 0 || !k.is_multiple_of(self.every) || self.failed.is_some() {
            return;
        }
        let written = match (p.save_stages(), sink.save_state()) {
            (Ok(stages), Some(sink)) => Checkpoint {
                invocation: self.invocation.to_string(),
                fingerprint: self.fingerprint,
                frame: k,
                stages,
                run: st.clone(),
                sink,
            }
            .write(self.dir)
            .map_err(|e| format!("{}: cannot write: {e}", self.dir.join(FILE).display())),
            (Err(stage), _) => Err(format!("the {stage} cannot be checkpointed")),
            (_, None) => Err("the outputs cannot be checkpointed".into()),
        };
        self.failed = written.err();
    }
}
