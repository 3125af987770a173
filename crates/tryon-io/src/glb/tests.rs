//! Tests of the streamed GLB: it reads back with the gltf crate, morph targets hold each frame's
//! offsets, a file writer and an in-memory writer give the same bytes, and bad frames are named.

use super::*;
use serde_json::{Value, json};

const TRI: [[u32; 3]; 1] = [[0, 1, 2]];

fn body() -> Vec<Vec3> {
    vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ]
}

fn header(body: &[Vec3]) -> GlbHeader<'_> {
    GlbHeader {
        name: "t",
        body: BodyExport::Static {
            positions: body,
            triangles: &TRI,
        },
        garment_triangles: &TRI,
        garment_names: &[],
        triangle_garment: &[],
    }
}

/// Frame k: the triangle lifted by k/10 along z and stretched along x by k/20.
fn frame(k: usize) -> Vec<Vec3> {
    body()
        .iter()
        .map(|p| Vec3::new(p.x * (1.0 + k as Real / 20.0), p.y, k as Real / 10.0))
        .collect()
}

/// The JSON and the BIN chunk of a GLB, split by hand.
fn chunks(glb: &[u8]) -> (Value, &[u8]) {
    let u32_at = |o: usize| u32::from_le_bytes(glb[o..o + 4].try_into().unwrap()) as usize;
    assert_eq!(&glb[0..4], b"glTF");
    assert_eq!(u32_at(8), glb.len(), "the header's length is the file's");
    let json_len = u32_at(12);
    let json = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let bin = &glb[20 + json_len + 8..];
    (json, bin)
}

fn floats(json: &Value, bin: &[u8], accessor: u64) -> Vec<f32> {
    let a = &json["accessors"][accessor as usize];
    let v = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let off = v["byteOffset"].as_u64().unwrap() as usize;
    let len = v["byteLength"].as_u64().unwrap() as usize;
    bin[off..off + len]
        .chunks(4)
        .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
        .collect()
}

#[test]
fn a_static_body_and_a_morphing_garment_read_back_with_each_frames_offsets() {
    let b = body();
    let mut w = GlbWriter::in_memory(&header(&b)).unwrap();
    for k in 0..4 {
        w.frame(k as Real * 0.5, &frame(k), None);
    }
    let bytes = w.finish_to_vec().unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    assert_eq!(g.meshes().count(), 2);
    assert_eq!(g.animations().count(), 1);
    let (json, bin) = chunks(&bytes);
    let targets = json["meshes"][1]["primitives"][0]["targets"]
        .as_array()
        .unwrap();
    assert_eq!(targets.len(), 3, "every frame after the first is a target");
    for (k, t) in targets.iter().enumerate() {
        let got = floats(&json, bin, t["POSITION"].as_u64().unwrap());
        let want: Vec<f32> = frame(k + 1)
            .iter()
            .zip(&frame(0))
            .flat_map(|(a, b)| {
                let d = a - b;
                [d.x as f32, d.y as f32, d.z as f32]
            })
            .collect();
        assert_eq!(got, want, "target {k}");
    }
    // Frame 2 shows target 1 at full weight.
    let sampler = &json["animations"][0]["samplers"][0];
    let w = floats(&json, bin, sampler["output"].as_u64().unwrap());
    assert_eq!(&w[6..9], &[0.0, 1.0, 0.0]);
}

#[test]
fn a_file_writer_writes_what_an_in_memory_one_makes_and_leaves_no_spool() {
    let dir = std::env::temp_dir().join(format!("tryon-glb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("s.glb");
    let b = body();
    let mut file = GlbWriter::create(&path, &header(&b)).unwrap();
    let mut mem = GlbWriter::in_memory(&header(&b)).unwrap();
    for k in 0..5 {
        file.frame(k as Real, &frame(k), None);
        mem.frame(k as Real, &frame(k), None);
    }
    file.finish().unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), mem.finish_to_vec().unwrap());
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().collect();
    assert_eq!(names.len(), 1, "only the GLB is left");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_skinned_body_is_animated_per_joint() {
    let b = body();
    let names = vec!["root".to_string(), "tip".to_string()];
    let skinned = SkinnedExport {
        positions: &b,
        triangles: &TRI,
        joint_names: &names,
        parents: &[None, Some(0)],
        joint_rest: &[Vec3::zeros(), Vec3::y()],
        joints: &[[0, 1, 0, 0]; 3],
        weights: &[[0.5, 0.5, 0.0, 0.0]; 3],
    };
    let h = GlbHeader {
        body: BodyExport::Skinned(skinned),
        ..header(&b)
    };
    let mut w = GlbWriter::in_memory(&h).unwrap();
    let spin = [
        UnitQuat::identity(),
        UnitQuat::from_axis_angle(&Vec3::z_axis(), 0.3),
    ];
    // Frame 1 has the body's vertex 2 pressed 1 cm along x (a sparse morph target).
    let pressed = [(2u32, Vec3::new(0.01, 0.0, 0.0))];
    for k in 0..3 {
        let pose = FramePose {
            root_translation: Vec3::new(0.1 * k as Real, 0.0, 0.0),
            rotations: &spin[..k.min(2)],
            skin_offsets: if k == 1 { &pressed } else { &[] },
        };
        w.frame(k as Real, &frame(k), Some(pose));
    }
    let bytes = w.finish_to_vec().unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    assert_eq!(g.skins().count(), 1);
    // Two joint rotations, the root's translation, the body's and the garment's weights.
    assert_eq!(g.animations().next().unwrap().channels().count(), 5);
    let (json, bin) = chunks(&bytes);
    let targets = json["meshes"][0]["primitives"][0]["targets"]
        .as_array()
        .unwrap();
    assert_eq!(targets.len(), 3, "one body target per frame");
    let acc = |t: usize| &json["accessors"][targets[t]["POSITION"].as_u64().unwrap() as usize];
    // Frames with nothing pressed list vertex 0 at zero.
    for t in [0, 2] {
        assert_eq!(acc(t)["sparse"]["count"], 1);
        assert_eq!(
            (acc(t)["min"].clone(), acc(t)["max"].clone()),
            (json!([0.0, 0.0, 0.0]), json!([0.0, 0.0, 0.0]))
        );
    }
    let sparse = &acc(1)["sparse"];
    assert_eq!(sparse["count"], 1);
    let view = |v: &Value| {
        let bv = &json["bufferViews"][v["bufferView"].as_u64().unwrap() as usize];
        let at = bv["byteOffset"].as_u64().unwrap() as usize;
        &bin[at..at + bv["byteLength"].as_u64().unwrap() as usize]
    };
    assert_eq!(view(&sparse["indices"]), 2u32.to_le_bytes());
    let x: Vec<f32> = view(&sparse["values"])
        .chunks(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    assert_eq!(x, vec![0.01, 0.0, 0.0]);
    let mut bad = GlbWriter::in_memory(&h).unwrap();
    let far = [(7u32, Vec3::x())];
    let pose = FramePose {
        root_translation: Vec3::zeros(),
        rotations: &spin,
        skin_offsets: &far,
    };
    bad.frame(0.0, &frame(0), Some(pose));
    let e = bad.finish_to_vec().unwrap_err();
    assert!(e.to_string().contains("vertex 7"), "{e}");
    let mut no_pose = GlbWriter::in_memory(&h).unwrap();
    no_pose.frame(0.0, &frame(0), None);
    let e = no_pose.finish_to_vec().unwrap_err();
    assert!(e.to_string().contains("no pose"), "{e}");
}

#[test]
fn bad_frames_are_named_and_an_empty_run_is_refused() {
    let b = body();
    let run = |frames: &[(Real, Vec<Vec3>)]| {
        let mut w = GlbWriter::in_memory(&header(&b)).unwrap();
        for (t, g) in frames {
            w.frame(*t, g, None);
        }
        w.finish_to_vec().map(|_| ()).unwrap_err().to_string()
    };
    assert!(run(&[]).contains("no frame"));
    assert!(run(&[(0.0, frame(0)), (0.0, frame(1))]).contains("times must increase"));
    let short = frame(1)[..2].to_vec();
    assert!(run(&[(0.0, frame(0)), (1.0, short)]).contains("vertex count"));
    let mut nan = frame(1);
    nan[1].y = Real::NAN;
    assert!(run(&[(0.0, frame(0)), (1.0, nan)]).contains("not finite"));
    assert!(run(&[(0.0, frame(0)[..2].to_vec())]).contains("past the last vertex"));
}

#[test]
fn garments_worn_together_are_primitives_with_their_own_triangles_and_materials() {
    let b = body();
    // Two garments on four shared-numbered vertices: a triangle each.
    let tris = [[0, 1, 2], [1, 3, 2]];
    let names = ["slip".to_string(), "dress".to_string()];
    let h = GlbHeader {
        garment_triangles: &tris,
        garment_names: &names,
        triangle_garment: &[1, 0],
        ..header(&b)
    };
    let quad = |z: Real| {
        vec![
            Vec3::new(0.0, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(0.0, 1.0, z),
            Vec3::new(1.0, 1.0, z),
        ]
    };
    let mut w = GlbWriter::in_memory(&h).unwrap();
    w.frame(0.0, &quad(0.0), None);
    w.frame(0.5, &quad(0.1), None);
    let bytes = w.finish_to_vec().unwrap();
    let g = gltf::Gltf::from_slice(&bytes).unwrap();
    let garment = g.meshes().nth(1).unwrap();
    let prims: Vec<_> = garment.primitives().collect();
    assert_eq!(prims.len(), 2, "one primitive per garment");
    let (json, bin) = chunks(&bytes);
    for (k, (name, tri)) in [("slip", [1u32, 3, 2]), ("dress", [0, 1, 2])]
        .iter()
        .enumerate()
    {
        let m = prims[k].material().index().unwrap();
        assert_eq!(json["materials"][m]["name"], json!(name));
        let idx = &json["accessors"][prims[k].indices().unwrap().index()];
        let v = &json["bufferViews"][idx["bufferView"].as_u64().unwrap() as usize];
        let off = v["byteOffset"].as_u64().unwrap() as usize;
        let got: Vec<u32> = bin[off..off + 12]
            .chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(got, tri.to_vec(), "{name}'s triangle");
        assert_eq!(prims[k].morph_targets().count(), 1, "frames shared");
    }
    let colour = |k: usize| {
        prims[k]
            .material()
            .pbr_metallic_roughness()
            .base_color_factor()
    };
    assert_ne!(colour(0), colour(1), "told apart by colour");
    // A triangle of a garment not named is refused.
    let bad = GlbHeader {
        triangle_garment: &[0, 2],
        ..h
    };
    assert!(GlbWriter::in_memory(&bad).is_err());
}
