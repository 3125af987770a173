//! Point caches other animation tools read: PC2 (Blender's Mesh Cache modifier, 3ds Max and
//! Maya's point-cache importers) streamed frame by frame, and one OBJ per frame (an OBJ sequence,
//! which Blender, Houdini and most tools import as a frame range).
//!
//! PC2 is `POINTCACHE2\0`, then little-endian i32 version (1), i32 point count, f32 start frame,
//! f32 sample rate (frames between samples), i32 sample count, then per sample each point's x, y,
//! z as f32. [`Pc2Writer`] spools the samples into a hidden file beside the cache and, at
//! [`Pc2Writer::finish`], writes the count into the header and renames it over the cache, so the
//! cache appears whole or not at all.

use crate::atomic::write_atomic_with;
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::math::Vec3;

const SIGNATURE: &[u8; 12] = b"POINTCACHE2\0";
/// Bytes before the first sample.
const HEADER: u64 = 32;

/// Why a cache could not be written or read.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum CacheError {
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: {what}", path.display())]
    Invalid { path: PathBuf, what: String },
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> CacheError + '_ {
    move |source| CacheError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes a PC2 cache of a fixed number of points, a frame at a time.
#[derive(Debug)]
pub struct Pc2Writer {
    path: PathBuf,
    part: PathBuf,
    out: BufWriter<File>,
    points: usize,
    samples: u32,
}

/// What a [`Pc2Writer`] had written at a checkpoint.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pc2State {
    pub points: usize,
    pub samples: u32,
}

impl Pc2Writer {
    /// A cache of `points` points at `path`, sampled every frame from frame 0 at `fps`.
    pub fn create(path: &Path, points: usize) -> Result<Self, CacheError> {
        let part = part_path(path);
        let mut out = BufWriter::new(File::create(&part).map_err(io(&part))?);
        let mut head = Vec::with_capacity(HEADER as usize);
        head.extend_from_slice(SIGNATURE);
        head.extend_from_slice(&1i32.to_le_bytes());
        head.extend_from_slice(&(points as i32).to_le_bytes());
        head.extend_from_slice(&0f32.to_le_bytes());
        head.extend_from_slice(&1f32.to_le_bytes());
        head.extend_from_slice(&0i32.to_le_bytes());
        out.write_all(&head).map_err(io(&part))?;
        Ok(Pc2Writer {
            path: path.to_path_buf(),
            part,
            out,
            points,
            samples: 0,
        })
    }

    /// Appends one frame; it must have the cache's point count.
    pub fn frame(&mut self, positions: &[Vec3]) -> Result<(), CacheError> {
        if positions.len() != self.points {
            return Err(CacheError::Invalid {
                path: self.path.clone(),
                what: format!(
                    "a frame of {} points in a cache of {}",
                    positions.len(),
                    self.points
                ),
            });
        }
        let bytes: Vec<u8> = (positions.iter())
            .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
            .flat_map(f32::to_le_bytes)
            .collect();
        self.out.write_all(&bytes).map_err(io(&self.part))?;
        self.samples += 1;
        Ok(())
    }

    /// Flushes what is written and says how far it got.
    pub fn checkpoint(&mut self) -> Result<Pc2State, CacheError> {
        self.out.flush().map_err(io(&self.part))?;
        Ok(Pc2State {
            points: self.points,
            samples: self.samples,
        })
    }

    /// A writer of the cache at `path` going on from `state` (its hidden part file cut back to
    /// the samples the state counts).
    pub fn resume(path: &Path, state: &Pc2State) -> Result<Self, CacheError> {
        let part = part_path(path);
        let len = HEADER + state.samples as u64 * state.points as u64 * 12;
        let out = reopen_part(&part, len)?;
        Ok(Pc2Writer {
            path: path.to_path_buf(),
            part,
            out,
            points: state.points,
            samples: state.samples,
        })
    }

    /// Writes the sample count into the header and moves the cache into place.
    pub fn finish(self) -> Result<(), CacheError> {
        let Pc2Writer {
            path,
            part,
            out,
            samples,
            ..
        } = self;
        let mut f = out.into_inner().map_err(|e| io(&part)(e.into_error()))?;
        f.seek(SeekFrom::Start(28)).map_err(io(&part))?;
        f.write_all(&(samples as i32).to_le_bytes())
            .map_err(io(&part))?;
        f.sync_all().map_err(io(&part))?;
        std::fs::rename(&part, &path).map_err(io(&path))
    }
}

/// A part file written up to a checkpoint, reopened to go on writing after its first `len`
/// bytes (what came after the checkpoint is cut off); refused when it is shorter than that.
pub(crate) fn reopen_part(part: &Path, len: u64) -> Result<BufWriter<File>, CacheError> {
    let mut f = OpenOptions::new()
        .write(true)
        .open(part)
        .map_err(io(part))?;
    if f.metadata().map_err(io(part))?.len() < len {
        return Err(CacheError::Invalid {
            path: part.to_path_buf(),
            what: "shorter than at the checkpoint".into(),
        });
    }
    f.set_len(len).map_err(io(part))?;
    f.seek(SeekFrom::End(0)).map_err(io(part))?;
    Ok(BufWriter::new(f))
}

fn part_path(path: &Path) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("cache");
    path.with_file_name(format!(".{name}.part"))
}

/// A PC2 cache's frames.
pub fn read_pc2(path: &Path) -> Result<Vec<Vec<[f32; 3]>>, CacheError> {
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(io(path))?;
    let bad = |what: &str| CacheError::Invalid {
        path: path.to_path_buf(),
        what: what.into(),
    };
    if bytes.len() < HEADER as usize || &bytes[..12] != SIGNATURE {
        return Err(bad("not a PC2 point cache"));
    }
    let int =
        |at: usize| i32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let (points, samples) = (int(16), int(28));
    let (Ok(points), Ok(samples)) = (usize::try_from(points), usize::try_from(samples)) else {
        return Err(bad("a negative point or sample count"));
    };
    let body = &bytes[HEADER as usize..];
    if points.checked_mul(samples).and_then(|n| n.checked_mul(12)) != Some(body.len()) {
        return Err(bad("its length does not match its point and sample counts"));
    }
    let floats: Vec<f32> = (body.chunks_exact(4))
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    Ok((floats.chunks_exact(3 * points.max(1)))
        .map(|s| s.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
        .collect())
}

/// Writes one frame of a garment as an OBJ (atomically): its vertices, and its triangles in one
/// group (`g`) per garment (`names`, and each triangle's garment in `garment_of`).
pub fn write_obj_frame(
    path: &Path,
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    (names, garment_of): (&[String], &[u16]),
) -> Result<(), CacheError> {
    write_atomic_with(path, |w| {
        writeln!(w, "# tryon garment frame")?;
        for p in positions {
            writeln!(w, "v {} {} {}", p.x as f32, p.y as f32, p.z as f32)?;
        }
        let groups = names.len().max(1);
        for g in 0..groups {
            if let Some(name) = names.get(g) {
                writeln!(w, "g {name}")?;
            }
            for (k, t) in triangles.iter().enumerate() {
                if garment_of.get(k).copied().unwrap_or(0) as usize == g {
                    writeln!(w, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1)?;
                }
            }
        }
        Ok(())
    })
    .map_err(io(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("tryon-cache-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_pc2_cache_reads_back_and_matches_the_format() {
        let dir = scratch("pc2");
        let path = dir.join("g.pc2");
        let frames: Vec<Vec<Vec3>> = (0..3)
            .map(|k| {
                (0..4)
                    .map(|i| Vec3::new(i as f64, k as f64 * 0.5, -0.25))
                    .collect()
            })
            .collect();
        let mut w = Pc2Writer::create(&path, 4).unwrap();
        for f in &frames {
            w.frame(f).unwrap();
        }
        assert!(w.frame(&frames[0][..2]).is_err());
        assert!(!path.exists(), "the cache appears only when finished");
        w.finish().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        // The header as the format's readers expect it (Blender's io_mesh_pc2 unpacks
        // '<12siiffi'): 3 samples of 4 points.
        assert_eq!(&bytes[..12], b"POINTCACHE2\0");
        assert_eq!(bytes[12..16], 1i32.to_le_bytes());
        assert_eq!(bytes[16..20], 4i32.to_le_bytes());
        assert_eq!(bytes[28..32], 3i32.to_le_bytes());
        assert_eq!(bytes.len(), 32 + 3 * 4 * 12);
        let back = read_pc2(&path).unwrap();
        assert_eq!(back.len(), 3);
        assert_eq!(back[2][3], [3.0, 1.0, -0.25]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_pc2_cache_resumes_from_its_checkpoint_to_the_same_bytes() {
        let dir = scratch("pc2-resume");
        let frame = |k: usize| vec![Vec3::new(k as f64, 0.0, 1.0); 5];
        let (a, b) = (dir.join("a.pc2"), dir.join("b.pc2"));
        let mut w = Pc2Writer::create(&a, 5).unwrap();
        (0..6).for_each(|k| w.frame(&frame(k)).unwrap());
        w.finish().unwrap();
        let mut w = Pc2Writer::create(&b, 5).unwrap();
        (0..3).for_each(|k| w.frame(&frame(k)).unwrap());
        let state = w.checkpoint().unwrap();
        // Killed after two more frames had been written.
        (3..5).for_each(|k| w.frame(&frame(k)).unwrap());
        w.checkpoint().unwrap();
        drop(w);
        let mut w = Pc2Writer::resume(&b, &state).unwrap();
        (3..6).for_each(|k| w.frame(&frame(k)).unwrap());
        w.finish().unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn an_obj_frame_reads_back_with_its_groups() {
        let dir = scratch("obj");
        let path = dir.join("f.obj");
        let p = [Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()];
        let names = ["skirt".to_string(), "top".to_string()];
        write_obj_frame(&path, &p, &[[0, 1, 2], [0, 2, 3]], (&names, &[0, 1])).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("g skirt\nf 1 2 3\ng top\nf 1 3 4\n"),
            "{text}"
        );
        let back = crate::read_obj(&path).unwrap();
        assert_eq!(back.positions.len(), 4);
        assert_eq!(back.faces.len(), 2);
        assert_eq!(
            (back.group_faces("skirt"), back.group_faces("top")),
            (vec![0], vec![1])
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
