//! view.bin: a run's frames as `tryon view` plays them: the body, the coarse cloth and the output
//! garment every frame, in one file the page reads whole (little-endian): `TRYONVW1`, a u32
//! header length, the header as JSON (padded with spaces to a multiple of 4 bytes), then every
//! frame at one size: its time (f32), then the body's, the coarse cloth's and the garment's
//! positions (f32 x, y, z, in the counts the header gives), then, when the header's `depth` is
//! set (version 2), one byte per garment vertex, its depth in the body in quarter millimetres
//! ([`crate::depth_code`]), padded with zeros to a multiple of 4 bytes.
//!
//! Frames stream into a hidden part file and the file is renamed into place at the end, so it is
//! whole or absent; a checkpoint keeps the frames written and a resumed writer cuts back to them.

use crate::cache::CacheError;
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::{Path, PathBuf};
use tryon_core::math::Vec3;

const MAGIC: &[u8; 8] = b"TRYONVW1";

/// A mesh of the view: its vertex count and triangles.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewMesh {
    pub vertices: usize,
    pub triangles: Vec<[u32; 3]>,
}

/// The garment of the view, with the garment each triangle belongs to and their colours.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewGarment {
    pub vertices: usize,
    pub triangles: Vec<[u32; 3]>,
    pub triangle_garment: Vec<u16>,
    pub names: Vec<String>,
    pub colours: Vec<[u8; 3]>,
}

/// What stays the same over a run's view.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ViewHeader {
    pub version: u32,
    pub name: String,
    pub fps: f64,
    pub body: ViewMesh,
    /// The coarse cloth under a refined garment (no vertices when the garment is the coarse cloth).
    pub coarse: ViewMesh,
    pub garment: ViewGarment,
    /// Whether each frame ends with the garment vertices' depths in the body.
    #[serde(default)]
    pub depth: bool,
}

impl ViewHeader {
    fn frame_floats(&self) -> usize {
        1 + 3 * (self.body.vertices + self.coarse.vertices + self.garment.vertices)
    }

    /// Bytes of the depths at the end of each frame (0 without them).
    fn depth_bytes(&self) -> usize {
        match self.depth {
            true => self.garment.vertices.next_multiple_of(4),
            false => 0,
        }
    }

    fn frame_bytes(&self) -> usize {
        4 * self.frame_floats() + self.depth_bytes()
    }

    /// The header's bytes as the file holds them (length, JSON, padding).
    fn bytes(&self) -> Vec<u8> {
        let mut json = serde_json::to_vec(self).unwrap_or_default();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut out = MAGIC.to_vec();
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(&json);
        out
    }
}

/// Writes view.bin a frame at a time.
#[derive(Debug)]
pub struct ViewWriter {
    path: PathBuf,
    part: PathBuf,
    out: BufWriter<File>,
    header: ViewHeader,
    frames: u64,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> CacheError + '_ {
    move |source| CacheError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl ViewWriter {
    /// A view of `header`'s meshes at `path`.
    pub fn create(path: &Path, header: ViewHeader) -> Result<Self, CacheError> {
        let part = part_path(path);
        let mut out = BufWriter::new(File::create(&part).map_err(io(&part))?);
        out.write_all(&header.bytes()).map_err(io(&part))?;
        Ok(ViewWriter {
            path: path.to_path_buf(),
            part,
            out,
            header,
            frames: 0,
        })
    }

    /// Appends a frame: its time, the body's, coarse cloth's and garment's positions, and (when
    /// the header says so) the garment's depths (none given: all 0).
    pub fn frame(
        &mut self,
        time: f64,
        (body, coarse, garment): (&[Vec3], &[Vec3], &[Vec3]),
        depth: &[u8],
    ) -> Result<(), CacheError> {
        let h = &self.header;
        if body.len() != h.body.vertices
            || coarse.len() != h.coarse.vertices
            || garment.len() != h.garment.vertices
            || !(depth.is_empty() || (h.depth && depth.len() == garment.len()))
        {
            return Err(CacheError::Invalid {
                path: self.path.clone(),
                what: "a frame whose vertex counts are not the view's".into(),
            });
        }
        let mut bytes = Vec::with_capacity(h.frame_bytes());
        bytes.extend_from_slice(&(time as f32).to_le_bytes());
        for p in body.iter().chain(coarse).chain(garment) {
            for v in [p.x, p.y, p.z] {
                bytes.extend_from_slice(&(v as f32).to_le_bytes());
            }
        }
        bytes.extend_from_slice(depth);
        bytes.resize(h.frame_bytes(), 0);
        self.out.write_all(&bytes).map_err(io(&self.part))?;
        self.frames += 1;
        Ok(())
    }

    /// Flushes what is written and says how many frames it holds.
    pub fn checkpoint(&mut self) -> Result<u64, CacheError> {
        self.out.flush().map_err(io(&self.part))?;
        Ok(self.frames)
    }

    /// A writer of the view at `path` (made with `header`) going on after `frames` frames.
    pub fn resume(path: &Path, header: ViewHeader, frames: u64) -> Result<Self, CacheError> {
        let part = part_path(path);
        let len = header.bytes().len() as u64 + frames * header.frame_bytes() as u64;
        let out = crate::cache::reopen_part(&part, len)?;
        Ok(ViewWriter {
            path: path.to_path_buf(),
            part,
            out,
            header,
            frames,
        })
    }

    /// Moves the view into place.
    pub fn finish(self) -> Result<(), CacheError> {
        let f = (self.out.into_inner()).map_err(|e| io(&self.part)(e.into_error()))?;
        f.sync_all().map_err(io(&self.part))?;
        std::fs::rename(&self.part, &self.path).map_err(io(&self.path))
    }
}

fn part_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .and_then(|n| n.to_str())
        .unwrap_or("view.bin");
    path.with_file_name(format!(".{name}.part"))
}

/// A view file's header and frame count, checked against its length (what `tryon view` serves).
pub fn read_view_header(path: &Path) -> Result<(ViewHeader, u64), CacheError> {
    let bad = |what: String| CacheError::Invalid {
        path: path.to_path_buf(),
        what,
    };
    let mut f = File::open(path).map_err(io(path))?;
    let total = f.metadata().map_err(io(path))?.len();
    let mut head = [0u8; 12];
    f.read_exact(&mut head)
        .map_err(|_| bad("not a tryon view file".into()))?;
    if &head[..8] != MAGIC {
        return Err(bad("not a tryon view file".into()));
    }
    let n = u32::from_le_bytes([head[8], head[9], head[10], head[11]]) as u64;
    if n > total.saturating_sub(12) || n > 1 << 30 {
        return Err(bad(format!("a header of {n} bytes in a file of {total}")));
    }
    let mut json = vec![0u8; n as usize];
    f.read_exact(&mut json).map_err(io(path))?;
    let header: ViewHeader =
        serde_json::from_slice(&json).map_err(|e| bad(format!("its header: {e}")))?;
    let body = total - 12 - n;
    // A frame's bytes, from counts a damaged or hostile header may make huge: checked, and at
    // most the file's length.
    let counts = [
        header.body.vertices,
        header.coarse.vertices,
        header.garment.vertices,
    ];
    let depth = match header.depth {
        true => (header.garment.vertices as u64).checked_next_multiple_of(4),
        false => Some(0),
    };
    let frame = (counts.iter())
        .try_fold(1u64, |a, &c| a.checked_add((c as u64).checked_mul(3)?))
        .and_then(|floats| floats.checked_mul(4)?.checked_add(depth?))
        .filter(|&f| f <= body.max(4))
        .ok_or_else(|| {
            bad(format!(
                "vertex counts {counts:?}: a frame would not fit in the file"
            ))
        })?;
    if !body.is_multiple_of(frame) {
        return Err(bad(format!(
            "{body} bytes of frames are not whole frames of {frame}"
        )));
    }
    Ok((header, body / frame))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header() -> ViewHeader {
        ViewHeader {
            version: 1,
            name: "t".into(),
            fps: 30.0,
            body: ViewMesh {
                vertices: 3,
                triangles: vec![[0, 1, 2]],
            },
            coarse: ViewMesh::default(),
            garment: ViewGarment {
                vertices: 2,
                triangles: vec![],
                triangle_garment: vec![],
                names: vec!["dress".into()],
                colours: vec![[1, 2, 3]],
            },
            depth: false,
        }
    }

    #[test]
    fn a_view_reads_back_and_resumes_to_the_same_bytes() {
        let dir = std::env::temp_dir().join(format!("tryon-view-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.bin"), dir.join("b.bin"));
        let body = |k: usize| vec![Vec3::new(k as f64, 1.0, 2.0); 3];
        let garment = |k: usize| vec![Vec3::new(0.5, k as f64, -1.0); 2];
        let write = |w: &mut ViewWriter, k: usize| {
            w.frame(k as f64 / 30.0, (&body(k), &[], &garment(k)), &[])
                .unwrap()
        };
        let mut w = ViewWriter::create(&a, header()).unwrap();
        (0..5).for_each(|k| write(&mut w, k));
        assert!(w.frame(0.0, (&body(0), &[], &body(0)), &[]).is_err());
        assert!(
            w.frame(0.0, (&body(0), &[], &garment(0)), &[1, 2]).is_err(),
            "no depths in this view"
        );
        w.finish().unwrap();
        let mut w = ViewWriter::create(&b, header()).unwrap();
        (0..2).for_each(|k| write(&mut w, k));
        let at = w.checkpoint().unwrap();
        (2..4).for_each(|k| write(&mut w, k));
        w.checkpoint().unwrap();
        drop(w);
        let mut w = ViewWriter::resume(&b, header(), at).unwrap();
        (2..5).for_each(|k| write(&mut w, k));
        w.finish().unwrap();
        let bytes = std::fs::read(&a).unwrap();
        assert_eq!(bytes, std::fs::read(&b).unwrap());
        let (h, frames) = read_view_header(&a).unwrap();
        assert_eq!((h, frames), (header(), 5));
        // Frame 3's garment vertex 1, as the page finds it.
        let start = 12 + u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
        let at = start + 3 * 4 * (1 + 3 * 5) + 4 * (1 + 3 * 3 + 3);
        let y = f32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap());
        assert_eq!(y, 3.0);
        std::fs::write(&b, &bytes[..bytes.len() - 4]).unwrap();
        assert!(read_view_header(&b).is_err(), "a cut frame");
        std::fs::write(&b, b"TRYONVW1\xff\xff\xff\xff{}").unwrap();
        assert!(
            read_view_header(&b).is_err(),
            "a header longer than the file"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn depths_follow_each_frames_positions_padded_to_four_bytes() {
        let dir = std::env::temp_dir().join(format!("tryon-view-depth-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("v.bin");
        let h = ViewHeader {
            version: 2,
            depth: true,
            ..header()
        };
        let mut w = ViewWriter::create(&path, h.clone()).unwrap();
        let body = vec![Vec3::zeros(); 3];
        let garment = vec![Vec3::new(1.0, 2.0, 3.0); 2];
        w.frame(0.0, (&body, &[], &garment), &[9, 255]).unwrap();
        w.frame(0.1, (&body, &[], &garment), &[]).unwrap();
        assert!(
            w.frame(0.2, (&body, &[], &garment), &[1]).is_err(),
            "one depth for two vertices"
        );
        w.finish().unwrap();
        let (back, frames) = read_view_header(&path).unwrap();
        assert_eq!((back, frames), (h, 2));
        let bytes = std::fs::read(&path).unwrap();
        let start = 12 + u32::from_le_bytes(bytes[8..12].try_into().unwrap()) as usize;
        let floats = 4 * (1 + 3 * 5);
        assert_eq!(bytes.len(), start + 2 * (floats + 4));
        assert_eq!(&bytes[start + floats..start + floats + 4], &[9, 255, 0, 0]);
        assert_eq!(
            &bytes[start + 2 * floats + 4..],
            &[0, 0, 0, 0],
            "no depths given: 0"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
