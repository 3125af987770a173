//! Integration tests over the public APIs: the drape scene end to end, the hard cases of the
//! foundation (a jumping body, a cloth that starts inside the body, bad meshes), determinism.

mod budgets;
mod caches;
mod cloth_cloth;
mod end_to_end;
mod folds;
mod hard_cases;
mod kimono;
mod makehuman_body;
mod real_assets;
mod resume;
mod retarget;
mod shirt;
mod tradeoff_scenes;

use body_collide::{
    BodyFollower, BodyMesh, ExactCollider, FollowParams, NearestVertexCollider, penetration_depths,
};
use cloth_dyn::{BuildClothError, ClothModel, ClothParams, ClothSim, IntegratorKind};
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, Vec3, is_finite};
use tryon_core::mesh::{Face, MeshError, PolyMesh, grid_xz};
use tryon_core::pose::Pose;
use tryon_core::shapes::icosphere;
use tryon_core::stages::{BodyModel, StillMotion};
use tryon_core::topology::TopologyError;
use tryon_pipeline::drape::drape_params;
use tryon_pipeline::{DrapeConfig, DrapeScene};

fn deepest(referee: &ExactCollider, x: &[Vec3]) -> Real {
    penetration_depths(referee, x)
        .into_iter()
        .fold(0.0, Real::max)
}

/// A body that holds still until time `at`, then stands moved by `jump` (a teleport).
struct JumpingBody {
    rest: Vec<Vec3>,
    jump: Vec3,
    at: Real,
}

impl BodyModel for JumpingBody {
    fn pose(&mut self, pose: &Pose, out: &mut BodyFrame) {
        out.time = pose.time;
        self.shape_at(pose, &mut out.positions);
    }
    fn shape_at(&self, pose: &Pose, out: &mut Vec<Vec3>) {
        let by = if pose.time > self.at {
            self.jump
        } else {
            Vec3::zeros()
        };
        out.clear();
        out.extend(self.rest.iter().map(|p| p + by));
    }
}

/// A small cloth draped on a sphere for `frames` frames by the product's frame loop, with body
/// following; in the next frame the sphere jumps by `jump`. Returns the scene and the sphere.
fn draped_then_jumping(n: usize, frames: usize, jump: Vec3) -> (DrapeScene, PolyMesh) {
    let mut cfg = DrapeConfig::new(n, IntegratorKind::Rk4);
    cfg.sphere_subdivisions = 3;
    cfg.drop_height = 0.35;
    let mut p = DrapeScene::pipeline(&cfg).unwrap();
    let sphere = p.body_mesh.clone();
    p.body = Box::new(JumpingBody {
        rest: sphere.positions.clone(),
        jump,
        at: p.frame_time(frames) + 0.5 / cfg.fps,
    });
    p.motion = Some(Box::new(StillMotion {
        joints: 1,
        duration: 10.0,
    }));
    let follower = BodyFollower::new(BodyMesh::new(&sphere).unwrap(), FollowParams::default());
    p.follower = Some(Box::new(follower));
    assert!(p.stages().contains(&"follow_body") && p.stages().contains(&"collider_update"));
    let mut scene = DrapeScene::started(cfg, p);
    for _ in 0..frames {
        scene.step();
    }
    (scene, sphere)
}

fn moved(sphere: &PolyMesh, by: Vec3) -> PolyMesh {
    let mut m = sphere.clone();
    for p in &mut m.positions {
        *p += by;
    }
    m
}

#[test]
fn drape_scene_stays_finite_outside_and_bounded() {
    let mut cfg = DrapeConfig::new(16, IntegratorKind::Rk4);
    cfg.duration = 1.0;
    let mut scene = DrapeScene::new(cfg).unwrap();
    let r = scene.run(|_| {});
    assert_eq!(r.frames, 60);
    assert!(
        scene
            .frame()
            .positions
            .iter()
            .chain(&scene.frame().velocities)
            .all(is_finite)
    );
    assert!(
        r.max_penetration <= 1e-3,
        "penetration {} m",
        r.max_penetration
    );
    assert!(r.max_stretch <= 1.10, "stretch {}", r.max_stretch);
    assert!(r.steps.contacts > 0, "the cloth should rest on the sphere");
    let lowest = scene
        .frame()
        .positions
        .iter()
        .map(|p| p.y)
        .fold(Real::INFINITY, Real::min);
    assert!(
        lowest < 0.0,
        "the cloth should hang below the sphere's top, lowest at {lowest}"
    );
    assert_eq!(
        r.steps.retries + r.steps.rollbacks + r.steps.non_finite_events,
        0
    );
}

#[test]
fn body_jumping_half_a_metre_leaves_no_particle_inside() {
    for jump in [
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.0, -0.2, 0.5),
    ] {
        let (mut scene, sphere) = draped_then_jumping(12, 40, jump);
        let referee = ExactCollider::new(&moved(&sphere, jump), 0.0).unwrap();
        let r = scene.step();
        let x = &scene.frame().positions;
        let depth = deepest(&referee, x);
        assert!(
            depth <= 1e-9,
            "after a jump of {jump:?} a particle is {depth} m inside"
        );
        assert!(x.iter().all(is_finite));
        assert_eq!(r.rollbacks, 0);
    }
}

#[test]
fn following_carries_the_resting_cloth_with_the_body() {
    let (mut scene, _) = draped_then_jumping(12, 60, Vec3::new(0.0, 0.5, 0.0));
    let top_before = scene
        .frame()
        .positions
        .iter()
        .map(|p| p.y)
        .fold(Real::NEG_INFINITY, Real::max);
    scene.step();
    let top_after = scene
        .frame()
        .positions
        .iter()
        .map(|p| p.y)
        .fold(Real::NEG_INFINITY, Real::max);
    // The cloth on the sphere's top rises with it (less one frame of fall).
    assert!(
        top_after - top_before > 0.45,
        "top went from {top_before} to {top_after}"
    );
}

#[test]
fn cloth_starting_inside_the_body_is_outside_after_one_step() {
    let sphere = icosphere(0.3, 3, Vec3::zeros());
    let referee = ExactCollider::new(&sphere, 0.0).unwrap();
    let params = drape_params(20);
    // A horizontal cloth through the sphere's middle.
    let model = ClothModel::build(&grid_xz(19, 19, 1.0, 1.0, 0.1), &params, vec![]).unwrap();
    let mut sim = ClothSim::new(model, params, IntegratorKind::Rk4);
    let mut frame = sim.initial_frame();
    assert!(
        deepest(&referee, &frame.positions) > 0.1,
        "the cloth must start inside"
    );
    let mut collider = NearestVertexCollider::new(&sphere, 0.002).unwrap();
    tryon_core::stages::ClothSolver::step_frame(&mut sim, &mut frame, 1.0 / 60.0, &mut collider);
    let depth = deepest(&referee, &frame.positions);
    assert!(depth <= 1e-9, "a particle is still {depth} m inside");
}

#[test]
fn bad_cloth_meshes_are_rejected_with_names() {
    let p = ClothParams::default();
    let mut zero_edge = grid_xz(2, 2, 1.0, 1.0, 0.0);
    zero_edge.positions[4] = zero_edge.positions[1];
    let e = ClothModel::build(&zero_edge, &p, vec![]).unwrap_err();
    assert!(
        matches!(
            e,
            BuildClothError::Topology(TopologyError::Mesh(MeshError::ZeroLengthEdge { .. }))
        ),
        "{e}"
    );
    assert!(e.to_string().contains("zero-length edge"), "{e}");

    let mut dup = grid_xz(2, 2, 1.0, 1.0, 0.0);
    dup.positions.push(dup.positions[8]);
    let e = ClothModel::build(&dup, &p, vec![]).unwrap_err();
    assert!(
        e.to_string().contains("vertices 8 and 9 are duplicates"),
        "{e}"
    );

    let mut degenerate = grid_xz(2, 2, 1.0, 1.0, 0.0);
    degenerate.positions.push(Vec3::new(0.75, 0.0, -0.5));
    degenerate.faces.push(Face::Tri([0, 1, 9]));
    let e = ClothModel::build(&degenerate, &p, vec![]).unwrap_err();
    assert!(e.to_string().contains("face 4 is degenerate"), "{e}");

    let nan = PolyMesh {
        positions: vec![Vec3::new(0.0, Real::NAN, 0.0), Vec3::x(), Vec3::z()],
        faces: vec![Face::Tri([0, 1, 2])],
    };
    let e = NearestVertexCollider::new(&nan, 0.0).unwrap_err();
    assert!(
        e.to_string()
            .contains("vertex 0 has a non-finite coordinate"),
        "{e}"
    );
}

#[test]
fn drape_is_deterministic() {
    let run = || {
        let mut cfg = DrapeConfig::new(10, IntegratorKind::SymplecticEuler);
        cfg.duration = 0.5;
        cfg.measure_penetration = false;
        let mut s = DrapeScene::new(cfg).unwrap();
        s.run(|_| {});
        s.frame().positions.clone()
    };
    assert_eq!(run(), run());
}

#[test]
fn stretch_guard_bounds_the_impact_peak_and_reports_its_retries() {
    let run = |guard: Option<Real>| {
        let mut cfg = DrapeConfig::new(24, IntegratorKind::Rk4);
        cfg.duration = 1.0;
        cfg.measure_penetration = false;
        // A weak limit (2 passes to 1.02, no long-range lines) that the impact overwhelms.
        cfg.params.strain_iterations = 2;
        cfg.params.max_strain = Some(1.02);
        cfg.params.long_range = false;
        cfg.params.stretch_guard = guard;
        DrapeScene::new(cfg).unwrap().run(|_| {})
    };
    let (free, guarded) = (run(None), run(Some(1.06)));
    assert!(
        free.max_stretch > 1.08,
        "without the guard the impact should overstretch ({})",
        free.max_stretch
    );
    assert!(
        guarded.max_stretch < free.max_stretch,
        "{} vs {}",
        guarded.max_stretch,
        free.max_stretch
    );
    assert!(guarded.steps.retries > 0 && free.steps.retries == 0);
}

/// A centred, symmetric drop stays centred and comes to rest. (Flexion springs with the bending
/// limit, and strain-limit corrections of a retried substep turned into velocity, pumped energy
/// into the sheet: at N = 64 it hopped and slid 0.18 m off the sphere within 2 s.)
#[test]
fn a_centred_drape_stays_centred_and_settles() {
    let cfg = DrapeConfig::new(64, IntegratorKind::Rk4);
    let mut scene = DrapeScene::new(cfg).unwrap();
    let mut last_kinetic = Real::INFINITY;
    let mut last_height = Real::NAN;
    let r = scene.run(|f| {
        last_kinetic = f.kinetic;
        last_height = f.centroid.y;
    });
    assert!(r.max_drift < 5e-3, "the cloth drifted {} m", r.max_drift);
    // Issue 2's accuracy targets (its time target is a benchmark's business).
    assert!(r.max_stretch <= 1.03, "max stretch {}", r.max_stretch);
    assert!(
        r.max_penetration <= 1e-3,
        "penetration {} m",
        r.max_penetration
    );
    assert!(
        last_kinetic < 5e-3,
        "still moving after 2 s: {last_kinetic} J"
    );
    // Resting on the sphere: its centroid below the top (0.3) and above the centre.
    assert!(
        (0.0..0.3).contains(&last_height),
        "centroid at {last_height}"
    );
}

/// Between two legs the nearest vertex of one leg is a local minimum of the distance for a point
/// inside the other: P1's hill-climb alone stays on the first leg and calls the point outside (the
/// skirt hem of makehuman-dress-walk went 43 mm into a calf this way). The collider's probes (the
/// VBD solver's contact planes) check the climb against a spatial hash of the body's vertices.
#[test]
fn a_point_inside_one_leg_is_found_while_its_track_is_on_the_other() {
    use tryon_core::stages::Collider;
    let body = body_model::Mannequin::new(&Default::default()).unwrap();
    let mesh = &body.mesh;
    let referee = ExactCollider::new(mesh, 0.0).unwrap();
    // The calves at 0.35 m: the innermost vertex of each leg (+x one leg, -x the other).
    let near = |side: Real| {
        mesh.positions
            .iter()
            .filter(|p| (p.y - 0.35).abs() < 0.03 && p.x * side > 0.0)
            .min_by(|a, b| (a.x * side).total_cmp(&(b.x * side)))
            .copied()
            .unwrap()
    };
    let (left, right) = (near(1.0), near(-1.0));
    assert!(left.x - right.x > 0.03, "the legs touch: {left} {right}");
    // Inside the -x calf by 2 cm, found from a track that starts at the +x calf's inner side.
    let inside = right + Vec3::new(-0.02, 0.0, 0.0);
    assert!(referee.signed_distance(&inside).unwrap() < -0.01);
    let mut c = NearestVertexCollider::new(mesh, 0.002).unwrap();
    let mut out = Vec::new();
    let mut points = vec![left + Vec3::new(-0.005, 0.0, 0.0)];
    c.probe_near(&points, &[0], 0.05, &mut out);
    assert!(out[0].distance > 0.0, "outside the +x calf: {:?}", out[0]);
    points[0] = inside;
    c.probe_near(&points, &[0], 0.05, &mut out);
    assert!(out[0].distance < -0.01, "probe: {:?}", out[0]);
    // The -x calf's inner side faces +x: out of the calf, not on through it.
    assert!(out[0].normal.x > 0.5, "normal {}", out[0].normal);
}
