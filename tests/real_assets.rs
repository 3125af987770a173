//! The readers on the shared real assets (../shared/data, or TRYON_DATA): counts and facts its
//! README states, read with the project's own readers.

use std::path::PathBuf;
use tryon_core::math::Real;
use tryon_io::{read_binding, read_bvh, read_mhskel, read_mhw, read_obj, read_target};

/// The shared asset folder; tests that need it fail (not skip) when it is missing.
pub fn data() -> PathBuf {
    tryon_io::data_root_from(std::path::Path::new(env!("CARGO_MANIFEST_DIR"))).expect(
        "the shared asset folder was not found: put ../shared/data beside the checkout or set TRYON_DATA",
    )
}

#[test]
fn base_mesh_keeps_order_units_and_groups() {
    let m = read_obj(&data().join("makehuman/base.obj")).unwrap();
    assert_eq!(m.positions.len(), 19_158);
    assert_eq!(m.faces.len(), 18_486);
    assert_eq!(m.face_uvs.len(), m.faces.len());
    let body = m.group_vertices("body");
    assert_eq!(body.first(), Some(&0));
    assert_eq!(body.last(), Some(&13_379));
    assert_eq!(body.len(), 13_380);
    // Decimetres: the raw base is 1.67 m tall, feet at y = -8.4.
    let (lo, hi) = m.bounds().unwrap();
    assert!((hi.y - lo.y - 16.7).abs() < 0.3, "{lo:?} {hi:?}");
    assert!((lo.y + 8.4).abs() < 0.2, "{lo:?}");
}

#[test]
fn skeletons_weights_and_targets() {
    let d = data();
    let s = read_mhskel(&d.join("makehuman/default.mhskel")).unwrap();
    assert_eq!(s.bones.len(), 163);
    for (i, b) in s.bones.iter().enumerate() {
        assert!(
            b.parent.is_none_or(|p| p < i),
            "{} before its parent",
            b.name
        );
    }
    let cmu = read_mhskel(&d.join("makehuman-assets/rigs/cmu_mb.mhskel")).unwrap();
    assert_eq!(cmu.bones.len(), 31);
    assert_eq!(cmu.bones[0].name, "Hips");
    let mut unknown = vec![];
    for b in &cmu.bones {
        assert!(
            b.reference.iter().all(|r| s.index(r).is_some()),
            "{}",
            b.name
        );
        unknown.extend(b.weights_reference.iter().filter(|r| s.index(r).is_none()));
    }
    // The one slip in cmu_mb: the big toe has two bones in the default rig, not three.
    assert_eq!(unknown, ["toe1-3.L", "toe1-3.R"]);
    let w = read_mhw(&d.join("makehuman/default_weights.mhw")).unwrap();
    assert!(w.bones.iter().all(|(b, _)| s.index(b).is_some()));
    assert!(
        w.bones
            .iter()
            .flat_map(|(_, l)| l)
            .all(|(v, _)| *v < 19_158)
    );
    let mut targets = 0;
    for dir in ["measure", "macrodetails"] {
        for e in std::fs::read_dir(d.join("makehuman/targets").join(dir)).unwrap() {
            let t = read_target(&e.unwrap().path()).unwrap();
            assert!(!t.offsets.is_empty() && t.offsets.iter().all(|(v, _)| *v < 19_158));
            // Offsets are metres: no measurement target moves a vertex by 20 cm.
            assert!(t.offsets.iter().all(|(_, o)| o.norm() < 0.2), "{}", t.name);
            targets += 1;
        }
    }
    assert_eq!(targets, 46);
}

#[test]
fn garment_and_proxy_bindings_match_their_meshes() {
    let d = data().join("makehuman-assets");
    for (bind, verts) in [
        (
            "clothes/female_elegantsuit01/female_elegantsuit01.mhclo",
            2_205,
        ),
        (
            "clothes/female_casualsuit02/female_casualsuit02.mhclo",
            2_876,
        ),
        ("proxymeshes/proxy741/proxy741.proxy", 741),
    ] {
        let path = d.join(bind);
        let b = read_binding(&path).unwrap();
        let obj = read_obj(&path.with_file_name(&b.obj_file)).unwrap();
        assert_eq!(b.refs.len(), verts, "{bind}");
        assert_eq!(obj.positions.len(), verts, "{bind}");
        assert!(b.scales.iter().all(Option::is_some));
        assert!(b.refs.iter().flatten().all(|v| *v < 19_158));
        for w in &b.weights {
            let s: Real = w.iter().sum();
            assert!((s - 1.0).abs() < 0.02, "{bind}: weights sum {s}");
        }
    }
}

#[test]
fn cmu_clips_read_with_both_naming_schemes_and_line_ends() {
    let d = data().join("cmu-mocap-bvh");
    let a = read_bvh(&d.join("10_04.bvh"), None).unwrap();
    assert_eq!(a.frames.len(), 550);
    assert!((a.fps() - 120.0).abs() < 0.01);
    assert_eq!(a.unit, 0.056444, "CMU units should be recognised");
    assert!(a.skeleton.names.iter().any(|n| n == "LeftUpLeg"));
    let b = read_bvh(&d.join("131_01.bvh"), None).unwrap();
    assert_eq!(b.frames.len(), 994);
    assert!(b.skeleton.names.iter().any(|n| n == "LeftHip"));
    // Hip height about 17 units, about 1 m.
    let hip = a.frames[1].root_translation.y;
    assert!((0.85..1.15).contains(&hip), "hip at {hip} m");
    for clip in [&a, &b] {
        assert!(clip.frames.iter().all(|f| {
            f.root_translation.iter().all(|x| x.is_finite())
                && f.local_rotations
                    .iter()
                    .all(|q| q.coords.iter().all(|x| x.is_finite()))
        }));
    }
    let pose = read_bvh(&data().join("makehuman/poses/benchmark.bvh"), None).unwrap();
    assert_eq!(pose.unit, 0.1, "MakeHuman poses are in decimetres");
}
