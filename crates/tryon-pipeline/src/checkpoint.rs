//! Checkpoints (issue 24): a long run writes its whole state every N frames to
//! `checkpoint.tryon` in its output folder, and a killed run goes on from there to the same bytes
//! an uninterrupted run writes.
//!
//! A checkpoint holds each stage's state (`tryon_core::state`: every stage object whole), the
//! pipeline's own (the coarse cloth, the fine surface, the bands, a grab still to come), the
//! frame loop's ([`RunState`]) and the outputs' (the GLB writer's in-memory figures, the
//! preview's frame, how far the streamed files had got). It also names how the run was made (the
//! caller's `invocation`, e.g. the command line) and a fingerprint of the scene as built, so a
//! run resumes only onto the scene it was made from. The file is written atomically:
//! `TRYONCK6`, a postcard body, and an FNV-1a check sum of the body.

use crate::pipeline::Pipeline;
use crate::run::RunState;
use body_collide::Bands;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::frames::{CoarseFrame, FineSurface};
use tryon_core::interact::Grab;
use tryon_core::pose::Pose;
use tryon_core::state::{StateError, decode, encode, fnv1a};

/// The checkpoint's file name in a run's output folder.
pub const FILE: &str = "checkpoint.tryon";
/// Raised whenever the layout of what a checkpoint holds changes (postcard is not self-describing,
/// so an older layout could otherwise be read as the new one): 5 since VBD lost its coarse pokes.
const MAGIC: &[u8; 8] = b"TRYONCK6";

/// Why a run could not go on from its checkpoint.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CheckpointError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: not a tryon checkpoint (or one from another version of tryon)", path.display())]
    NotACheckpoint { path: PathBuf },
    #[error("{}: damaged (its check sum does not match)", path.display())]
    Damaged { path: PathBuf },
    #[error("{}: {source}", path.display())]
    Decode { path: PathBuf, source: StateError },
    #[error(
        "{}: the scene changed since the checkpoint was written (its settings, meshes or motion \
         differ); run it again from the start",
        path.display()
    )]
    SceneChanged { path: PathBuf },
    #[error("{}: the {stage} does not take the checkpoint's state: {source}", path.display())]
    Stage {
        path: PathBuf,
        stage: String,
        source: StateError,
    },
}

/// Everything a run needs to go on from a frame.
#[derive(Debug, Serialize, Deserialize)]
pub struct Checkpoint {
    /// How the run was made, as its caller wrote it (the command line keeps its arguments).
    pub invocation: String,
    /// [`Pipeline::fingerprint`] of the run's pipeline.
    pub fingerprint: u64,
    /// The last frame written before the checkpoint.
    pub frame: usize,
    pub stages: StageStates,
    pub run: RunState,
    /// The outputs' state (`FrameSink::save_state`).
    pub sink: Vec<u8>,
}

/// The stages' states and the pipeline's own between frames.
#[derive(Debug, Serialize, Deserialize)]
pub struct StageStates {
    body: Vec<u8>,
    follower: Option<Vec<u8>>,
    collider: Option<Vec<u8>>,
    solver: Vec<u8>,
    surface_stages: Vec<Vec<u8>>,
    referee: Vec<u8>,
    cloth: CoarseFrame,
    surface: FineSurface,
    bands: Option<Bands>,
    grab: Option<Grab>,
}

impl Checkpoint {
    /// Writes the checkpoint to `dir`/[`FILE`] atomically.
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        let body = encode(self);
        let mut bytes = Vec::with_capacity(body.len() + 16);
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&body);
        bytes.extend_from_slice(&fnv1a(&body).to_le_bytes());
        tryon_io::write_atomic(&dir.join(FILE), &bytes)
    }

    /// Reads `dir`/[`FILE`].
    pub fn read(dir: &Path) -> Result<Checkpoint, CheckpointError> {
        let path = dir.join(FILE);
        let bytes = std::fs::read(&path).map_err(|source| CheckpointError::Io {
            path: path.clone(),
            source,
        })?;
        let Some(body) = bytes
            .strip_prefix(MAGIC)
            .filter(|b| b.len() >= 8)
            .map(|b| &b[..b.len() - 8])
        else {
            return Err(CheckpointError::NotACheckpoint { path });
        };
        let sum = u64::from_le_bytes(bytes[bytes.len() - 8..].try_into().unwrap_or_default());
        if fnv1a(body) != sum {
            return Err(CheckpointError::Damaged { path });
        }
        decode(body).map_err(|source| CheckpointError::Decode { path, source })
    }
}

impl Pipeline {
    /// A fingerprint of the pipeline as built for `frames` frames: the scene's settings, the body
    /// and garment as placed, the cloth's starting state and the motion sampled over the run.
    /// Call before the run starts.
    pub fn fingerprint(&self, frames: usize) -> u64 {
        let scene = serde_json::to_string(&self.scene).unwrap_or_default();
        let mut poses: Vec<Pose> = Vec::new();
        if let Some(m) = &self.motion {
            let samples = frames.clamp(1, 64);
            for k in 0..=samples {
                let mut pose = Pose::default();
                m.sample(self.frame_time(k * frames / samples), &mut pose);
                poses.push(pose);
            }
        }
        let what = (
            scene,
            frames,
            &self.body_mesh.positions,
            &self.garment.positions,
            &self.cloth,
            poses,
        );
        fnv1a(&encode(&what))
    }

    /// The stages' states, or the name of the first stage that cannot be checkpointed.
    pub fn save_stages(&self) -> Result<StageStates, String> {
        let need = |s: Option<Vec<u8>>, name: &str| s.ok_or_else(|| name.to_string());
        let opt = |s: Option<Option<Vec<u8>>>, name: &str| s.map(|x| need(x, name)).transpose();
        Ok(StageStates {
            body: need(self.body.save_state(), "body model")?,
            follower: opt(
                self.follower.as_ref().map(|f| f.save_state()),
                "body follower",
            )?,
            collider: opt(self.collider.as_ref().map(|c| c.save_state()), "collider")?,
            solver: need(self.solver.save_state(), "cloth solver")?,
            surface_stages: (self.surface_stages.iter())
                .map(|s| need(s.save_state(), &s.parts().join("+")))
                .collect::<Result<_, _>>()?,
            referee: need(
                tryon_core::stages::Collider::save_state(&self.referee),
                "referee",
            )?,
            cloth: self.cloth.clone(),
            surface: self.surface.clone(),
            bands: self.bands.clone(),
            grab: self.grab.clone(),
        })
    }

    /// Takes back the stages' states on a pipeline built the same way (from `path`, for errors).
    pub fn restore_stages(&mut self, s: StageStates, path: &Path) -> Result<(), CheckpointError> {
        let err = |stage: &str| {
            let (path, stage) = (path.to_path_buf(), stage.to_string());
            move |source| CheckpointError::Stage {
                path,
                stage,
                source,
            }
        };
        let mismatch = |what: &str| StateError::Mismatch(what.to_string());
        self.body
            .restore_state(&s.body)
            .map_err(err("body model"))?;
        match (&mut self.follower, &s.follower) {
            (Some(f), Some(b)) => f.restore_state(b).map_err(err("body follower"))?,
            (None, None) => {}
            _ => {
                return Err(err("body follower")(mismatch(
                    "on in one, off in the other",
                )));
            }
        }
        match (&mut self.collider, &s.collider) {
            (Some(c), Some(b)) => c.restore_state(b).map_err(err("collider"))?,
            (None, None) => {}
            _ => return Err(err("collider")(mismatch("on in one, off in the other"))),
        }
        self.solver
            .restore_state(&s.solver)
            .map_err(err("cloth solver"))?;
        if s.surface_stages.len() != self.surface_stages.len() {
            return Err(err("surface")(mismatch(
                "a different count of surface stages",
            )));
        }
        for (stage, b) in self.surface_stages.iter_mut().zip(&s.surface_stages) {
            let name = stage.parts().join("+");
            stage.restore_state(b).map_err(err(&name))?;
        }
        tryon_core::stages::Collider::restore_state(&mut self.referee, &s.referee)
            .map_err(err("referee"))?;
        let particles = self.cloth.positions.len();
        if s.cloth.positions.len() != particles || s.cloth.velocities.len() != particles {
            return Err(err("cloth")(mismatch("a different count of particles")));
        }
        if s.bands.is_some() != self.bands.is_some() {
            return Err(err("bands")(mismatch("on in one, off in the other")));
        }
        self.cloth = s.cloth;
        self.surface = s.surface;
        self.bands = s.bands;
        self.grab = s.grab;
        Ok(())
    }
}
