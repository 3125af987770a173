//! The MakeHuman body on the shared assets: mesh, skeleton and weights, measurement morphs,
//! skinning; and .mhclo garments fitted onto it.

use crate::real_assets::data;
use body_collide::{ExactCollider, penetration_depths};
use body_model::MakeHumanBody;
use tryon_core::Measurements;
use tryon_core::math::Real;
use tryon_io::{MhRig, load_makehuman};

#[test]
fn raw_body_mesh_rig_and_weights() {
    let a = load_makehuman(&data(), MhRig::CmuMb).unwrap();
    let b = MakeHumanBody::build(&a, 0.5, None).unwrap();
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
        let b = MakeHumanBody::build(&a, 0.5, Some(&m)).unwrap();
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
    let e = MakeHumanBody::build(&a, 0.5, Some(&too_big)).unwrap_err();
    assert!(e.to_string().contains("can be morphed to"), "{e}");
}

/// Fits both shared garments on `body` (binding alone, or binding then placement outside) and
/// returns (name, vertices, share more than 5 mm inside).
fn fitted_inside_share(body: &MakeHumanBody, outside: bool) -> Vec<(String, usize, Real)> {
    let referee = ExactCollider::new(&body.mesh(), 0.0).unwrap();
    let mut placer = ExactCollider::new(&body.mesh(), 0.002).unwrap();
    let clothes = data().join("makehuman-assets/clothes");
    ["female_elegantsuit01", "female_casualsuit02"]
        .iter()
        .map(|g| {
            let path = clothes.join(g).join(format!("{g}.mhclo"));
            let b = tryon_io::read_binding(&path).unwrap();
            let obj = tryon_io::read_obj(&path.with_file_name(&b.obj_file)).unwrap();
            let mesh = if outside {
                garment_fit::fit_garment_outside(&b, &obj, &body.rest, &mut placer)
                    .unwrap()
                    .0
            } else {
                garment_fit::fit_garment(&b, &obj, &body.rest).unwrap()
            };
            let d = penetration_depths(&referee, &mesh.positions);
            let inside = d.iter().filter(|d| **d > 0.005).count();
            (g.to_string(), d.len(), inside as Real / d.len() as Real)
        })
        .collect()
}

#[test]
fn garments_fit_outside_raw_and_morphed_bodies() {
    let a = load_makehuman(&data(), MhRig::CmuMb).unwrap();
    let morphed = Measurements {
        height: 1.75,
        bust: 0.98,
        waist: 0.80,
        hip: 1.02,
        ..Measurements::default()
    };
    for (gender, m) in [
        (0.5, None),
        (0.0, None),
        (0.0, Some(Measurements::default())),
        (0.5, Some(morphed)),
    ] {
        let body = MakeHumanBody::build(&a, gender, m.as_ref()).unwrap();
        let bound = fitted_inside_share(&body, false);
        let fitted = fitted_inside_share(&body, true);
        for ((g, n, before), (_, _, after)) in bound.iter().zip(&fitted) {
            eprintln!(
                "{g} on gender {gender}, {m:?}: {n} vertices more than 5 mm inside: binding {:.2}%, fitted {:.2}%",
                before * 100.0,
                after * 100.0
            );
            // The binding alone is close (the data's README: at most 1.3% on the raw base).
            assert!(
                *before <= 0.02,
                "{g}: binding leaves {:.2}% inside",
                before * 100.0
            );
            assert!(
                *after <= 0.01,
                "{g}: {:.2}% inside after fitting",
                after * 100.0
            );
        }
    }
}

#[test]
fn makehuman_scenes_run_finite_and_report_penetration_and_stretch() {
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes");
    for (name, frames) in [("makehuman-dress-walk", 14), ("makehuman-casual-131", 14)] {
        let scene = tryon_pipeline::Scene::load(&scenes.join(format!("{name}.toml"))).unwrap();
        let mut p = tryon_pipeline::Pipeline::new(scene).unwrap();
        assert!(
            p.stages().contains(&"motion") && p.stages().contains(&"skinning"),
            "{:?}",
            p.stages()
        );
        let out = p.run(Some(frames), |_, _| {});
        assert_eq!(
            out.frames.len(),
            frames + 1,
            "the placed garment, then one record per frame"
        );
        for f in &out.frames {
            assert!(f.garment.iter().all(|x| x.iter().all(|c| c.is_finite())));
        }
        let m = &out.stats.metrics;
        eprintln!(
            "{name}: {frames} frames, penetration max {:.1} mm, stretch max {:.3}, mean {:.3}",
            m.max_penetration_m * 1e3,
            m.max_stretch,
            m.mean_stretch
        );
        assert!(m.max_penetration_m.is_finite() && m.max_stretch >= 1.0);
        assert_eq!(m.non_finite_events, 0);
    }
}

/// The walk's scene as shipped: the exact collider with the swept test holds the coarse cloth,
/// and P1's refined surface is raised out of the body by it. Over the walk's first 40 frames the
/// surface stays out of the body (measured 0 mm over 90 frames). With the nearest-vertex
/// collider and the coarse cloth as output (the scene before session 44) the same frames reached
/// 3.3 mm (frame 26), and skin showed through between the particles.
#[test]
fn the_elegant_suit_walking_stays_out_of_the_body_on_its_refined_surface() {
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes");
    let scene = tryon_pipeline::Scene::load(&scenes.join("makehuman-dress-walk.toml")).unwrap();
    let mut p = tryon_pipeline::Pipeline::new(scene).unwrap();
    for stage in ["refine", "fine_collision"] {
        assert!(p.stages().contains(&stage), "{:?}", p.stages());
    }
    let out = p.run(Some(40), |_, _| {});
    let m = &out.stats.metrics;
    eprintln!(
        "penetration max {:.2} mm, p99 {:.2} mm, stretch max {:.3}, detached {}",
        m.max_penetration_m * 1e3,
        m.p99_penetration_m * 1e3,
        m.max_stretch,
        m.detached_share
    );
    assert_eq!(m.non_finite_events, 0);
    assert!(m.max_penetration_m <= 0.002, "{} m", m.max_penetration_m);
    assert!(m.p99_penetration_m <= 0.0005, "{} m", m.p99_penetration_m);
    assert_eq!(m.detached_share, 0.0);
    assert_eq!(m.rollbacks, 0);
}

/// Every parallel stage of a frame (skinning, the body press, the collider's probes and
/// projection, the sweeps, the swept test) collects its results in order, so a real run gives
/// bitwise the same frames on one thread as on two.
#[test]
fn a_makehuman_walk_gives_the_same_frames_on_one_and_two_threads() {
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes");
    // Two seconds into CMU 131_01, where the arms swing against the chest and the press acts.
    let sets = [
        "motion.file=\"cmu-mocap-bvh/131_01.bvh\"".to_string(),
        "motion.start=2.0".to_string(),
        "motion.ease_in=0".to_string(),
    ];
    let file = scenes.join("makehuman-dress-walk.toml");
    let scene = tryon_pipeline::Scene::load_with_overrides(&file, &sets).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let scene = scene.clone();
        pool.install(move || {
            let mut p = tryon_pipeline::Pipeline::new(scene).unwrap();
            let out = p.run(Some(8), |_, _| {});
            let m = &out.stats;
            (out.frames, m.metrics.body_pressed_per_pose, m.retarget)
        })
    };
    let one = run(1);
    // The press did act, so its parallel part was exercised.
    assert!(one.1.is_some_and(|m| m > 0.0), "{:?}", one.1);
    // stats.json says what retargeting changed: this clip raises a hand to the face and the
    // arms are turned off the hips and head in some frames, by at most the 45-degree cap.
    assert!(
        one.2
            .is_some_and(|r| r.arm_frames_moved > 0 && r.max_arm_turn_deg <= 45.0),
        "{:?}",
        one.2
    );
    assert!(run(2) == one, "two threads differ from one");
}

/// Shorts on a running body (131_01 from its start) ratchet down at every stride unless their
/// waistband grips: without bands they were below the knees by frame 85 and on the floor by 100.
/// With bands every garment vertex stays near the body through frame 110.
#[test]
fn elastic_bands_keep_shorts_on_a_running_body() {
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes");
    let scene = tryon_pipeline::Scene::load(&scenes.join("makehuman-casual-131.toml")).unwrap();
    let mut p = tryon_pipeline::Pipeline::new(scene).unwrap();
    let bands = p.bands.as_ref().expect("the casual suit has bands");
    // Shorts waistband (56 vertices), collar (20) and both sleeve cuffs (21 each), before any
    // vertex fails to bind.
    assert!(
        (100..=118).contains(&bands.vertices.len()),
        "{} band vertices",
        bands.vertices.len()
    );
    assert!(p.stages().contains(&"bands"), "{:?}", p.stages());
    let mut st = p.start();
    let mut timers = tryon_pipeline::run::Timers::default();
    for k in 1..=110 {
        p.advance(&mut st, p.frame_time(k), &mut timers);
        let body = &st.body_frame.positions;
        let (mut lo, mut hi) = (body[0], body[0]);
        for x in body {
            lo = lo.inf(x);
            hi = hi.sup(x);
        }
        let off = p
            .cloth
            .positions
            .iter()
            .filter(|x| (0..3).any(|a| x[a] < lo[a] - 0.1 || x[a] > hi[a] + 0.1))
            .count();
        assert_eq!(
            off, 0,
            "frame {k}: {off} garment vertices left the body's box"
        );
    }
}

/// Trousers, shorts or a skirt modelled with ease at the waist (here: the casual suit with its
/// band gap cut to 1 mm, so that its waistband is no longer a band) have nothing to hang from.
/// Without the waist rule they slid off on the walk (CMU 10_04): 6% of the garment more than
/// 10 cm from where it started by frame 30, 20% by frame 60, 42% by frame 90, the shorts on the
/// floor at frame 150 (`--set garment.waist_gap=0`). Held as a belt holds them, nothing leaves the body.
#[test]
fn a_waist_looser_than_the_band_gap_is_held_as_a_belt_holds_it() {
    use tryon_pipeline::{Pipeline, Scene};
    let file = crate::end_to_end::repo().join("data/scenes/makehuman-casual-131.toml");
    let sets = [
        "garment.band_gap=0.001".to_string(),
        "motion.file=\"cmu-mocap-bvh/10_04.bvh\"".to_string(),
    ];
    let scene = Scene::load_with_overrides(&file, &sets).unwrap_or_else(|e| panic!("{e}"));
    let mut p = Pipeline::new(scene).unwrap();
    let bands = p.bands.as_ref().expect("the shorts' waist is held");
    // The shorts' top loop (56 vertices), and no loop of the T-shirt, which reaches the shoulders.
    assert!(
        (40..=60).contains(&bands.vertices.len()),
        "{} held vertices",
        bands.vertices.len()
    );
    let out = p.run(Some(60), |_, _| {});
    let m = &out.stats.metrics;
    assert_eq!(m.non_finite_events, 0);
    assert_eq!(
        m.detached_share, 0.0,
        "a share of the garment left the body: {m:?}"
    );
}

/// Winding number of the closed surface `tris` over `x` around `p`: about 1 inside one layer of
/// it, 2 where two parts overlap, 0 outside (Van Oosterom and Strackee's solid angle).
fn winding(p: &tryon_core::math::Vec3, x: &[tryon_core::math::Vec3], tris: &[[u32; 3]]) -> Real {
    let mut sum = 0.0;
    for t in tris {
        let [a, b, c] = t.map(|v| x[v as usize] - p);
        let (la, lb, lc) = (a.norm(), b.norm(), c.norm());
        let num = a.dot(&b.cross(&c));
        let den = la * lb * lc + a.dot(&b) * lc + a.dot(&c) * lb + b.dot(&c) * la;
        sum += 2.0 * num.atan2(den);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// On makehuman-dress-walk (CMU 10_04 retargeted onto the body), linear blend skinning sinks the
/// swinging arms into the chest's sides by a centimetre or more. Points one cloth thickness (4 mm)
/// off the upper arms' skin below the armpit's crease then lie inside the chest: the body's winding number there is about 1
/// (the nearest-surface referee cannot see it: the nearest surface is the arm's, and the point is
/// outside that). With the parts pressed apart two thicknesses, such points are outside.
#[test]
fn arms_swinging_against_the_chest_are_pressed_out_of_it() {
    use tryon_core::math::vertex_normals;
    use tryon_pipeline::{Pipeline, Scene};
    let scene = crate::end_to_end::repo().join("data/scenes/makehuman-dress-walk.toml");
    let inside = |press: bool| {
        let set = [format!("effects.body_press={press}")];
        let p = Pipeline::new(Scene::load_with_overrides(&scene, &set).unwrap()).unwrap();
        let rig = p.body.rig().unwrap();
        let upper_arm = |v: usize| {
            let (j, w) = (rig.joints[v], rig.weights[v]);
            let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap();
            let name = &rig.skeleton.names[j[k] as usize];
            // Below the armpit's crease: past 40% of the bone from the shoulder joint at rest.
            let side = match name.as_str() {
                "LeftArm" => "Left",
                "RightArm" => "Right",
                _ => return false,
            };
            let joint = |n: String| rig.skeleton.names.iter().position(|x| *x == n).unwrap();
            let (a, b) = (joint(format!("{side}Arm")), joint(format!("{side}ForeArm")));
            let bone = rig.joint_rest[b] - rig.joint_rest[a];
            (rig.rest_positions[v] - rig.joint_rest[a]).dot(&bone) >= 0.4 * bone.norm_squared()
        };
        let tris = p.body_mesh.triangulate().0;
        let mut count = 0;
        let mut pose = tryon_core::pose::Pose::rest(rig.skeleton.names.len());
        for k in (20..160).step_by(28) {
            p.motion
                .as_ref()
                .unwrap()
                .sample(p.frame_time(k), &mut pose);
            let mut x = Vec::new();
            p.body.shape_at(&pose, &mut x);
            let mut n = Vec::new();
            vertex_normals(&x, &tris, &mut n);
            count += (0..x.len())
                .filter(|&v| upper_arm(v))
                .filter(|&v| winding(&(x[v] + n[v] * 0.004), &x, &tris) > 0.5)
                .count();
        }
        count
    };
    let (before, after) = (inside(false), inside(true));
    eprintln!("points inside the chest over 5 frames: {before} -> {after}");
    assert!(
        before >= 50,
        "the skinned arms must sink into the chest: {before}"
    );
    assert!(
        after * 10 <= before,
        "{after} of {before} points still inside"
    );
}
