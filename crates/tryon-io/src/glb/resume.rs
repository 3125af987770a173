//! A [`GlbWriter`] stopped at a checkpoint and taken up again: what it keeps in memory is saved
//! (the spool flushed to disk first), and a writer made again from the same header reopens the
//! spool and cuts it back to the checkpoint's length (a run killed after its checkpoint may
//! have spooled frames the resumed run makes again).

use super::{GlbError, GlbHeader, GlbWriter, Spool};
use std::fs::OpenOptions;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use tryon_core::math::{Real, Vec3};

/// What a [`GlbWriter`] holds between frames, beside its spool's bytes.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GlbState {
    /// The spool file and its length at the checkpoint.
    pub spool: PathBuf,
    pub spooled: u64,
    pub times: Vec<Real>,
    pub rotations: Vec<[f32; 4]>,
    pub root_translations: Vec<Vec3>,
    pub body_targets: Vec<Vec<(u32, [f32; 3])>>,
    pub base: Vec<Vec3>,
    pub base_normals: Vec<Vec3>,
    pub targets: Vec<(u64, [f32; 3], [f32; 3])>,
}

impl GlbWriter {
    /// Flushes the spool and gives the writer's state (`None` for an in-memory writer, or one
    /// that has met an error: its `finish` reports it).
    pub fn checkpoint(&mut self) -> Option<GlbState> {
        if self.error.is_some() {
            return None;
        }
        let Spool::File { out, path } = &mut self.spool else {
            return None;
        };
        if let Err(source) = out.flush() {
            self.error = Some(GlbError::Io {
                path: path.clone(),
                source,
            });
            return None;
        }
        Some(GlbState {
            spool: path.clone(),
            spooled: self.spooled,
            times: self.times.clone(),
            rotations: self.rotations.clone(),
            root_translations: self.root_translations.clone(),
            body_targets: self.body_targets.clone(),
            base: self.base.clone(),
            base_normals: self.base_normals.clone(),
            targets: self.targets.clone(),
        })
    }

    /// A writer of the GLB at `path` (described by `header`, as when it was created) that goes
    /// on from `state`: its spool must be beside `path` and hold at least the saved bytes.
    pub fn resume(path: &Path, header: &GlbHeader, state: GlbState) -> Result<Self, GlbError> {
        let spool = path.with_file_name(state.spool.file_name().unwrap_or_default());
        let io = |source| GlbError::Io {
            path: spool.clone(),
            source,
        };
        let mut file = OpenOptions::new().write(true).open(&spool).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        if len < state.spooled {
            return Err(GlbError::Invalid(format!(
                "{}: the spool holds {len} bytes, the checkpoint says {}",
                spool.display(),
                state.spooled
            )));
        }
        file.set_len(state.spooled).map_err(io)?;
        file.seek(SeekFrom::End(0)).map_err(io)?;
        let spool_file = Spool::File {
            out: BufWriter::new(file),
            path: spool.clone(),
        };
        let mut w = Self::with_spool(Some(path.to_path_buf()), header, spool_file)?;
        let frames = state.times.len();
        let joints = w.body.rig.as_ref().map_or(0, |r| r.joint_names.len());
        let in_base = |v: &u32| (*v as usize) < state.base.len();
        let fits = (frames == 0 || header.garment_triangles.iter().flatten().all(in_base))
            && state.base_normals.len() == state.base.len()
            && state.targets.len() == frames.saturating_sub(1)
            && state.targets.iter().all(|t| t.0 < state.spooled)
            && state.rotations.len() == frames * joints
            && (joints == 0
                || state.root_translations.len() == frames && state.body_targets.len() == frames);
        if !fits {
            return Err(GlbError::Invalid(
                "the checkpoint's frames do not fit the scene's garment and body".into(),
            ));
        }
        w.spooled = state.spooled;
        w.times = state.times;
        w.rotations = state.rotations;
        w.root_translations = state.root_translations;
        w.body_targets = state.body_targets;
        w.base = state.base;
        w.base_normals = state.base_normals;
        w.targets = state.targets;
        Ok(w)
    }
}
