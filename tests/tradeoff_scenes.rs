//! Issue 6 end to end: P4's cloth-on-spot scene runs and its fine correction lowers penetration;
//! the pipelined loop (frame n+1's coarse step beside frame n's surface stages) gives exactly the
//! sequential loop's frames; every collider and integrator a scene can name runs the demo finite;
//! scene overrides and the new keys are checked with errors that name them.

use std::path::{Path, PathBuf};
use tryon_pipeline::{Pipeline, Scene};

/// A scene of data/scenes with `sets` applied.
pub(crate) fn scene(file: &str, sets: &[&str]) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/scenes")
        .join(file);
    // Every frame judged, so two runs' figures compare.
    let sets: Vec<String> = (sets.iter().map(|s| s.to_string()))
        .chain(["output.referee_share=1".to_string()])
        .collect();
    Scene::load_with_overrides(&path, &sets).unwrap_or_else(|e| panic!("{e}"))
}

fn run(s: Scene, frames: usize) -> tryon_pipeline::RunOutput {
    let mut p = Pipeline::new(s).unwrap_or_else(|e| panic!("{e}"));
    p.run(Some(frames), |_, _| {})
}

#[test]
fn pipelined_loop_gives_the_sequential_frames() {
    let a = run(scene("cloth-on-spot.toml", &["scene.pipelined=false"]), 12);
    let b = run(scene("cloth-on-spot.toml", &["scene.pipelined=true"]), 12);
    assert_eq!(a.frames.len(), b.frames.len());
    for (fa, fb) in a.frames.iter().zip(&b.frames) {
        assert_eq!(fa.time, fb.time);
        assert_eq!(fa.garment, fb.garment, "frame at t = {}", fa.time);
    }
    assert_eq!(
        a.stats.metrics.max_penetration_m,
        b.stats.metrics.max_penetration_m
    );
}

#[test]
fn the_spot_scene_drapes_and_the_depth_maps_correct_the_fine_surface() {
    // 1.2 s: the cloth has landed on spot and the table (before the grab at 1.5 s).
    let off = run(
        scene("cloth-on-spot.toml", &["effects.fine_collision=false"]),
        36,
    );
    let on = run(scene("cloth-on-spot.toml", &[]), 36);
    for out in [&off, &on] {
        assert!(
            out.frames
                .iter()
                .all(|f| f.garment.iter().all(|x| x.iter().all(|c| c.is_finite())))
        );
        // Resting on something: no vertex fell below the table top (y = 0) by more than 1 cm.
        let last = &out.frames[out.frames.len() - 1].garment;
        let lowest = last.iter().map(|x| x.y).fold(f64::INFINITY, f64::min);
        assert!(lowest > -0.01, "lowest vertex at y = {lowest}");
    }
    let (a, b) = (&off.stats.metrics, &on.stats.metrics);
    assert!(
        b.share_over_1mm <= a.share_over_1mm && b.p99_penetration_m <= a.p99_penetration_m,
        "depth maps: share {} -> {}, p99 {} -> {}",
        a.share_over_1mm,
        b.share_over_1mm,
        a.p99_penetration_m,
        b.p99_penetration_m
    );
    assert!(on.stats.stages.contains_key("fine_collision"));
    assert!(!off.stats.stages.contains_key("fine_collision"));
}

/// P1's tracker on an object standing on a table (two pieces of body): every cloth particle keeps a
/// track on each piece. (When the only extra track was on the piece the first track was not
/// started on, the cloth starting nearest spot had no track on the table and fell through it.)
#[test]
fn nearest_vertex_tracking_holds_the_cloth_on_spots_table() {
    let out = run(
        scene(
            "cloth-on-spot.toml",
            &[
                "effects.body_collision=\"nearest_vertex\"",
                "effects.refine=0",
            ],
        ),
        36,
    );
    for (k, f) in out.frames.iter().enumerate() {
        let lowest = f.garment.iter().map(|x| x.y).fold(f64::INFINITY, f64::min);
        assert!(
            lowest > -0.005,
            "frame {k}: lowest particle at y = {lowest}"
        );
    }
    assert!(
        out.stats.metrics.p99_penetration_m < 1e-3,
        "p99 penetration {}",
        out.stats.metrics.p99_penetration_m
    );
}

#[test]
fn the_grab_drags_a_corner_along_its_path() {
    let out = run(scene("cloth-on-spot.toml", &[]), 120);
    // The grab (t = 1.5 s, frame 45) takes the coarse particle then nearest (-0.4, 0, -0.4) and
    // moves it by the path's displacement, (-0.25, +0.25, -0.15) by t = 3 s, held to the end.
    // Coarse particles come first in the fine surface's vertices.
    let coarse = 24 * 24;
    let before = &out.frames[44].garment[..coarse];
    let start = tryon_core::math::Vec3::new(-0.4, 0.0, -0.4);
    let k = (0..coarse)
        .min_by(|&a, &b| {
            (before[a] - start)
                .norm_squared()
                .total_cmp(&(before[b] - start).norm_squared())
        })
        .unwrap();
    let expected = before[k] + tryon_core::math::Vec3::new(-0.25, 0.25, -0.15);
    let last = &out.frames[out.frames.len() - 1].garment;
    assert!(
        (last[k] - expected).norm() < 0.01,
        "grabbed particle {k} ended at {:?}, the path puts it at {expected:?}",
        last[k]
    );
    assert_eq!(out.stats.metrics.non_finite_events, 0);
}

#[test]
fn every_collider_and_integrator_runs_the_demo_finite() {
    for sets in [
        [
            "effects.body_collision=\"sdf\"",
            "cloth.p1.integrator=\"rk4\"",
        ],
        [
            "effects.body_collision=\"depth_maps\"",
            "cloth.p1.integrator=\"rk4\"",
        ],
        [
            "effects.body_collision=\"exact\"",
            "cloth.p1.integrator=\"symplectic_euler\"",
        ],
        [
            "effects.body_collision=\"nearest_vertex\"",
            "cloth.p1.integrator=\"implicit_euler\"",
        ],
    ] {
        let s = scene("demo-dress-walk.toml", &sets);
        let out = run(s, 10);
        let m = &out.stats.metrics;
        assert_eq!(m.non_finite_events, 0, "{sets:?}");
        assert!(
            m.max_penetration_m < 0.02,
            "{sets:?}: {}",
            m.max_penetration_m
        );
        assert!(m.max_stretch < 1.5, "{sets:?}: {}", m.max_stretch);
    }
}

fn err(file: &str, sets: &[&str]) -> String {
    let path: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/scenes")
        .join(file);
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    match Scene::load_with_overrides(&path, &sets) {
        Ok(_) => panic!("accepted {sets:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn overrides_and_new_keys_are_checked() {
    let e = err("demo-dress-walk.toml", &["effects.refine"]);
    assert!(e.contains("--set") && e.contains("table.key=value"), "{e}");
    let e = err("demo-dress-walk.toml", &["effects.sdf.resolution=4"]);
    assert!(
        e.contains("effects.sdf.resolution") && e.contains("8..=512"),
        "{e}"
    );
    let e = err("demo-dress-walk.toml", &["effects.depth_maps.resolution=5"]);
    assert!(e.contains("effects.depth_maps.resolution"), "{e}");
    let e = err("demo-dress-walk.toml", &["effects.fine_collider=\"none\""]);
    assert!(e.contains("fine_collision = false"), "{e}");
    let e = err(
        "demo-dress-walk.toml",
        &["effects.body_collision=\"magic\""],
    );
    assert!(e.contains("magic") && e.contains("depth_maps"), "{e}");
    let e = err(
        "cloth-on-spot.toml",
        &["garment.grab=[[2.0, 0, 0, 0], [1.0, 0, 0, 0]]"],
    );
    assert!(e.contains("garment.grab") && e.contains("rising"), "{e}");
    let e = err("demo-dress-walk.toml", &["body.table=1.0"]);
    assert!(e.contains("body.table") && e.contains("object"), "{e}");
    let s = scene("cloth-on-spot.toml", &["body.file=\"nope/missing.obj\""]);
    let e = Pipeline::new(s)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("body.file") && e.contains("missing.obj"), "{e}");
}
