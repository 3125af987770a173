//! The caches a run's outputs stream frame by frame for other tools: the PC2 point cache, the OBJ
//! sequence, the animated GIF and the USD stage (see `Outputs`).

use super::{BODY_COLOUR, Outputs};
use crate::run::FrameRecord;
use tryon_core::math::{Real, Vec3};
use tryon_io::{
    Camera, GifWriter, Pc2Writer, PreviewMesh, UsdMesh, UsdWriter, garment_colour, render,
    write_obj_frame,
};

/// The caches' files and the OBJ sequence's folder in the output folder.
pub(super) const PC2: &str = "garment.pc2";
pub(super) const OBJ_DIR: &str = "garment-obj";
pub(super) const GIF: &str = "run.gif";
pub(super) const USD: &str = "run.usda";
pub(super) const VIEW: &str = "view.bin";

impl Outputs {
    /// Writes frame `rec` to the caches the scene asks for (PC2, the OBJ sequence).
    pub(super) fn cache_frame(&mut self, rec: &FrameRecord) {
        if self.error.is_some() {
            return;
        }
        let mut written = Ok(());
        if self.config.pc2 {
            if self.pc2.is_none() {
                match Pc2Writer::create(&self.dir.join(PC2), rec.garment.len()) {
                    Ok(w) => self.pc2 = Some(w),
                    Err(e) => written = Err(e),
                }
            }
            if let Some(w) = &mut self.pc2 {
                written = written.and_then(|()| w.frame(&rec.garment));
            }
        }
        if self.config.obj_sequence && written.is_ok() {
            let path = (self.dir.join(OBJ_DIR)).join(format!("garment_{:05}.obj", self.frames));
            let names = self.garment_names.as_slice();
            let groups = (names, self.triangle_garment.as_slice());
            written = write_obj_frame(&path, &rec.garment, &self.garment_triangles, groups);
        }
        if written.is_ok() && self.config.gif && self.frames.is_multiple_of(self.config.gif_every) {
            written = self.gif_frame(rec);
        }
        if written.is_ok() && self.config.usd {
            written = self.usd_frame(rec);
        }
        if written.is_ok() && self.config.view && self.frames.is_multiple_of(self.config.view_every)
        {
            written = self.view_frame(rec);
        }
        if let Err(e) = written {
            self.error = Some(e.into());
        }
    }

    /// Draws frame `rec` into the GIF: the body and each garment, seen by frame 0's camera moved
    /// with the body's centre.
    fn gif_frame(&mut self, rec: &FrameRecord) -> Result<(), tryon_io::CacheError> {
        let parts = self.garments();
        let meshes = picture(&self.body_triangles, &rec.body, &rec.garment, &parts);
        let n = rec.body.len().max(1) as Real;
        let centre = rec.body.iter().fold(Vec3::zeros(), |a, p| a + p) / n;
        if self.gif.is_none() {
            let (w, h, delay) = self.gif_shape();
            let writer = GifWriter::create(&self.dir.join(GIF), w, h, delay)?;
            self.gif = Some((writer, Camera::framing(&meshes), centre));
        }
        let Some((writer, first, start)) = &mut self.gif else {
            return Ok(());
        };
        let mut camera = *first;
        camera.eye += centre - *start;
        camera.target += centre - *start;
        let (w, h) = (writer.width(), writer.height());
        writer.frame(&render(&meshes, &camera, w, h))
    }

    /// Writes frame `rec` into the USD stage: the garment's points and, when asked, the body's.
    fn usd_frame(&mut self, rec: &FrameRecord) -> Result<(), tryon_io::CacheError> {
        let mut points: Vec<&[Vec3]> = vec![&rec.garment];
        if self.config.usd_body {
            points.push(&rec.body);
        }
        if self.usd.is_none() {
            let counts: Vec<usize> = points.iter().map(|p| p.len()).collect();
            let meshes = self.usd_meshes(&counts);
            let w = UsdWriter::create(&self.dir.join(USD), self.fps, meshes)?;
            self.usd = Some((w, counts));
        }
        match &mut self.usd {
            Some((w, _)) => w.frame(&points),
            None => Ok(()),
        }
    }

    /// The USD stage's meshes of `points` points each: the garment (a subset per garment when
    /// there are several) and, when there are two, the body.
    pub(super) fn usd_meshes(&self, points: &[usize]) -> Vec<UsdMesh> {
        let mut subsets: Vec<(String, Vec<u32>)> = (self.garment_names.iter())
            .map(|n| (n.clone(), Vec::new()))
            .collect();
        for (k, &g) in self.triangle_garment.iter().enumerate() {
            if let Some(s) = subsets.get_mut(g as usize) {
                s.1.push(k as u32);
            }
        }
        if subsets.len() < 2 {
            subsets.clear();
        }
        let mut meshes = vec![UsdMesh {
            name: "garment".into(),
            triangles: self.garment_triangles.clone(),
            points: points.first().copied().unwrap_or(0),
            colour: garment_colour(0),
            subsets,
        }];
        if let Some(&n) = points.get(1) {
            meshes.push(UsdMesh {
                name: "body".into(),
                triangles: self.body_triangles.clone(),
                points: n,
                colour: BODY_COLOUR,
                subsets: Vec::new(),
            });
        }
        meshes
    }

    /// Writes frame `rec` into view.bin: the body, the coarse cloth and the garment.
    fn view_frame(&mut self, rec: &FrameRecord) -> Result<(), tryon_io::CacheError> {
        if self.view.is_none() {
            let counts = [rec.body.len(), rec.coarse.len(), rec.garment.len()];
            let w = tryon_io::ViewWriter::create(&self.dir.join(VIEW), self.view_header(counts))?;
            self.view = Some((w, counts));
        }
        match &mut self.view {
            Some((w, _)) => w.frame(rec.time, (&rec.body, &rec.coarse, &rec.garment), &rec.depth),
            None => Ok(()),
        }
    }

    /// view.bin's header for meshes of `counts` vertices (body, coarse cloth, garment).
    pub(super) fn view_header(&self, counts: [usize; 3]) -> tryon_io::ViewHeader {
        let fps = self.fps / self.config.view_every.max(1) as Real;
        let meshes = ViewMeshes {
            body: &self.body_triangles,
            coarse: &self.coarse_triangles,
            garment: &self.garment_triangles,
            triangle_garment: &self.triangle_garment,
            names: &self.garment_names,
        };
        let mut h = view_header(&self.name, fps, &meshes, counts);
        h.depth = self.config.referee_every > 0;
        h
    }

    /// The garment triangles of each garment, in order (all in one when not told apart).
    pub(super) fn garments(&self) -> Vec<Vec<[u32; 3]>> {
        let n = self.triangle_garment.iter().map(|&g| g as usize + 1).max();
        let mut parts = vec![Vec::new(); n.unwrap_or(1)];
        for (k, t) in self.garment_triangles.iter().enumerate() {
            let g = self.triangle_garment.get(k).copied().unwrap_or(0) as usize;
            parts[g].push(*t);
        }
        parts
    }
}

/// The meshes of a picture: the body (`body_triangles` at `body`) and each garment (`parts`) at
/// `garment`, in their colours.
pub(super) fn picture<'a>(
    body_triangles: &'a [[u32; 3]],
    body: &'a [Vec3],
    garment: &'a [Vec3],
    parts: &'a [Vec<[u32; 3]>],
) -> Vec<PreviewMesh<'a>> {
    let mut meshes = vec![PreviewMesh {
        positions: body,
        triangles: body_triangles,
        color: BODY_COLOUR,
    }];
    meshes.extend(parts.iter().enumerate().map(|(k, tris)| PreviewMesh {
        positions: garment,
        triangles: tris,
        color: garment_colour(k),
    }));
    meshes
}

/// The triangles of view.bin's meshes and the garments' names.
#[derive(Clone, Copy, Debug)]
pub struct ViewMeshes<'a> {
    pub body: &'a [[u32; 3]],
    pub coarse: &'a [[u32; 3]],
    pub garment: &'a [[u32; 3]],
    /// The garment of each of `garment`'s triangles.
    pub triangle_garment: &'a [u16],
    pub names: &'a [String],
}

/// view.bin's header (also the live page's) for `meshes` of `counts` vertices (body, coarse
/// cloth, garment; no coarse triangles when the coarse count is 0), without depths.
pub fn view_header(
    name: &str,
    fps: Real,
    meshes: &ViewMeshes<'_>,
    counts: [usize; 3],
) -> tryon_io::ViewHeader {
    let garments = meshes.names.len().max(1);
    tryon_io::ViewHeader {
        version: 2,
        depth: false,
        name: name.to_string(),
        fps,
        body: tryon_io::ViewMesh {
            vertices: counts[0],
            triangles: meshes.body.to_vec(),
        },
        coarse: tryon_io::ViewMesh {
            vertices: counts[1],
            triangles: match counts[1] {
                0 => Vec::new(),
                _ => meshes.coarse.to_vec(),
            },
        },
        garment: tryon_io::ViewGarment {
            vertices: counts[2],
            triangles: meshes.garment.to_vec(),
            triangle_garment: meshes.triangle_garment.to_vec(),
            names: meshes.names.to_vec(),
            colours: (0..garments).map(garment_colour).collect(),
        },
    }
}
