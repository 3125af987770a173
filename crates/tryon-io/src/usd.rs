//! A USD stage of a run (`run.usda`, the text form of Pixar's Universal Scene Description, which
//! Houdini, Omniverse, Blender, Maya and usdview open): one `Mesh` prim per animated mesh under
//! `/Run`, its triangles once and its points as time samples, one a frame (time code = frame,
//! `timeCodesPerSecond` = the run's fps, metres, Y up). Garments worn together are one mesh with
//! a `GeomSubset` per garment.
//!
//! Each mesh's samples are spooled into a hidden part file as frames come; [`UsdWriter::finish`]
//! writes the stage (header, topology, the spooled samples) atomically and removes the parts, so
//! the stage appears whole or not at all. A checkpoint records the spools' lengths, and a resumed
//! writer cuts them back to it, so a killed and resumed run writes the same bytes.

use crate::atomic::write_atomic_with;
use crate::cache::CacheError;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use tryon_core::math::Vec3;

/// One mesh of the stage: its prim name, triangles, display colour and named face subsets.
#[derive(Clone, Debug)]
pub struct UsdMesh {
    pub name: String,
    pub triangles: Vec<[u32; 3]>,
    pub points: usize,
    pub colour: [u8; 3],
    /// Named sets of faces (indices into `triangles`), written as `GeomSubset`s; none when empty.
    pub subsets: Vec<(String, Vec<u32>)>,
}

/// Writes a USD stage a frame at a time.
#[derive(Debug)]
pub struct UsdWriter {
    path: PathBuf,
    fps: f64,
    meshes: Vec<UsdMesh>,
    spools: Vec<(PathBuf, BufWriter<File>, u64)>,
    samples: u32,
}

/// What a [`UsdWriter`] had written at a checkpoint: the samples and each spool's length.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct UsdState {
    pub samples: u32,
    pub spooled: Vec<u64>,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> CacheError + '_ {
    move |source| CacheError::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl UsdWriter {
    /// A stage of `meshes` at `path`, sampled every frame from time code 0 at `fps`.
    pub fn create(path: &Path, fps: f64, meshes: Vec<UsdMesh>) -> Result<Self, CacheError> {
        check_fps(path, fps)?;
        let mut spools = Vec::with_capacity(meshes.len());
        for k in 0..meshes.len() {
            let part = spool_path(path, k);
            let f = File::create(&part).map_err(io(&part))?;
            spools.push((part, BufWriter::new(f), 0));
        }
        Ok(Self::new(path, fps, meshes, spools, 0))
    }

    fn new(
        path: &Path,
        fps: f64,
        mut meshes: Vec<UsdMesh>,
        spools: Vec<(PathBuf, BufWriter<File>, u64)>,
        samples: u32,
    ) -> Self {
        for m in &mut meshes {
            m.name = prim_name(&m.name);
            for s in &mut m.subsets {
                s.0 = prim_name(&s.0);
            }
        }
        UsdWriter {
            path: path.to_path_buf(),
            fps,
            meshes,
            spools,
            samples,
        }
    }

    /// Appends one frame: each mesh's points, in the order of the meshes.
    pub fn frame(&mut self, points: &[&[Vec3]]) -> Result<(), CacheError> {
        if points.len() != self.meshes.len()
            || (points.iter().zip(&self.meshes)).any(|(p, m)| p.len() != m.points)
        {
            return Err(CacheError::Invalid {
                path: self.path.clone(),
                what: "a frame whose meshes or point counts are not the stage's".into(),
            });
        }
        for (p, (part, out, len)) in points.iter().zip(&mut self.spools) {
            let mut line = format!("            {}: [", self.samples);
            for (i, q) in p.iter().enumerate() {
                let sep = if i == 0 { "" } else { ", " };
                let (x, y, z) = (q.x as f32, q.y as f32, q.z as f32);
                let _ = std::fmt::Write::write_fmt(&mut line, format_args!("{sep}({x}, {y}, {z})"));
            }
            line += "],\n";
            out.write_all(line.as_bytes()).map_err(io(part))?;
            *len += line.len() as u64;
        }
        self.samples += 1;
        Ok(())
    }

    /// Flushes what is written and says how far it got.
    pub fn checkpoint(&mut self) -> Result<UsdState, CacheError> {
        let mut spooled = Vec::with_capacity(self.spools.len());
        for (part, out, len) in &mut self.spools {
            out.flush().map_err(io(part))?;
            spooled.push(*len);
        }
        Ok(UsdState {
            samples: self.samples,
            spooled,
        })
    }

    /// A writer of the stage at `path` (made with the same fps and meshes) going on from `state`,
    /// its spools cut back to the checkpoint's lengths.
    pub fn resume(
        path: &Path,
        fps: f64,
        meshes: Vec<UsdMesh>,
        state: &UsdState,
    ) -> Result<Self, CacheError> {
        check_fps(path, fps)?;
        if state.spooled.len() != meshes.len() {
            return Err(CacheError::Invalid {
                path: path.to_path_buf(),
                what: "the checkpoint's meshes are not the stage's".into(),
            });
        }
        let mut spools = Vec::with_capacity(meshes.len());
        for (k, &len) in state.spooled.iter().enumerate() {
            let part = spool_path(path, k);
            let out = crate::cache::reopen_part(&part, len)?;
            spools.push((part, out, len));
        }
        Ok(Self::new(path, fps, meshes, spools, state.samples))
    }

    /// Writes the stage atomically and removes the spools.
    pub fn finish(mut self) -> Result<(), CacheError> {
        let mut parts = Vec::with_capacity(self.spools.len());
        for (part, out, _) in self.spools.drain(..) {
            let f = out.into_inner().map_err(|e| io(&part)(e.into_error()))?;
            drop(f);
            parts.push(part);
        }
        let (meshes, samples, fps) = (&self.meshes, self.samples, self.fps);
        write_atomic_with(&self.path, |w| {
            write_header(w, samples, fps)?;
            for (m, part) in meshes.iter().zip(&parts) {
                write_mesh(w, m, part)?;
            }
            writeln!(w, "}}")
        })
        .map_err(io(&self.path))?;
        for part in &parts {
            let _ = std::fs::remove_file(part);
        }
        Ok(())
    }
}

fn check_fps(path: &Path, fps: f64) -> Result<(), CacheError> {
    if fps.is_finite() && fps > 0.0 {
        return Ok(());
    }
    Err(CacheError::Invalid {
        path: path.to_path_buf(),
        what: format!("{fps} frames a second: it must be positive"),
    })
}

fn write_header(w: &mut dyn Write, samples: u32, fps: f64) -> std::io::Result<()> {
    writeln!(w, "#usda 1.0")?;
    writeln!(w, "(")?;
    writeln!(
        w,
        "    doc = \"tryon: a simulated garment on a moving body\""
    )?;
    writeln!(w, "    defaultPrim = \"Run\"")?;
    writeln!(w, "    metersPerUnit = 1")?;
    writeln!(w, "    upAxis = \"Y\"")?;
    writeln!(w, "    startTimeCode = 0")?;
    writeln!(w, "    endTimeCode = {}", samples.saturating_sub(1))?;
    writeln!(w, "    timeCodesPerSecond = {fps}")?;
    writeln!(w, "    framesPerSecond = {fps}")?;
    writeln!(w, ")")?;
    writeln!(w)?;
    writeln!(w, "def Xform \"Run\"")?;
    writeln!(w, "{{")
}

/// One mesh prim: its topology, its spooled point samples, its colour and subsets.
fn write_mesh(w: &mut dyn Write, m: &UsdMesh, spool: &Path) -> std::io::Result<()> {
    writeln!(w, "    def Mesh \"{}\"", m.name)?;
    writeln!(w, "    {{")?;
    let counts = vec!["3"; m.triangles.len()].join(", ");
    writeln!(w, "        int[] faceVertexCounts = [{counts}]")?;
    let indices: Vec<String> = (m.triangles.iter().flatten()).map(u32::to_string).collect();
    writeln!(
        w,
        "        int[] faceVertexIndices = [{}]",
        indices.join(", ")
    )?;
    writeln!(w, "        uniform token orientation = \"rightHanded\"")?;
    writeln!(w, "        uniform token subdivisionScheme = \"none\"")?;
    writeln!(w, "        uniform bool doubleSided = 1")?;
    let c = m.colour.map(|v| v as f32 / 255.0);
    writeln!(
        w,
        "        color3f[] primvars:displayColor = [({}, {}, {})] (",
        c[0], c[1], c[2]
    )?;
    writeln!(w, "            interpolation = \"constant\"")?;
    writeln!(w, "        )")?;
    if !m.subsets.is_empty() {
        let family = "uniform token subsetFamily:garment:familyType = \"partition\"";
        writeln!(w, "        {family}")?;
    }
    writeln!(w, "        point3f[] points.timeSamples = {{")?;
    let mut f = File::open(spool)?;
    std::io::copy(&mut f, w)?;
    writeln!(w, "        }}")?;
    for (name, faces) in &m.subsets {
        let faces: Vec<String> = faces.iter().map(u32::to_string).collect();
        writeln!(w)?;
        writeln!(w, "        def GeomSubset \"{name}\"")?;
        writeln!(w, "        {{")?;
        writeln!(w, "            uniform token elementType = \"face\"")?;
        writeln!(w, "            uniform token familyName = \"garment\"")?;
        writeln!(w, "            int[] indices = [{}]", faces.join(", "))?;
        writeln!(w, "        }}")?;
    }
    writeln!(w, "    }}")
}

/// `name` as a USD prim name: letters, digits and `_`, not starting with a digit.
fn prim_name(name: &str) -> String {
    let mut s: String = (name.chars())
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

fn spool_path(path: &Path, k: usize) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("run");
    path.with_file_name(format!(".{name}.{k}.part"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("tryon-usd-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn meshes() -> Vec<UsdMesh> {
        vec![
            UsdMesh {
                name: "garment".into(),
                triangles: vec![[0, 1, 2], [0, 2, 3]],
                points: 4,
                colour: [255, 0, 51],
                subsets: vec![("2 skirt".into(), vec![0]), ("top".into(), vec![1])],
            },
            UsdMesh {
                name: "body".into(),
                triangles: vec![[0, 1, 2]],
                points: 3,
                colour: [0, 0, 0],
                subsets: vec![],
            },
        ]
    }

    fn frame(k: usize) -> (Vec<Vec3>, Vec<Vec3>) {
        let g = (0..4).map(|i| Vec3::new(i as f64, k as f64 * 0.5, 0.1));
        let b = (0..3).map(|i| Vec3::new(-(i as f64), 1.0, k as f64));
        (g.collect(), b.collect())
    }

    #[test]
    fn a_stage_is_written_whole_with_its_samples_and_subsets() {
        let dir = scratch("write");
        let path = dir.join("run.usda");
        let mut w = UsdWriter::create(&path, 30.0, meshes()).unwrap();
        for k in 0..3 {
            let (g, b) = frame(k);
            w.frame(&[&g, &b]).unwrap();
        }
        assert!(w.frame(&[&frame(0).0]).is_err(), "a mesh missing");
        assert!(!path.exists(), "the stage appears only when finished");
        w.finish().unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("#usda 1.0\n"));
        assert!(text.contains("endTimeCode = 2\n"), "{text}");
        assert!(text.contains("timeCodesPerSecond = 30\n"));
        assert!(text.contains("int[] faceVertexIndices = [0, 1, 2, 0, 2, 3]"));
        assert!(
            text.contains("            2: [(0, 1, 0.1), (1, 1, 0.1), (2, 1, 0.1), (3, 1, 0.1)],\n")
        );
        assert!(text.contains("            1: [(-0, 1, 1), (-1, 1, 1), (-2, 1, 1)],\n"));
        assert!(text.contains("def GeomSubset \"_2_skirt\""), "a prim name");
        assert!(text.contains("color3f[] primvars:displayColor = [(1, 0, 0.2)]"));
        let left = std::fs::read_dir(&dir).unwrap().count();
        assert_eq!(left, 1, "the spools are removed");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_stage_resumes_from_its_checkpoint_to_the_same_bytes() {
        let dir = scratch("resume");
        let (a, b) = (dir.join("a.usda"), dir.join("b.usda"));
        let write = |w: &mut UsdWriter, k| {
            let (g, bd) = frame(k);
            w.frame(&[&g, &bd]).unwrap();
        };
        let mut w = UsdWriter::create(&a, 24.0, meshes()).unwrap();
        (0..6).for_each(|k| write(&mut w, k));
        w.finish().unwrap();
        let mut w = UsdWriter::create(&b, 24.0, meshes()).unwrap();
        (0..3).for_each(|k| write(&mut w, k));
        let state = w.checkpoint().unwrap();
        // Killed after two more frames.
        (3..5).for_each(|k| write(&mut w, k));
        w.checkpoint().unwrap();
        drop(w);
        let mut w = UsdWriter::resume(&b, 24.0, meshes(), &state).unwrap();
        (3..6).for_each(|k| write(&mut w, k));
        w.finish().unwrap();
        assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
        let short = UsdState {
            samples: 9,
            spooled: vec![1 << 40, 0],
        };
        UsdWriter::create(&b, 24.0, meshes()).unwrap();
        assert!(UsdWriter::resume(&b, 24.0, meshes(), &short).is_err());
        assert!(UsdWriter::create(&a, f64::NAN, meshes()).is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
