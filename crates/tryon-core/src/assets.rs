//! Plain data read from asset files (tryon-io parses them; the stage crates use them): polygon meshes
//! that keep their file's vertex order, MakeHuman skeletons, skin weights, morph targets and garment
//! bindings, and motion clips. All lengths are in metres.

use crate::math::{Real, Vec3};
use crate::mesh::Face;
use crate::pose::{Pose, Skeleton};
use std::ops::Range;

/// A mesh as its file stores it: vertices in file order, faces (triangles and quads) with optional
/// texture-coordinate faces, and named face groups.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObjMesh {
    pub positions: Vec<Vec3>,
    pub uvs: Vec<[Real; 2]>,
    pub faces: Vec<Face>,
    /// One UV face per face when the file gives texture coordinates for every face, else empty.
    pub face_uvs: Vec<Face>,
    /// Named face groups (`g name`), in file order, as ranges of `faces`.
    pub groups: Vec<(String, Range<usize>)>,
}

impl ObjMesh {
    /// Faces of every group called `name` (a group may be opened more than once).
    pub fn group_faces(&self, name: &str) -> Vec<usize> {
        self.groups
            .iter()
            .filter(|(n, _)| n == name)
            .flat_map(|(_, r)| r.clone())
            .collect()
    }

    /// Sorted, distinct vertices used by the faces of group `name`.
    pub fn group_vertices(&self, name: &str) -> Vec<u32> {
        let mut v: Vec<u32> = self
            .group_faces(name)
            .into_iter()
            .flat_map(|f| self.faces[f].vertices().to_vec())
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// Axis-aligned bounding box (min, max); `None` without vertices.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
        )
    }
}

/// One bone of a MakeHuman skeleton (.mhskel): head and tail are the means of base-mesh vertices.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MhBone {
    pub name: String,
    pub parent: Option<usize>,
    pub head: Vec<u32>,
    pub tail: Vec<u32>,
    /// Default-rig bones this bone stands for (`reference`).
    pub reference: Vec<String>,
    /// Default-rig bones whose weights this bone takes (`weights_reference`; empty: use `reference`).
    pub weights_reference: Vec<String>,
}

/// A MakeHuman skeleton; bones are ordered so that parents come before children.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MhSkeleton {
    pub name: String,
    pub bones: Vec<MhBone>,
}

impl MhSkeleton {
    /// Index of the bone called `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    /// Mean of the listed vertices of `positions` (the head or tail of a bone); `None` when a
    /// vertex is out of range or the list is empty.
    pub fn joint_position(verts: &[u32], positions: &[Vec3]) -> Option<Vec3> {
        if verts.is_empty() {
            return None;
        }
        let mut sum = Vec3::zeros();
        for &v in verts {
            sum += positions.get(v as usize)?;
        }
        Some(sum / verts.len() as Real)
    }
}

/// Raw skin weights (.mhw): for each bone, (vertex, weight) pairs as the file lists them.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MhWeights {
    pub bones: Vec<(String, Vec<(u32, Real)>)>,
}

/// A morph target (.target): offsets (m) of the listed vertices.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MorphTarget {
    pub name: String,
    pub offsets: Vec<(u32, Vec3)>,
}

impl MorphTarget {
    /// Adds `weight` times the target to `positions` (vertices out of range are skipped).
    pub fn apply(&self, weight: Real, positions: &mut [Vec3]) {
        for (v, d) in &self.offsets {
            if let Some(p) = positions.get_mut(*v as usize) {
                *p += d * weight;
            }
        }
    }
}

/// A scale reference of a binding: the distance along one axis between two base vertices, and that
/// distance (m) on the mesh the garment was made for.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ScaleRef {
    pub a: u32,
    pub b: u32,
    pub rest: Real,
}

/// A garment or proxy binding (.mhclo / .proxy): each garment vertex is a weighted mix of three base
/// vertices plus an offset scaled per axis by the body's size against the rest size.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClothBinding {
    pub name: String,
    pub obj_file: String,
    pub refs: Vec<[u32; 3]>,
    pub weights: Vec<[Real; 3]>,
    /// Offsets (m) before scaling.
    pub offsets: Vec<Vec3>,
    /// x, y and z scale references; an axis without one keeps scale 1.
    pub scales: [Option<ScaleRef>; 3],
    /// Base vertices the garment hides (`delete_verts`).
    pub delete_verts: Vec<u32>,
}

/// The assets a MakeHuman body is made of (lengths in metres, as tryon-io reads them).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct MakeHumanAssets {
    /// base.obj (all groups, file vertex order).
    pub base: ObjMesh,
    /// The default rig (its joints define the landmarks; its bones own the weights).
    pub default_rig: MhSkeleton,
    /// default_weights.mhw.
    pub weights: MhWeights,
    /// The rig to skin with (`None`: the default rig).
    pub rig: Option<MhSkeleton>,
    /// Measurement targets by file name, e.g. `measure-hips-circ-incr`.
    pub targets: Vec<MorphTarget>,
    /// Macro targets by file name, e.g. `caucasian-female-young`.
    pub macros: Vec<MorphTarget>,
}

/// A motion clip: a skeleton, and one pose per frame at a fixed frame time. Rotations are relative
/// to the skeleton's rest offsets (the pose with every rotation zero).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MotionClip {
    pub skeleton: Skeleton,
    /// End sites: (joint, offset from it) for joints without children in the file.
    pub end_sites: Vec<(usize, Vec3)>,
    /// Seconds per frame.
    pub frame_time: Real,
    pub frames: Vec<Pose>,
    /// Metres per file unit used at load.
    pub unit: Real,
}

impl MotionClip {
    /// Frames per second.
    pub fn fps(&self) -> Real {
        1.0 / self.frame_time
    }

    /// Duration (s) from the first to the last frame.
    pub fn duration(&self) -> Real {
        self.frames.len().saturating_sub(1) as Real * self.frame_time
    }
}
