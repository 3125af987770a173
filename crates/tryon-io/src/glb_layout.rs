//! The GLB's layout: the glTF JSON and the pieces of its BIN chunk (bytes made at the end, spans
//! of the spooled frames, the morph weights generated while writing), and the container written
//! from them: header, JSON chunk padded with spaces, BIN chunk padded with zeros.

use crate::glb::GlbWriter;
use serde_json::{Value, json};
use std::io::Write;
use tryon_core::math::Vec3;

/// A part of the BIN chunk.
#[derive(Clone, Debug)]
pub(crate) enum Piece {
    Pad(u64),
    Bytes(Vec<u8>),
    /// `len` bytes of the spool from `start`.
    Spool {
        start: u64,
        len: u64,
    },
    /// The morph weights animation: for each of `frames` frames, `targets` f32 weights, target
    /// k - `first` at 1 in frame k.
    Weights {
        frames: usize,
        targets: usize,
        first: usize,
    },
}

/// Buffer views and accessors as they are laid into the BIN chunk.
#[derive(Debug, Default)]
pub(crate) struct Doc {
    pub len: u64,
    pub pieces: Vec<Piece>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Doc {
    /// A view of `len` bytes made of `piece`, aligned to 4.
    fn view_of(&mut self, piece: Piece, len: u64, target: Option<u32>) -> usize {
        let pad = (4 - self.len % 4) % 4;
        if pad > 0 {
            self.pieces.push(Piece::Pad(pad));
            self.len += pad;
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.len, "byteLength": len});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.pieces.push(piece);
        self.len += len;
        self.views.push(v);
        self.views.len() - 1
    }

    fn view(&mut self, bytes: Vec<u8>, target: Option<u32>) -> usize {
        let len = bytes.len() as u64;
        self.view_of(Piece::Bytes(bytes), len, target)
    }

    fn accessor(&mut self, a: Value) -> usize {
        self.accessors.push(a);
        self.accessors.len() - 1
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
        let view = self.view(bytes, target);
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
        self.accessor(a)
    }

    /// A VEC3 f32 accessor over `count` vectors of a piece laid elsewhere.
    fn vec3s(&mut self, piece: Piece, count: usize, bounds: Option<([f32; 3], [f32; 3])>) -> usize {
        let view = self.view_of(piece, 12 * count as u64, Some(34962));
        let mut a =
            json!({"bufferView": view, "componentType": 5126, "count": count, "type": "VEC3"});
        if let Some((lo, hi)) = bounds {
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        self.accessor(a)
    }

    fn indices(&mut self, tris: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = tris
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let view = self.view(bytes, Some(34963));
        self.accessor(json!({"bufferView": view, "componentType": 5125, "count": tris.len() * 3, "type": "SCALAR"}))
    }
}

pub(crate) fn flat(v: &[Vec3]) -> Vec<f32> {
    v.iter()
        .flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect()
}

/// Area-weighted vertex normals, unit length in f32 (up where undefined).
pub(crate) fn normals(x: &[Vec3], tris: &[[u32; 3]]) -> Vec<Vec3> {
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

pub(crate) fn unit_f32(v: &[Vec3]) -> Vec<f32> {
    v.iter()
        .flat_map(|p| {
            let (x, y, z) = (p.x as f32, p.y as f32, p.z as f32);
            let l = (x * x + y * y + z * z).sqrt();
            [x / l, y / l, z / l]
        })
        .collect()
}

/// The animation's samplers, channels and the nodes they move.
#[derive(Default)]
struct Anim {
    nodes: Vec<Value>,
    channels: Vec<Value>,
    samplers: Vec<Value>,
    skins: Vec<Value>,
    roots: Vec<usize>,
}

impl Anim {
    fn channel(&mut self, time_acc: usize, out: usize, node: usize, path: &str) {
        self.samplers
            .push(json!({"input": time_acc, "output": out, "interpolation": "LINEAR"}));
        self.channels.push(
            json!({"sampler": self.samplers.len() - 1, "target": {"node": node, "path": path}}),
        );
    }
}

/// The skinned body's joints, skin and animation.
fn rig(w: &GlbWriter, d: &mut Doc, a: &mut Anim, attrs: &mut Value, time_acc: usize) {
    let Some(s) = &w.body.rig else { return };
    let jbytes: Vec<u8> = s
        .joints
        .iter()
        .flatten()
        .flat_map(|j| j.to_le_bytes())
        .collect();
    let jv = d.view(jbytes, Some(34962));
    attrs["JOINTS_0"] = json!(d.accessor(
        json!({"bufferView": jv, "componentType": 5123, "count": s.joints.len(), "type": "VEC4"})
    ));
    let wts: Vec<f32> = s
        .weights
        .iter()
        .flat_map(|w| {
            let mut f = w.map(|x| x as f32);
            let sum: f32 = f.iter().sum();
            f.iter_mut().for_each(|x| *x /= sum);
            f
        })
        .collect();
    attrs["WEIGHTS_0"] = json!(d.floats(&wts, 4, "VEC4", Some(34962), false));
    // Joint nodes: node j is joint j; translations are rest offsets from the parent.
    let base = a.nodes.len();
    let n = s.joint_names.len();
    for j in 0..n {
        let t = match s.parents[j] {
            Some(p) => s.joint_rest[j] - s.joint_rest[p],
            None => s.joint_rest[j],
        };
        let children: Vec<usize> = (0..n)
            .filter(|&c| s.parents[c] == Some(j))
            .map(|c| base + c)
            .collect();
        let mut node =
            json!({"name": s.joint_names[j], "translation": [t.x as f32, t.y as f32, t.z as f32]});
        if !children.is_empty() {
            node["children"] = json!(children);
        }
        a.nodes.push(node);
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
    let root = (0..n).find(|&j| s.parents[j].is_none()).unwrap_or(0);
    a.skins.push(json!({"joints": (base..base + n).collect::<Vec<_>>(), "inverseBindMatrices": ibm_acc, "skeleton": base + root}));
    a.roots.push(base + root);
    let frames = w.times.len();
    for j in 0..n {
        let q: Vec<f32> = (0..frames).flat_map(|f| w.rotations[f * n + j]).collect();
        let out = d.floats(&q, 4, "VEC4", None, false);
        a.channel(time_acc, out, base + j, "rotation");
    }
    let tr: Vec<Vec3> = w
        .root_translations
        .iter()
        .map(|t| s.joint_rest[root] + t)
        .collect();
    let out = d.floats(&flat(&tr), 3, "VEC3", None, false);
    a.channel(time_acc, out, base + root, "translation");
}

/// The glTF document of everything `w` took, its binary laid into `d`.
pub(crate) fn document(w: &GlbWriter, name: &str, d: &mut Doc) -> Value {
    let mut a = Anim::default();
    let mut meshes: Vec<Value> = Vec::new();
    let times: Vec<f32> = w.times.iter().map(|&t| t as f32).collect();
    let time_acc = d.floats(&times, 1, "SCALAR", None, true);
    let mut materials = vec![
        json!({"name": "body", "pbrMetallicRoughness": {"baseColorFactor": [0.80, 0.66, 0.58, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.8}}),
    ];
    for (k, (name, _)) in w.parts.iter().enumerate() {
        let c = crate::preview::garment_colour(k).map(|c| c as f32 / 255.0);
        materials.push(json!({"name": name, "doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [c[0], c[1], c[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9}}));
    }
    // Body.
    let (bx, btris) = (&w.body.positions, &w.body.triangles);
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
    rig(w, d, &mut a, &mut attrs, time_acc);
    let mut prim = json!({"attributes": attrs, "indices": idx, "material": 0});
    let mut body_mesh = json!({"name": "body"});
    let morph = body_morphs(w, d, &mut prim, &mut body_mesh);
    body_mesh["primitives"] = json!([prim]);
    meshes.push(body_mesh);
    let mut body_node = json!({"name": "body", "mesh": 0});
    if !a.skins.is_empty() {
        body_node["skin"] = json!(0);
    }
    a.nodes.push(body_node);
    a.roots.push(a.nodes.len() - 1);
    if let Some(out) = morph {
        a.channel(time_acc, out, a.nodes.len() - 1, "weights");
    }
    garment(w, d, &mut a, &mut meshes, time_acc);
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "tryon"},
        "scene": 0,
        "scenes": [{"name": name, "nodes": a.roots}],
        "nodes": a.nodes,
        "meshes": meshes,
        "materials": materials,
        "buffers": [{"byteLength": d.len}],
        "bufferViews": d.views,
        "accessors": d.accessors,
    });
    if !a.skins.is_empty() {
        doc["skins"] = json!(a.skins);
    }
    if !a.channels.is_empty() {
        doc["animations"] =
            json!([{"name": "tryon", "channels": a.channels, "samplers": a.samplers}]);
    }
    doc
}

/// The body's per-frame sparse morph targets (what the press added, in the rest pose), when any
/// frame has one: one target per frame, on in its frame; returns the weights' accessor.
fn body_morphs(w: &GlbWriter, d: &mut Doc, prim: &mut Value, mesh: &mut Value) -> Option<usize> {
    if w.body_targets.iter().all(Vec::is_empty) {
        return None;
    }
    let n = w.body.positions.len();
    let targets: Vec<Value> = w
        .body_targets
        .iter()
        .map(|e| {
            // Vertices left out are zero, so zero is within the bounds unless every one is listed.
            let zero = if e.len() < n { 0.0 } else { f32::INFINITY };
            let (mut lo, mut hi) = ([zero; 3], [-zero; 3]);
            for (_, v) in e {
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            // A frame with nothing pressed still lists vertex 0 (at zero): readers such as the
            // gltf crate refuse an accessor with neither a buffer view nor sparse values.
            let zero = [(0u32, [0.0f32; 3])];
            let e = if e.is_empty() { &zero[..] } else { &e[..] };
            let ib: Vec<u8> = e.iter().flat_map(|(i, _)| i.to_le_bytes()).collect();
            let vb: Vec<u8> = e.iter().flat_map(|(_, v)| v.map(f32::to_le_bytes)).flatten().collect();
            let (iv, vv) = (d.view(ib, None), d.view(vb, None));
            let sparse = json!({"count": e.len(), "indices": {"bufferView": iv, "componentType": 5125}, "values": {"bufferView": vv}});
            let acc = json!({"componentType": 5126, "count": n, "type": "VEC3", "min": lo, "max": hi, "sparse": sparse});
            json!({"POSITION": d.accessor(acc)})
        })
        .collect();
    let (frames, t) = (w.times.len(), targets.len());
    prim["targets"] = json!(targets);
    mesh["weights"] = json!(vec![0.0f32; t]);
    let piece = Piece::Weights {
        frames,
        targets: t,
        first: 0,
    };
    let view = d.view_of(piece, 4 * (frames * t) as u64, None);
    Some(d.accessor(
        json!({"bufferView": view, "componentType": 5126, "count": frames * t, "type": "SCALAR"}),
    ))
}

/// The garment: frame 0 is the base; every later frame is a morph target read from the spool.
fn garment(w: &GlbWriter, d: &mut Doc, a: &mut Anim, meshes: &mut Vec<Value>, time_acc: usize) {
    let n = w.base.len();
    let gpos = d.floats(&flat(&w.base), 3, "VEC3", Some(34962), true);
    let gnrm = d.floats(&unit_f32(&w.base_normals), 3, "VEC3", Some(34962), false);
    let bytes = 12 * n as u64;
    let targets: Vec<Value> = w
        .targets
        .iter()
        .map(|&(start, lo, hi)| {
            let p = d.vec3s(Piece::Spool { start, len: bytes }, n, Some((lo, hi)));
            let span = Piece::Spool {
                start: start + bytes,
                len: bytes,
            };
            let nm = d.vec3s(span, n, None);
            json!({"POSITION": p, "NORMAL": nm})
        })
        .collect();
    // One primitive per garment: the vertices and their frames are shared, the triangles and
    // the material are the garment's own.
    let t = targets.len();
    let prims: Vec<Value> = w
        .parts
        .iter()
        .enumerate()
        .filter(|(_, (_, tris))| !tris.is_empty())
        .map(|(k, (_, tris))| {
            let mut prim = json!({"attributes": {"POSITION": gpos, "NORMAL": gnrm}, "indices": d.indices(tris), "material": 1 + k});
            if t > 0 {
                prim["targets"] = json!(targets);
            }
            prim
        })
        .collect();
    let mut gmesh = json!({"name": "garment", "primitives": prims});
    let frames = w.times.len();
    let mut weights_out = None;
    if t > 0 {
        gmesh["weights"] = json!(vec![0.0f32; t]);
        let len = 4 * (frames * t) as u64;
        let piece = Piece::Weights {
            frames,
            targets: t,
            first: 1,
        };
        let view = d.view_of(piece, len, None);
        weights_out = Some(d.accessor(json!({"bufferView": view, "componentType": 5126, "count": frames * t, "type": "SCALAR"})));
    }
    meshes.push(gmesh);
    a.nodes.push(json!({"name": "garment", "mesh": 1}));
    a.roots.push(a.nodes.len() - 1);
    if let Some(out) = weights_out {
        a.channel(time_acc, out, a.nodes.len() - 1, "weights");
    }
}

/// The GLB container, ready to write.
#[derive(Debug)]
pub(crate) struct Layout {
    pub json: Vec<u8>,
    pub pieces: Vec<Piece>,
    pub bin_len: u64,
}

fn pad4(n: u64) -> u64 {
    (n + 3) & !3
}

impl Layout {
    /// Length of the whole file.
    pub fn total_len(&self) -> u64 {
        12 + 8 + pad4(self.json.len() as u64) + 8 + pad4(self.bin_len)
    }

    /// Writes the file; `spool(w, start, len)` copies a span of the spooled frames.
    pub fn write(
        &self,
        w: &mut dyn Write,
        spool: &mut dyn FnMut(&mut dyn Write, u64, u64) -> std::io::Result<()>,
    ) -> std::io::Result<()> {
        w.write_all(b"glTF")?;
        w.write_all(&2u32.to_le_bytes())?;
        w.write_all(&(self.total_len() as u32).to_le_bytes())?;
        let json_len = pad4(self.json.len() as u64);
        w.write_all(&(json_len as u32).to_le_bytes())?;
        w.write_all(b"JSON")?;
        w.write_all(&self.json)?;
        w.write_all(&vec![b' '; (json_len - self.json.len() as u64) as usize])?;
        let bin_len = pad4(self.bin_len);
        w.write_all(&(bin_len as u32).to_le_bytes())?;
        w.write_all(b"BIN\0")?;
        for p in &self.pieces {
            match p {
                Piece::Pad(n) => w.write_all(&vec![0u8; *n as usize])?,
                Piece::Bytes(b) => w.write_all(b)?,
                Piece::Spool { start, len } => spool(w, *start, *len)?,
                Piece::Weights {
                    frames,
                    targets,
                    first,
                } => {
                    for k in 0..*frames {
                        let row: Vec<u8> = (0..*targets)
                            .flat_map(|i| {
                                let x: f32 = if k >= *first && i == k - first {
                                    1.0
                                } else {
                                    0.0
                                };
                                x.to_le_bytes()
                            })
                            .collect();
                        w.write_all(&row)?;
                    }
                }
            }
        }
        w.write_all(&vec![0u8; (bin_len - self.bin_len) as usize])
    }
}
