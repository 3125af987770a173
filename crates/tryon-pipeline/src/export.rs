//! Writing a run's outputs into a directory as the run goes: scene.glb (skinned body + morph-target
//! garment, streamed by tryon-io's `GlbWriter` and written atomically at the end), frames.jsonl
//! (the referee's figures of each judged frame, one JSON object a line, streamed as frames are
//! made), preview.png (one frame, body and garment in different colours; only that frame is
//! kept) and stats.json (at the end). With checkpoints, the outputs' state goes into each one
//! and a resumed run's outputs go on from it (`checkpoint`).

mod caches;
pub use caches::{ViewMeshes, view_header};

use crate::pipeline::Pipeline;
use crate::run::{FrameRecord, FrameSink, FrameStats, RunHeader, RunOutput, Stats};
use crate::scene::OutputSection;
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::math::{Real, Vec3};
use tryon_io::{
    BodyExport, Camera, FramePose, GifWriter, GlbError, GlbHeader, GlbWriter, Pc2Writer,
    PreviewError, SkinnedExport, UsdWriter, render, write_json, write_png,
};

use caches::{GIF, OBJ_DIR, PC2, USD, VIEW};

/// The body's colour in pictures.
const BODY_COLOUR: [u8; 3] = [205, 170, 150];

/// Why an output could not be written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ExportError {
    #[error("{}: cannot create the output directory: {source}", path.display())]
    Dir {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Glb(#[from] GlbError),
    #[error(transparent)]
    Preview(#[from] PreviewError),
    #[error(transparent)]
    Cache(#[from] tryon_io::CacheError),
    #[error("{}: cannot write: {source}", path.display())]
    Json {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// The outputs a scene asks for, taking frames as they are made.
#[derive(Debug)]
pub struct Outputs {
    dir: PathBuf,
    config: OutputSection,
    glb: Option<GlbWriter>,
    /// The frame the preview shows (the chosen one once reached, else the latest).
    preview: Option<(usize, FrameRecord)>,
    frames: usize,
    garment_triangles: Vec<[u32; 3]>,
    /// The garment each of `garment_triangles` belongs to, and the garments' names.
    triangle_garment: Vec<u16>,
    garment_names: Vec<String>,
    body_triangles: Vec<[u32; 3]>,
    /// frames.jsonl as it is streamed, and the bytes written to it.
    per_frame: Option<(std::io::BufWriter<std::fs::File>, u64)>,
    /// garment.pc2 (made at the first frame, when the garment's vertex count is known).
    pc2: Option<Pc2Writer>,
    /// run.gif, its camera as frame 0 framed it and the body's centre then (the camera follows
    /// the body's centre from there).
    gif: Option<(GifWriter, Camera, Vec3)>,
    /// run.usda (made at the first frame) and its meshes' point counts.
    usd: Option<(UsdWriter, Vec<usize>)>,
    /// view.bin (made at the first frame) and its meshes' vertex counts (body, coarse, garment).
    view: Option<(tryon_io::ViewWriter, [usize; 3])>,
    coarse_triangles: Vec<[u32; 3]>,
    name: String,
    fps: Real,
    error: Option<ExportError>,
}

/// What [`Outputs`] has taken, for a checkpoint.
#[derive(Debug, serde::Serialize, serde::Deserialize)]
struct OutputsState {
    glb: Option<tryon_io::GlbState>,
    preview: Option<(usize, FrameRecord)>,
    frames: usize,
    per_frame_bytes: Option<u64>,
    pc2: Option<tryon_io::Pc2State>,
    gif: Option<(tryon_io::GifState, Camera, Vec3)>,
    usd: Option<(tryon_io::UsdState, Vec<usize>)>,
    view: Option<(u64, [usize; 3])>,
}

impl Outputs {
    /// Creates `dir` for the outputs `config` asks for.
    pub fn new(dir: &Path, config: &OutputSection) -> Result<Outputs, ExportError> {
        std::fs::create_dir_all(dir).map_err(|source| ExportError::Dir {
            path: dir.to_path_buf(),
            source,
        })?;
        Ok(Outputs {
            dir: dir.to_path_buf(),
            config: config.clone(),
            glb: None,
            preview: None,
            frames: 0,
            garment_triangles: Vec::new(),
            triangle_garment: Vec::new(),
            garment_names: Vec::new(),
            body_triangles: Vec::new(),
            per_frame: None,
            pc2: None,
            gif: None,
            usd: None,
            view: None,
            coarse_triangles: Vec::new(),
            name: String::new(),
            fps: 30.0,
            error: None,
        })
    }

    /// The outputs of a run resumed from a checkpoint whose outputs' state is `state`: the GLB
    /// writer and frames.jsonl go on where the checkpoint left them.
    pub fn resume(
        dir: &Path,
        config: &OutputSection,
        header: &RunHeader<'_>,
        state: &[u8],
    ) -> Result<Outputs, ExportError> {
        let bad = |m: String| ExportError::Glb(GlbError::Invalid(m));
        let st: OutputsState = tryon_core::state::decode(state).map_err(|e| bad(e.to_string()))?;
        let mut out = Outputs::new(dir, config)?;
        out.take_header(header);
        out.glb = match st.glb {
            Some(g) => Some(GlbWriter::resume(
                &dir.join("scene.glb"),
                &glb_header(header),
                g,
            )?),
            None => None,
        };
        if out.config.glb != out.glb.is_some() || out.config.stats != st.per_frame_bytes.is_some() {
            return Err(bad("the checkpoint's outputs are not the scene's".into()));
        }
        if let Some(len) = st.per_frame_bytes {
            let path = dir.join("frames.jsonl");
            let io = |source| ExportError::Json {
                path: path.clone(),
                source,
            };
            let mut f = std::fs::OpenOptions::new()
                .write(true)
                .open(&path)
                .map_err(io)?;
            if f.metadata().map_err(io)?.len() < len {
                return Err(bad(format!(
                    "{}: shorter than at the checkpoint",
                    path.display()
                )));
            }
            f.set_len(len).map_err(io)?;
            std::io::Seek::seek(&mut f, std::io::SeekFrom::End(0)).map_err(io)?;
            out.per_frame = Some((std::io::BufWriter::new(f), len));
        }
        if out.config.pc2 != st.pc2.is_some() {
            return Err(bad("the checkpoint's outputs are not the scene's".into()));
        }
        if let Some(pc2) = &st.pc2 {
            out.pc2 = Some(Pc2Writer::resume(&dir.join(PC2), pc2)?);
        }
        if out.config.gif != st.gif.is_some() {
            return Err(bad("the checkpoint's outputs are not the scene's".into()));
        }
        if let Some((g, camera, centre)) = st.gif {
            let w = GifWriter::resume(&dir.join(GIF), out.gif_shape(), g)?;
            out.gif = Some((w, camera, centre));
        }
        if out.config.usd != st.usd.is_some() {
            return Err(bad("the checkpoint's outputs are not the scene's".into()));
        }
        if let Some((u, points)) = st.usd {
            let meshes = out.usd_meshes(&points);
            let w = UsdWriter::resume(&dir.join(USD), out.fps, meshes, &u)?;
            out.usd = Some((w, points));
        }
        if out.config.view != st.view.is_some() {
            return Err(bad("the checkpoint's outputs are not the scene's".into()));
        }
        if let Some((frames, counts)) = st.view {
            let header = out.view_header(counts);
            let w = tryon_io::ViewWriter::resume(&dir.join(VIEW), header, frames)?;
            out.view = Some((w, counts));
        }
        out.preview = st.preview;
        out.frames = st.frames;
        Ok(out)
    }

    /// Keeps what the outputs need of the run's header.
    fn take_header(&mut self, h: &RunHeader<'_>) {
        self.garment_triangles = h.garment_triangles.to_vec();
        self.triangle_garment = h.triangle_garment.to_vec();
        self.garment_names = h.garment_names.to_vec();
        self.body_triangles = h.body_triangles.to_vec();
        self.coarse_triangles = h.coarse_triangles.to_vec();
        self.name = h.name.to_string();
        self.fps = h.fps;
    }

    /// The GIF's width, height and delay a frame (1/100 s).
    fn gif_shape(&self) -> (u32, u32, u16) {
        let c = &self.config;
        let height = (c.gif_width as u64 * c.preview_height as u64) / c.preview_width.max(1) as u64;
        let delay = (100.0 * c.gif_every as Real / self.fps)
            .round()
            .clamp(1.0, 65535.0);
        (c.gif_width, (height as u32).max(1), delay as u16)
    }

    /// Writes what is left (the GLB's layout, the preview, stats.json) and returns the files
    /// written, or the first error met while writing.
    pub fn finish(mut self, p: &Pipeline, stats: &Stats) -> Result<Vec<PathBuf>, ExportError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let mut written = Vec::new();
        if let Some((mut f, _)) = self.per_frame.take() {
            let path = self.dir.join("frames.jsonl");
            std::io::Write::flush(&mut f).map_err(|source| ExportError::Json {
                path: path.clone(),
                source,
            })?;
            written.push(path);
        }
        if let Some((gif, ..)) = self.gif.take() {
            gif.finish()?;
            written.push(self.dir.join(GIF));
        }
        if let Some(pc2) = self.pc2.take() {
            pc2.finish()?;
            written.push(self.dir.join(PC2));
        }
        if let Some((usd, _)) = self.usd.take() {
            usd.finish()?;
            written.push(self.dir.join(USD));
        }
        if let Some((view, _)) = self.view.take() {
            view.finish()?;
            written.push(self.dir.join(VIEW));
        }
        if self.config.obj_sequence && self.frames > 0 {
            written.push(self.dir.join(OBJ_DIR));
        }
        if let Some(glb) = self.glb.take()
            && self.frames > 0
        {
            glb.finish()?;
            written.push(self.dir.join("scene.glb"));
        }
        if let Some((_, rec)) = &self.preview {
            let path = self.dir.join("preview.png");
            let body = p.body_at(rec.pose.as_ref());
            let parts = self.garments();
            let meshes = caches::picture(&self.body_triangles, &body, &rec.garment, &parts);
            let cam = Camera::framing(&meshes);
            let (w, h) = (self.config.preview_width, self.config.preview_height);
            write_png(&path, &render(&meshes, &cam, w, h))?;
            written.push(path);
        }
        if self.config.stats {
            let path = self.dir.join("stats.json");
            write_json(&path, stats).map_err(|source| ExportError::Json {
                path: path.clone(),
                source,
            })?;
            written.push(path);
        }
        Ok(written)
    }
}

impl FrameSink for Outputs {
    fn begin(&mut self, h: &RunHeader<'_>) {
        self.take_header(h);
        if self.config.obj_sequence {
            let path = self.dir.join(OBJ_DIR);
            if let Err(source) = std::fs::create_dir_all(&path) {
                self.error = Some(ExportError::Dir { path, source });
            }
        }
        if self.config.stats {
            let path = self.dir.join("frames.jsonl");
            match std::fs::File::create(&path) {
                Ok(f) => self.per_frame = Some((std::io::BufWriter::new(f), 0)),
                Err(source) => self.error = Some(ExportError::Json { path, source }),
            }
        }
        if !self.config.glb {
            return;
        }
        match GlbWriter::create(&self.dir.join("scene.glb"), &glb_header(h)) {
            Ok(w) => self.glb = Some(w),
            Err(e) => self.error = Some(e.into()),
        }
    }

    fn frame_stats(&mut self, stats: &FrameStats) {
        let Some((f, written)) = &mut self.per_frame else {
            return;
        };
        let mut line = serde_json::to_vec(stats).unwrap_or_default();
        line.push(b'\n');
        match std::io::Write::write_all(f, &line) {
            Ok(()) => *written += line.len() as u64,
            Err(source) => {
                let path = self.dir.join("frames.jsonl");
                self.error.get_or_insert(ExportError::Json { path, source });
                self.per_frame = None;
            }
        }
    }

    fn save_state(&mut self) -> Option<Vec<u8>> {
        if self.error.is_some() {
            return None;
        }
        let glb = match &mut self.glb {
            Some(g) => Some(g.checkpoint()?),
            None => None,
        };
        let pc2 = match &mut self.pc2 {
            Some(w) => Some(w.checkpoint().ok()?),
            None => None,
        };
        let gif = match &mut self.gif {
            Some((w, camera, centre)) => Some((w.checkpoint().ok()?, *camera, *centre)),
            None => None,
        };
        let usd = match &mut self.usd {
            Some((w, points)) => Some((w.checkpoint().ok()?, points.clone())),
            None => None,
        };
        let view = match &mut self.view {
            Some((w, counts)) => Some((w.checkpoint().ok()?, *counts)),
            None => None,
        };
        let per_frame_bytes = match &mut self.per_frame {
            Some((f, n)) => {
                std::io::Write::flush(f).ok()?;
                Some(*n)
            }
            None => None,
        };
        Some(tryon_core::state::encode(&OutputsState {
            glb,
            preview: self.preview.clone(),
            frames: self.frames,
            per_frame_bytes,
            pc2,
            gif,
            usd,
            view,
        }))
    }

    fn frame(&mut self, rec: &FrameRecord) {
        if let Some(glb) = &mut self.glb {
            let pose = rec.pose.as_ref().map(|p| FramePose {
                root_translation: p.root_translation,
                rotations: &p.local_rotations,
                skin_offsets: &rec.skin_offsets,
            });
            glb.frame(rec.time, &rec.garment, pose);
        }
        self.cache_frame(rec);
        if self.config.preview {
            let k = self.frames;
            let reached = matches!((&self.preview, self.config.preview_frame),
                (Some((at, _)), Some(want)) if *at == want);
            if !reached {
                self.preview = Some((k, rec.clone()));
            }
        }
        self.frames += 1;
    }

    fn wants_skin_offsets(&self) -> bool {
        self.glb.is_some()
    }

    fn wants_body(&self) -> bool {
        self.config.gif || (self.config.usd && self.config.usd_body) || self.config.view
    }

    fn wants_coarse(&self) -> bool {
        self.config.view
    }

    fn wants_depth(&self) -> bool {
        self.config.view && self.config.referee_every > 0
    }
}

/// The GLB writer's header of a run.
fn glb_header<'a>(h: &'a RunHeader<'a>) -> GlbHeader<'a> {
    let body = match h.rig {
        Some(r) => BodyExport::Skinned(SkinnedExport {
            positions: r.rest_positions,
            triangles: h.body_triangles,
            joint_names: &r.skeleton.names,
            parents: &r.skeleton.parents,
            joint_rest: r.joint_rest,
            joints: r.joints,
            weights: r.weights,
        }),
        None => BodyExport::Static {
            positions: h.body_positions,
            triangles: h.body_triangles,
        },
    };
    GlbHeader {
        name: h.name,
        body,
        garment_triangles: h.garment_triangles,
        garment_names: h.garment_names,
        triangle_garment: h.triangle_garment,
    }
}

impl Pipeline {
    /// Runs the scene (`frames` output frames, its own count when `None`) straight into the
    /// outputs it asks for in `dir`: frames are written as they are made, so memory does not grow
    /// with the run's length. Returns the statistics and the files written.
    pub fn run_to(
        &mut self,
        dir: &Path,
        frames: Option<usize>,
        progress: impl FnMut(usize, usize),
    ) -> Result<(Stats, Vec<PathBuf>), ExportError> {
        let mut out = Outputs::new(dir, &self.scene.output)?;
        let summary = self.run_into(frames, progress, &mut out);
        let files = out.finish(self, &summary.stats)?;
        Ok((summary.stats, files))
    }

    /// Writes the outputs the scene asks for of a run kept in memory into `dir`; returns the
    /// files written.
    pub fn export(&self, run: &RunOutput, dir: &Path) -> Result<Vec<PathBuf>, ExportError> {
        let mut out = Outputs::new(dir, &self.scene.output)?;
        let moving = run.frames.iter().all(|f| f.pose.is_some());
        let (garment_names, triangle_garment) = self.output_garments(&run.garment_triangles);
        out.begin(&RunHeader {
            name: &self.scene.scene.name,
            garment_triangles: &run.garment_triangles,
            garment_names: &garment_names,
            triangle_garment: &triangle_garment,
            body_positions: &self.body_mesh.positions,
            body_triangles: &run.body_triangles,
            rig: self.body.rig().filter(|_| moving && self.motion.is_some()),
            fps: run.stats.fps,
            coarse_triangles: &[],
        });
        for f in &run.frames {
            // Frames kept in memory carry neither skin offsets nor the body (that sink does not
            // ask for them).
            let mut with = f.clone();
            let offsets = out.wants_skin_offsets() && f.skin_offsets.is_empty();
            if let Some(pose) = f.pose.as_ref().filter(|_| offsets) {
                self.body.skin_offsets_at(pose, &mut with.skin_offsets);
            }
            if out.wants_body() && f.body.is_empty() {
                with.body = self.body_at(f.pose.as_ref());
            }
            out.frame(&with);
        }
        for f in &run.stats.per_frame {
            out.frame_stats(f);
        }
        out.finish(self, &run.stats)
    }
}
