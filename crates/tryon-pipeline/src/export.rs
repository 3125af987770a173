//! Writing a run's outputs into a directory: scene.glb (skinned body + morph-target garment),
//! preview.png (one frame, body and garment in different colours) and stats.json.

use crate::pipeline::Pipeline;
use crate::run::RunOutput;
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::math::Vec3;
use tryon_core::pose::Pose;
use tryon_io::{
    AnimatedScene, BodyExport, Camera, GlbError, PreviewError, PreviewMesh, SkinnedExport, render,
    write_glb, write_json, write_png,
};

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
    #[error("{}: cannot write: {source}", path.display())]
    Json {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl Pipeline {
    /// Writes the outputs the scene asks for into `dir`; returns the files written.
    pub fn export(&self, run: &RunOutput, dir: &Path) -> Result<Vec<PathBuf>, ExportError> {
        std::fs::create_dir_all(dir).map_err(|source| ExportError::Dir {
            path: dir.to_path_buf(),
            source,
        })?;
        let o = &self.scene.output;
        let mut written = Vec::new();
        if o.glb && !run.frames.is_empty() {
            let path = dir.join("scene.glb");
            let times: Vec<f64> = run.frames.iter().map(|f| f.time).collect();
            let garment: Vec<Vec<Vec3>> = run.frames.iter().map(|f| f.garment.clone()).collect();
            let poses: Vec<&Pose> = run.frames.iter().filter_map(|f| f.pose.as_ref()).collect();
            let roots: Vec<Vec3> = poses.iter().map(|p| p.root_translation).collect();
            let rots: Vec<_> = poses.iter().map(|p| p.local_rotations.clone()).collect();
            let rig = self.body.rig().filter(|_| self.motion.is_some());
            let body = match rig {
                Some(m) if poses.len() == run.frames.len() => BodyExport::Skinned(SkinnedExport {
                    positions: m.rest_positions,
                    triangles: &run.body_triangles,
                    joint_names: &m.skeleton.names,
                    parents: &m.skeleton.parents,
                    joint_rest: m.joint_rest,
                    joints: m.joints,
                    weights: m.weights,
                    root_translation: &roots,
                    rotations: &rots,
                }),
                _ => BodyExport::Static {
                    positions: &self.body_mesh.positions,
                    triangles: &run.body_triangles,
                },
            };
            write_glb(
                &path,
                &AnimatedScene {
                    name: &self.scene.scene.name,
                    times: &times,
                    body,
                    garment_triangles: &run.garment_triangles,
                    garment_frames: &garment,
                },
            )?;
            written.push(path);
        }
        if o.preview && !run.frames.is_empty() {
            let path = dir.join("preview.png");
            let k = o
                .preview_frame
                .unwrap_or(run.frames.len() - 1)
                .min(run.frames.len() - 1);
            let rec = &run.frames[k];
            let body = self.body_at(rec.pose.as_ref());
            let meshes = [
                PreviewMesh {
                    positions: &body,
                    triangles: &run.body_triangles,
                    color: [205, 170, 150],
                },
                PreviewMesh {
                    positions: &rec.garment,
                    triangles: &run.garment_triangles,
                    color: [55, 85, 170],
                },
            ];
            let cam = Camera::framing(&meshes);
            write_png(
                &path,
                &render(&meshes, &cam, o.preview_width, o.preview_height),
            )?;
            written.push(path);
        }
        if o.stats {
            let path = dir.join("stats.json");
            write_json(&path, &run.stats).map_err(|source| ExportError::Json {
                path: path.clone(),
                source,
            })?;
            written.push(path);
        }
        Ok(written)
    }
}
