//! glTF 2.0 binary (GLB) export of an animated try-on. The body is a skinned mesh (a node per
//! joint, inverse bind matrices, 4 weights per vertex) animated by joint rotations and the root's
//! translation, or a static mesh. The garment is a mesh whose frames are morph targets (position
//! and normal offsets from frame 0), played by a `weights` animation that moves linearly from one
//! target to the next, so the file opens as shape-key animation in Blender and plays in three.js.
//! The glTF JSON is built with serde_json and packed by the `gltf` crate's GLB writer.

use crate::atomic::write_atomic;
use serde_json::{Value, json};
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
    /// Per frame: the root's translation from rest and every joint's local rotation.
    pub root_translation: &'a [Vec3],
    pub rotations: &'a [Vec<UnitQuat>],
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

/// What to write.
#[derive(Clone, Copy, Debug)]
pub struct AnimatedScene<'a> {
    pub name: &'a str,
    /// Time of every frame (s), strictly increasing.
    pub times: &'a [Real],
    pub body: BodyExport<'a>,
    pub garment_triangles: &'a [[u32; 3]],
    /// Garment positions per frame (same count as `times`).
    pub garment_frames: &'a [Vec<Vec3>],
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

#[derive(Default)]
struct Doc {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Doc {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    /// An accessor of f32 components (`kind` "SCALAR", "VEC3", ...); min/max when asked.
    fn floats(
        &mut self,
        data: &[f32],
        comps: usize,
        kind: &str,
        target: Option<u32>,
        bounds: bool,
    ) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let mut a = json!({"bufferView": view, "componentType": 5126, "count": data.len() / comps, "type": kind});
        if bounds {
            let mut lo = vec![f32::INFINITY; comps];
            let mut hi = vec![f32::NEG_INFINITY; comps];
            for c in data.chunks(comps) {
                for k in 0..comps {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(&bytes, Some(34963));
        self.accessors.push(json!({"bufferView": view, "componentType": 5125, "count": tris.len() * 3, "type": "SCALAR"}));
        self.accessors.len() - 1
    }
}

fn flat(v: &[Vec3]) -> Vec<f32> {
    v.iter()
        .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect()
}

/// Area-weighted vertex normals, unit length in f32 (up where undefined).
fn normals(x: &[Vec3], tris: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); x.len()];
    for t in tris {
        let f = (x[t[1] as usize] - x[t[0] as usize]).cross(&(x[t[2] as usize] - x[t[0] as usize]));
        for &v in t {
            n[v as usize] += f;
        }
    }
    n.iter()
        .map(|v| v.try_normalize(1e-20).unwrap_or(Vec3::y()))
        .collect()
}

fn unit_f32(v: &[Vec3]) -> Vec<f32> {
    v.iter()
        .flat_map(|p| {
            let (x, y, z) = (p.x as f32, p.y as f32, p.z as f32);
            let l = (x * x + y * y + z * z).sqrt();
            [x / l, y / l, z / l]
        })
        .collect()
}

fn check(scene: &AnimatedScene) -> Result<(), GlbError> {
    let bad = |m: String| Err(GlbError::Invalid(m));
    if scene.times.is_empty() || scene.times.len() != scene.garment_frames.len() {
        return bad(format!(
            "{} times for {} garment frames",
            scene.times.len(),
            scene.garment_frames.len()
        ));
    }
    if scene.times.windows(2).any(|w| !(w[1] > w[0])) {
        return bad("frame times must increase".into());
    }
    let n = scene.garment_frames[0].len();
    if scene.garment_frames.iter().any(|f| f.len() != n) {
        return bad("garment frames differ in vertex count".into());
    }
    let all = scene.garment_frames.iter().flatten();
    if all.clone().any(|p| !p.iter().all(|c| c.is_finite())) {
        return bad("a garment position is not finite".into());
    }
    if scene
        .garment_triangles
        .iter()
        .flatten()
        .any(|&v| v as usize >= n)
    {
        return bad("a garment triangle refers past the last vertex".into());
    }
    if let BodyExport::Skinned(s) = scene.body {
        let f = scene.times.len();
        if s.rotations.len() != f || s.root_translation.len() != f {
            return bad("body animation frames differ from the garment's".into());
        }
        if s.joints.len() != s.positions.len() || s.weights.len() != s.positions.len() {
            return bad("skin weights do not cover the body".into());
        }
    }
    Ok(())
}

/// The GLB file's bytes.
pub fn glb_bytes(scene: &AnimatedScene) -> Result<Vec<u8>, GlbError> {
    check(scene)?;
    let mut d = Doc::default();
    let mut nodes: Vec<Value> = Vec::new();
    let mut meshes: Vec<Value> = Vec::new();
    let mut channels: Vec<Value> = Vec::new();
    let mut samplers: Vec<Value> = Vec::new();
    let mut skins: Vec<Value> = Vec::new();
    let mut roots: Vec<usize> = Vec::new();
    let times: Vec<f32> = scene.times.iter().map(|&t| t as f32).collect();
    let time_acc = d.floats(&times, 1, "SCALAR", None, true);
    let materials = json!([
        {"name": "body", "pbrMetallicRoughness": {"baseColorFactor": [0.80, 0.66, 0.58, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}},
        {"name": "garment", "doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.20, 0.32, 0.70, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9}}
    ]);

    // Body.
    let (bx, btris) = match scene.body {
        BodyExport::Static {
            positions,
            triangles,
        } => (positions, triangles),
        BodyExport::Skinned(s) => (s.positions, s.triangles),
    };
    let pos = d.floats(&flat(bx), 3, "VEC3", Some(34962), true);
    let nrm = d.floats(
        &unit_f32(&normals(bx, btris)),
        3,
        "VEC3",
        Some(34962),
        false,
    );
    let idx = d.indices(btris);
    let mut attrs = json!({"POSITION": pos, "NORMAL": nrm});
    if let BodyExport::Skinned(s) = scene.body {
        let jbytes: Vec<u8> = s
            .joints
            .iter()
            .flatten()
            .flat_map(|j| j.to_le_bytes())
            .collect();
        let jv = d.view(&jbytes, Some(34962));
        d.accessors.push(json!({"bufferView": jv, "componentType": 5123, "count": s.joints.len(), "type": "VEC4"}));
        attrs["JOINTS_0"] = json!(d.accessors.len() - 1);
        let w: Vec<f32> = s
            .weights
            .iter()
            .flat_map(|w| {
                let mut f = w.map(|x| x as f32);
                let sum: f32 = f.iter().sum();
                f.iter_mut().for_each(|x| *x /= sum);
                f
            })
            .collect();
        attrs["WEIGHTS_0"] = json!(d.floats(&w, 4, "VEC4", Some(34962), false));
        // Joint nodes: node j is joint j; translations are rest offsets from the parent.
        let base = nodes.len();
        for j in 0..s.joint_names.len() {
            let t = match s.parents[j] {
                Some(p) => s.joint_rest[j] - s.joint_rest[p],
                None => s.joint_rest[j],
            };
            let children: Vec<usize> = (0..s.parents.len())
                .filter(|&c| s.parents[c] == Some(j))
                .map(|c| base + c)
                .collect();
            let mut n = json!({"name": s.joint_names[j], "translation": [t.x as f32, t.y as f32, t.z as f32]});
            if !children.is_empty() {
                n["children"] = json!(children);
            }
            nodes.push(n);
        }
        let ibm: Vec<f32> = s
            .joint_rest
            .iter()
            .flat_map(|p| {
                let mut m = [0f32; 16];
                m[0] = 1.0;
                m[5] = 1.0;
                m[10] = 1.0;
                m[15] = 1.0;
                m[12] = -p.x as f32;
                m[13] = -p.y as f32;
                m[14] = -p.z as f32;
                m
            })
            .collect();
        let ibm_acc = d.floats(&ibm, 16, "MAT4", None, false);
        let root = (0..s.parents.len())
            .find(|&j| s.parents[j].is_none())
            .unwrap_or(0);
        skins.push(json!({"joints": (base..base + s.joint_names.len()).collect::<Vec<_>>(), "inverseBindMatrices": ibm_acc, "skeleton": base + root}));
        roots.push(base + root);
        for j in 0..s.joint_names.len() {
            let q: Vec<f32> = s
                .rotations
                .iter()
                .flat_map(|r| {
                    let c = r
                        .get(j)
                        .copied()
                        .unwrap_or_else(UnitQuat::identity)
                        .into_inner()
                        .coords;
                    let f = [c.x as f32, c.y as f32, c.z as f32, c.w as f32];
                    let l = f.iter().map(|x| x * x).sum::<f32>().sqrt();
                    f.map(|x| x / l)
                })
                .collect();
            let out = d.floats(&q, 4, "VEC4", None, false);
            samplers.push(json!({"input": time_acc, "output": out, "interpolation": "LINEAR"}));
            channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": base + j, "path": "rotation"}}));
        }
        let tr: Vec<Vec3> = s
            .root_translation
            .iter()
            .map(|t| s.joint_rest[root] + t)
            .collect();
        let out = d.floats(&flat(&tr), 3, "VEC3", None, false);
        samplers.push(json!({"input": time_acc, "output": out, "interpolation": "LINEAR"}));
        channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": base + root, "path": "translation"}}));
    }
    meshes.push(json!({"name": "body", "primitives": [{"attributes": attrs, "indices": idx, "material": 0}]}));
    let mut body_node = json!({"name": "body", "mesh": 0});
    if !skins.is_empty() {
        body_node["skin"] = json!(0);
    }
    nodes.push(body_node);
    roots.push(nodes.len() - 1);

    // Garment: frame 0 is the base; every later frame is a morph target.
    let g0 = &scene.garment_frames[0];
    let gt = scene.garment_triangles;
    let n0 = normals(g0, gt);
    let gpos = d.floats(&flat(g0), 3, "VEC3", Some(34962), true);
    let gnrm = d.floats(&unit_f32(&n0), 3, "VEC3", Some(34962), false);
    let gidx = d.indices(gt);
    let mut targets = Vec::new();
    for f in &scene.garment_frames[1..] {
        let dp: Vec<Vec3> = f.iter().zip(g0).map(|(a, b)| a - b).collect();
        let nf = normals(f, gt);
        let dn: Vec<Vec3> = nf.iter().zip(&n0).map(|(a, b)| a - b).collect();
        let p = d.floats(&flat(&dp), 3, "VEC3", Some(34962), true);
        let n = d.floats(&flat(&dn), 3, "VEC3", Some(34962), false);
        targets.push(json!({"POSITION": p, "NORMAL": n}));
    }
    let mut prim =
        json!({"attributes": {"POSITION": gpos, "NORMAL": gnrm}, "indices": gidx, "material": 1});
    let t = targets.len();
    if t > 0 {
        prim["targets"] = json!(targets);
    }
    let mut gmesh = json!({"name": "garment", "primitives": [prim]});
    if t > 0 {
        gmesh["weights"] = json!(vec![0.0f32; t]);
        // Frame k (k >= 1) shows target k-1 at weight 1.
        let w: Vec<f32> = (0..scene.times.len())
            .flat_map(|k| (0..t).map(move |i| if k >= 1 && i == k - 1 { 1.0 } else { 0.0 }))
            .collect();
        let out = d.floats(&w, 1, "SCALAR", None, false);
        samplers.push(json!({"input": time_acc, "output": out, "interpolation": "LINEAR"}));
    }
    meshes.push(gmesh);
    nodes.push(json!({"name": "garment", "mesh": 1}));
    roots.push(nodes.len() - 1);
    if t > 0 {
        channels.push(json!({"sampler": samplers.len() - 1, "target": {"node": nodes.len() - 1, "path": "weights"}}));
    }

    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "tryon"},
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": roots}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "buffers": [{"byteLength": d.bin.len()}],
        "bufferViews": d.views,
        "accessors": d.accessors,
    });
    if !skins.is_empty() {
        doc["skins"] = json!(skins);
    }
    if !channels.is_empty() {
        doc["animations"] = json!([{"name": "tryon", "channels": channels, "samplers": samplers}]);
    }
    let json = serde_json::to_vec(&doc).map_err(|e| GlbError::Pack(e.to_string()))?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0,
        },
        json: json.into(),
        bin: Some(d.bin.into()),
    };
    glb.to_vec().map_err(|e| GlbError::Pack(e.to_string()))
}

/// Writes the GLB atomically.
pub fn write_glb(path: &Path, scene: &AnimatedScene) -> Result<(), GlbError> {
    let bytes = glb_bytes(scene)?;
    write_atomic(path, &bytes).map_err(|source| GlbError::Io {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn static_body_and_morphing_garment_read_back() {
        let body = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let tri = [[0u32, 1, 2]];
        let frames = vec![body.to_vec(), body.iter().map(|p| p + Vec3::z()).collect()];
        let scene = AnimatedScene {
            name: "t",
            times: &[0.0, 0.5],
            body: BodyExport::Static {
                positions: &body,
                triangles: &tri,
            },
            garment_triangles: &tri,
            garment_frames: &frames,
        };
        let bytes = glb_bytes(&scene).unwrap();
        let g = gltf::Gltf::from_slice(&bytes).unwrap();
        assert_eq!(g.meshes().count(), 2);
        assert_eq!(g.animations().count(), 1);
        let bad = AnimatedScene {
            times: &[0.0, 0.0],
            ..scene
        };
        assert!(matches!(glb_bytes(&bad), Err(GlbError::Invalid(_))));
    }
}
