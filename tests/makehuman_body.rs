//! The MakeHuman body on the shared assets: mesh, skeleton and weights, measurement morphs,
//! skinning; and .mhclo garments fitted onto it.

use crate::real_assets::data;
use body_collide::{ExactCollider, MakeHumanBody, penetration_depths};
use tryon_core::Measurements;
use tryon_core::math::Real;
use tryon_io::{MhRig, load_makehuman};

#[test]
fn raw_body_mesh_rig_and_weights() {
    let a = load_makehuman(&data(), MhRig::CmuMb).unwrap();
    let b = MakeHumanBody::build(&a, None).unwrap();
    assert_eq!(b.body_vertices, 13_380);
    assert_eq!(b.rest.len(), 19_158);
    assert_eq!(b.skeleton.names.len(), 31);
    let g = b.girths;
    eprintln!("raw base girths: {g:?}");
    assert!((g.height - 1.67).abs() < 0.03, "height {}", g.height);
    // Plausible adult girths, in the order a tape finds them.
    assert!(g.hip_y < g.waist_y && g.waist_y < g.bust_y, "{g:?}");
    assert!(g.waist < g.hip && g.waist < g.bust, "{g:?}");
    for (i, w) in b.skin.weights.iter().enumerate() {
        let s: Real = w.iter().sum();
        assert!((s - 1.0).abs() < 1e-9, "vertex {i} weights sum {s}");
    }
}

#[test]
fn measurement_targets_morph_toward_requested_girths() {
    let a = load_makehuman(&data(), MhRig::CmuMb).unwrap();
    for m in [
        Measurements::default(),
        Measurements {
            height: 1.75,
            bust: 0.98,
            waist: 0.80,
            hip: 1.02,
            ..Measurements::default()
        },
    ] {
        let b = MakeHumanBody::build(&a, Some(&m)).unwrap();
        let g = b.girths;
        eprintln!("requested {m:?}\n got {g:?}, morphs {:?}", b.morphs);
        for (want, got) in [
            (m.height, g.height),
            (m.bust, g.bust),
            (m.waist, g.waist),
            (m.hip, g.hip),
        ] {
            assert!(
                (got - want).abs() <= 0.01 * want,
                "wanted {want}, got {got}"
            );
        }
        // Helper vertices moved with the body: the skirt helper still lies around the hips.
        assert!(
            b.rest[13_380..]
                .iter()
                .all(|p| p.iter().all(|x| x.is_finite()))
        );
    }
    let too_big = Measurements {
        waist: 1.2,
        hip: 1.3,
        bust: 1.25,
        ..Measurements::default()
    };
    let e = MakeHumanBody::build(&a, Some(&too_big)).unwrap_err();
    assert!(e.to_string().contains("can be morphed to"), "{e}");
}
