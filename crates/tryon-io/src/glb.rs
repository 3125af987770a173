//! glTF 2.0 binary (GLB) export of an animated try-on, written as the run goes. The body is a
//! skinned mesh (a node per joint, inverse bind matrices, 4 weights per vertex) animated by joint
//! rotations and the root's translation, or a static mesh. The garment is a mesh whose frames are
//! morph targets (position and normal offsets from frame 0), played by a `weights` animation that
//! moves linearly from one target to the next, so the file opens as shape-key animation in Blender
//! and plays in three.js.
//!
//! [`GlbWriter`] takes one frame at a time: the garment's offsets go straight to a spool file beside
//! the output, and only small per-frame figures (time, pose, bounds) stay in memory, so a long run
//! does not hold its frames. [`GlbWriter::finish`] lays out the glTF JSON (serde_json) and writes
//! the GLB container (header, JSON chunk, BIN chunk) atomically, copying the spool in.

use crate::atomic::write_atomic_with;
use crate::glb_layout::{Doc, Layout, flat, normals};
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::math::{Real, UnitQuat, Vec3};

/// A skinned body: rest mesh, skeleton and weights.
#[derive(Clone, Copy, Debug)]
pub struct SkinnedExport<'a> {
    pub positions: &'a [Vec3],
    pub triangles: &'a [[u32; 3]],
    pub joint_names: &'a [String],
    pub parents: &'a [Option<usize>],
    /// Global joint positions in the rest pose (rest orientations are the identity).
    pub joint_rest: &'a [Vec3],
    pub joints: &'a [[u16; 4]],
    pub weights: &'a [[Real; 4]],
}

/// The body in the file.
#[derive(Clone, Copy, Debug)]
pub enum BodyExport<'a> {
    Static {
        positions: &'a [Vec3],
        triangles: &'a [[u32; 3]],
    },
    Skinned(SkinnedExport<'a>),
}

/// What stays the same over the run.
#[derive(Clone, Copy, Debug)]
pub struct GlbHeader<'a> {
    pub name: &'a str,
    pub body: BodyExport<'a>,
    pub garment_triangles: &'a [[u32; 3]],
    /// The garments worn, by name, and which of them each garment triangle belongs to: each is
    /// its own primitive with its own material. Empty for one garment named "garment".
    pub garment_names: &'a [String],
    pub triangle_garment: &'a [u16],
}

/// A skinned body's pose in one frame: the root's translation from rest and every joint's local
/// rotation (missing joints hold their rest orientation).
#[derive(Clone, Copy, Debug)]
pub struct FramePose<'a> {
    pub root_translation: Vec3,
    pub rotations: &'a [UnitQuat],
    /// Offsets of rest-mesh vertices (index, offset) the body adds before skinning in this frame
    /// (what the body press moved, carried to the rest pose): written as a sparse morph target
    /// of the body, one per frame. Empty for none.
    pub skin_offsets: &'a [(u32, Vec3)],
}

/// Why a GLB could not be written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum GlbError {
    #[error("cannot export: {0}")]
    Invalid(String),
    #[error("cannot pack the GLB: {0}")]
    Pack(String),
    #[error("{}: cannot write: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// The body, owned (the writer outlives the borrow of whoever described it).
#[derive(Clone, Debug)]
pub(crate) struct OwnedBody {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub rig: Option<OwnedRig>,
}

#[derive(Clone, Debug)]
pub(crate) struct OwnedRig {
    pub joint_names: Vec<String>,
    pub parents: Vec<Option<usize>>,
    pub joint_rest: Vec<Vec3>,
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[Real; 4]>,
}

/// Where the garment's per-frame offsets wait until the file is laid out.
#[derive(Debug)]
enum Spool {
    Memory(Vec<u8>),
    File { out: BufWriter<File>, path: PathBuf },
}

/// Writes an animated try-on frame by frame; see the module docs.
#[derive(Debug)]
pub struct GlbWriter {
    path: Option<PathBuf>,
    name: String,
    pub(crate) body: OwnedBody,
    pub(crate) garment_triangles: Vec<[u32; 3]>,
    /// Each garment's name and triangles (at least one).
    pub(crate) parts: Vec<GarmentPart>,
    spool: Spool,
    spooled: u64,
    pub(crate) times: Vec<Real>,
    /// Per frame and joint, the unit rotation in f32 (skinned bodies).
    pub(crate) rotations: Vec<[f32; 4]>,
    pub(crate) root_translations: Vec<Vec3>,
    /// Per frame, the body's sparse morph (vertex, offset), by increasing vertex (skinned bodies).
    pub(crate) body_targets: Vec<Vec<(u32, [f32; 3])>>,
    /// Frame 0's garment and its normals.
    pub(crate) base: Vec<Vec3>,
    pub(crate) base_normals: Vec<Vec3>,
    /// Per later frame: where its position and normal offsets are in the spool, and the position
    /// offsets' bounds.
    pub(crate) targets: Vec<(u64, [f32; 3], [f32; 3])>,
    error: Option<GlbError>,
}

impl GlbWriter {
    /// A writer of the GLB at `path`; the garment's frames are spooled beside it.
    pub fn create(path: &Path, header: &GlbHeader) -> Result<Self, GlbError> {
        let spool_path = spool_path(path);
        let file = File::create(&spool_path).map_err(|source| GlbError::Io {
            path: spool_path.clone(),
            source,
        })?;
        let spool = Spool::File {
            out: BufWriter::new(file),
            path: spool_path,
        };
        Self::with_spool(Some(path.to_path_buf()), header, spool)
    }

    /// A writer that keeps everything in memory ([`GlbWriter::finish_to_vec`]); for tests and
    /// short clips.
    pub fn in_memory(header: &GlbHeader) -> Result<Self, GlbError> {
        Self::with_spool(None, header, Spool::Memory(Vec::new()))
    }

    fn with_spool(path: Option<PathBuf>, h: &GlbHeader, spool: Spool) -> Result<Self, GlbError> {
        let (positions, triangles, rig) = match h.body {
            BodyExport::Static {
                positions,
                triangles,
            } => (positions, triangles, None),
            BodyExport::Skinned(s) => {
                if s.joints.len() != s.positions.len() || s.weights.len() != s.positions.len() {
                    return Err(GlbError::Invalid(
                        "skin weights do not cover the body".into(),
                    ));
                }
                let n = s.joint_names.len();
                if s.parents.len() != n || s.joint_rest.len() != n {
                    return Err(GlbError::Invalid(format!(
                        "{n} joint names for {} parents and {} rest positions",
                        s.parents.len(),
                        s.joint_rest.len()
                    )));
                }
                let rig = OwnedRig {
                    joint_names: s.joint_names.to_vec(),
                    parents: s.parents.to_vec(),
                    joint_rest: s.joint_rest.to_vec(),
                    joints: s.joints.to_vec(),
                    weights: s.weights.to_vec(),
                };
                (s.positions, s.triangles, Some(rig))
            }
        };
        let parts = garment_parts(h)?;
        Ok(GlbWriter {
            parts,
            path,
            name: h.name.to_string(),
            body: OwnedBody {
                positions: positions.to_vec(),
                triangles: triangles.to_vec(),
                rig,
            },
            garment_triangles: h.garment_triangles.to_vec(),
            spool,
            spooled: 0,
            times: Vec::new(),
            rotations: Vec::new(),
            root_translations: Vec::new(),
            body_targets: Vec::new(),
            base: Vec::new(),
            base_normals: Vec::new(),
            targets: Vec::new(),
            error: None,
        })
    }

    /// Adds a frame. A skinned body needs its `pose`. The first problem (times not increasing, a
    /// changed vertex count, a non-finite position, a failed write) is kept and returned by
    /// `finish`; later frames are then ignored.
    pub fn frame(&mut self, time: Real, garment: &[Vec3], pose: Option<FramePose>) {
        if self.error.is_none()
            && let Err(e) = self.try_frame(time, garment, pose)
        {
            self.error = Some(e);
        }
    }

    fn try_frame(
        &mut self,
        time: Real,
        garment: &[Vec3],
        pose: Option<FramePose>,
    ) -> Result<(), GlbError> {
        let bad = |m: String| Err(GlbError::Invalid(m));
        if self.times.last().is_some_and(|&t| !(time > t)) {
            return bad("frame times must increase".into());
        }
        if !self.times.is_empty() && garment.len() != self.base.len() {
            return bad("garment frames differ in vertex count".into());
        }
        if garment.iter().any(|p| !p.iter().all(|c| c.is_finite())) {
            return bad("a garment position is not finite".into());
        }
        if let Some(rig) = &self.body.rig {
            let Some(pose) = pose else {
                return bad("a frame of a skinned body has no pose".into());
            };
            self.rotations.extend((0..rig.joint_names.len()).map(|j| {
                let c = pose
                    .rotations
                    .get(j)
                    .copied()
                    .unwrap_or_else(UnitQuat::identity)
                    .into_inner()
                    .coords;
                let f = [c.x as f32, c.y as f32, c.z as f32, c.w as f32];
                let l = f.iter().map(|x| x * x).sum::<f32>().sqrt();
                f.map(|x| x / l)
            }));
            self.root_translations.push(pose.root_translation);
            let n = self.body.positions.len();
            let mut morph: Vec<(u32, [f32; 3])> = Vec::with_capacity(pose.skin_offsets.len());
            for &(v, d) in pose.skin_offsets {
                if v as usize >= n || !d.iter().all(|c| c.is_finite()) {
                    return bad(format!(
                        "a body offset of vertex {v} is past the last vertex or not finite"
                    ));
                }
                morph.push((v, [d.x as f32, d.y as f32, d.z as f32]));
            }
            morph.sort_by_key(|e| e.0);
            morph.dedup_by_key(|e| e.0);
            self.body_targets.push(morph);
        }
        if self.times.is_empty() {
            if self
                .garment_triangles
                .iter()
                .flatten()
                .any(|&v| v as usize >= garment.len())
            {
                return bad("a garment triangle refers past the last vertex".into());
            }
            self.base = garment.to_vec();
            self.base_normals = normals(garment, &self.garment_triangles);
        } else {
            self.spool_target(garment)?;
        }
        self.times.push(time);
        Ok(())
    }

    /// Writes a later frame's position and normal offsets from frame 0 to the spool.
    fn spool_target(&mut self, garment: &[Vec3]) -> Result<(), GlbError> {
        let dp: Vec<Vec3> = garment.iter().zip(&self.base).map(|(a, b)| a - b).collect();
        let nf = normals(garment, &self.garment_triangles);
        let dn: Vec<Vec3> = nf
            .iter()
            .zip(&self.base_normals)
            .map(|(a, b)| a - b)
            .collect();
        let (p, n) = (flat(&dp), flat(&dn));
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for c in p.chunks(3) {
            for k in 0..3 {
                lo[k] = lo[k].min(c[k]);
                hi[k] = hi[k].max(c[k]);
            }
        }
        self.targets.push((self.spooled, lo, hi));
        let bytes: Vec<u8> = p.iter().chain(&n).flat_map(|x| x.to_le_bytes()).collect();
        self.spooled += bytes.len() as u64;
        match &mut self.spool {
            Spool::Memory(v) => v.extend_from_slice(&bytes),
            Spool::File { out, path } => out.write_all(&bytes).map_err(|source| GlbError::Io {
                path: path.clone(),
                source,
            })?,
        }
        Ok(())
    }

    /// Number of frames taken so far.
    pub fn frames(&self) -> usize {
        self.times.len()
    }

    /// Lays the file out and writes it atomically to the path given at creation; the spool is
    /// removed either way.
    pub fn finish(mut self) -> Result<(), GlbError> {
        let result = self.finish_inner();
        if let Spool::File { path, .. } = &self.spool {
            let _ = std::fs::remove_file(path);
        }
        result
    }

    fn finish_inner(&mut self) -> Result<(), GlbError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let layout = self.layout()?;
        let path = self
            .path
            .clone()
            .ok_or_else(|| GlbError::Invalid("an in-memory GLB has no path".into()))?;
        let mut spool = match &mut self.spool {
            Spool::File { out, path: sp } => {
                let io = |source| GlbError::Io {
                    path: sp.clone(),
                    source,
                };
                out.flush().map_err(io)?;
                let mut f = File::open(&*sp).map_err(io)?;
                f.seek(SeekFrom::Start(0)).map_err(io)?;
                Some(f)
            }
            Spool::Memory(_) => None,
        };
        write_atomic_with(&path, |w| {
            layout.write(w, &mut |w, start, len| match &mut spool {
                Some(f) => {
                    f.seek(SeekFrom::Start(start))?;
                    std::io::copy(&mut Read::by_ref(f).take(len), w).map(|_| ())
                }
                None => Ok(()),
            })
        })
        .map_err(|source| GlbError::Io { path, source })
    }

    /// The whole file in memory (an in-memory writer; a file writer's spool is read back).
    pub fn finish_to_vec(mut self) -> Result<Vec<u8>, GlbError> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        let layout = self.layout()?;
        let mut out = Vec::new();
        let spool = match &mut self.spool {
            Spool::Memory(v) => std::mem::take(v),
            Spool::File { out, path } => {
                let mut v = Vec::new();
                let io = |source| GlbError::Io {
                    path: path.clone(),
                    source,
                };
                out.flush().map_err(io)?;
                File::open(&*path)
                    .and_then(|mut f| f.read_to_end(&mut v))
                    .map_err(io)?;
                v
            }
        };
        layout
            .write(&mut out, &mut |w, start, len| {
                w.write_all(&spool[start as usize..(start + len) as usize])
            })
            .map_err(|e| GlbError::Pack(e.to_string()))?;
        if let Spool::File { path, .. } = &self.spool {
            let _ = std::fs::remove_file(path);
        }
        Ok(out)
    }

    /// The JSON and the BIN chunk's pieces.
    fn layout(&self) -> Result<Layout, GlbError> {
        if self.times.is_empty() {
            return Err(GlbError::Invalid("no frame to write".into()));
        }
        let mut d = Doc::default();
        let json = crate::glb_layout::document(self, &self.name, &mut d);
        let json = serde_json::to_vec(&json).map_err(|e| GlbError::Pack(e.to_string()))?;
        let layout = Layout {
            json,
            pieces: d.pieces,
            bin_len: d.len,
        };
        if layout.total_len() > u32::MAX as u64 {
            return Err(GlbError::Invalid(format!(
                "the file would be {} bytes, past GLB's 4 GiB limit: export fewer frames \
                 (--frames) or a coarser surface (effects.refine)",
                layout.total_len()
            )));
        }
        Ok(layout)
    }
}

/// A garment's name and triangles.
pub(crate) type GarmentPart = (String, Vec<[u32; 3]>);

/// The header's garments with their triangles, in order; one named "garment" for none.
fn garment_parts(h: &GlbHeader) -> Result<Vec<GarmentPart>, GlbError> {
    if h.garment_names.is_empty() {
        return Ok(vec![("garment".into(), h.garment_triangles.to_vec())]);
    }
    if h.triangle_garment.len() != h.garment_triangles.len() {
        return Err(GlbError::Invalid(format!(
            "{} garment triangles but {} garment ids",
            h.garment_triangles.len(),
            h.triangle_garment.len()
        )));
    }
    let mut parts: Vec<GarmentPart> = h
        .garment_names
        .iter()
        .map(|n| (n.clone(), Vec::new()))
        .collect();
    for (t, &g) in h.garment_triangles.iter().zip(h.triangle_garment) {
        let Some(part) = parts.get_mut(g as usize) else {
            return Err(GlbError::Invalid(format!(
                "a triangle of garment {g}, but {} garments are named",
                h.garment_names.len()
            )));
        };
        part.1.push(*t);
    }
    Ok(parts)
}

/// Where a GLB's frames are spooled while it is written.
fn spool_path(path: &Path) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("out");
    path.with_file_name(format!(".{name}.{}.frames", std::process::id()))
}

mod resume;
#[cfg(test)]
mod tests;

pub use resume::GlbState;
