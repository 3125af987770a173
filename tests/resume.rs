//! Checkpoints and resume (issue 24): a run stopped after a checkpoint and resumed writes the same
//! bytes as one that ran through (stats.json but for its wall times), on scenes that between
//! them use every checkpointable stage: VBD, XPBD and P1's solver, the nearest-vertex, exact,
//! SDF and depth-map colliders, body following, bands, refinement, fine collision, wrinkles,
//! contact between layers, a grab, and the pipelined loop.

use std::path::{Path, PathBuf};
use tryon_pipeline::checkpoint::{Checkpoint, CheckpointError, FILE};
use tryon_pipeline::resume::{Checkpointing, ResumeError};
use tryon_pipeline::{Pipeline, Scene};

fn scene_file(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/scenes")
        .join(name)
}

fn demo(sets: &[&str]) -> Scene {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::parse_with_overrides(tryon_pipeline::DEMO_SCENE, Path::new("demo.toml"), &sets)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn from_file(name: &str, sets: &[&str]) -> Scene {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::load_with_overrides(&scene_file(name), &sets).unwrap_or_else(|e| panic!("{e}"))
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tryon-resume-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn scene_has(dir: &Path, file: &str) -> bool {
    dir.join(file).exists()
}

/// stats.json without what depends on the wall clock.
fn stats_without_times(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("stats.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let o = v.as_object_mut().unwrap();
    o.remove("stages");
    o.remove("loop_s");
    o.remove("frame_ms");
    v
}

/// Runs `scene` for `frames` frames straight through, and again stopped (as if killed) after
/// frame `stop` with a checkpoint every `every` frames, then resumed on a pipeline built anew;
/// the two output folders must hold the same bytes.
fn resumes_to_the_same_bytes(tag: &str, scene: Scene, frames: usize, every: usize, stop: usize) {
    let (whole, cut) = (
        scratch(&format!("{tag}-whole")),
        scratch(&format!("{tag}-cut")),
    );
    let c = Checkpointing {
        every,
        invocation: "test".into(),
    };
    let mut p = Pipeline::new(scene.clone()).unwrap_or_else(|e| panic!("{e}"));
    let w = p
        .run_checkpointed(&whole, Some(frames), &c, |_, _| {})
        .unwrap();
    assert_eq!(w.no_checkpoints, None, "{tag}");
    assert!(
        !whole.join(FILE).exists(),
        "{tag}: the checkpoint is removed at the end"
    );
    // Killed after frame `stop`: the progress callback unwinds out of the run.
    let mut p = Pipeline::new(scene.clone()).unwrap();
    let killed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        p.run_checkpointed(&cut, Some(frames), &c, |k, _| {
            if k == stop {
                std::panic::panic_any("killed");
            }
        })
    }));
    assert!(killed.is_err(), "{tag}: the run must have been stopped");
    assert!(!cut.join("scene.glb").exists(), "{tag}");
    // As if killed while writing the next checkpoint and an OBJ frame.
    std::fs::write(cut.join(".checkpoint.tryon.99999.tmp"), b"half").unwrap();
    if scene_has(&cut, "garment-obj") {
        std::fs::write(cut.join("garment-obj/.garment_00011.obj.99999.tmp"), b"v").unwrap();
    }
    let ck = Checkpoint::read(&cut).unwrap_or_else(|e| panic!("{tag}: {e}"));
    assert_eq!(ck.frame, stop / every * every, "{tag}: the last checkpoint");
    assert_eq!(ck.invocation, "test");
    let mut p = Pipeline::new(scene).unwrap();
    let r = p.resume_from(&cut, ck, every, |_, _| {});
    let r = r.unwrap_or_else(|e| panic!("{tag}: {e}"));
    assert_eq!(r.no_checkpoints, None);
    let mut files = vec![
        "scene.glb".to_string(),
        "preview.png".into(),
        "frames.jsonl".into(),
        "view.bin".into(),
    ];
    if scene_has(&whole, "run.usda") {
        files.push("run.usda".into());
    }
    if scene_has(&whole, "garment.pc2") {
        files.push("garment.pc2".into());
        files.push("run.gif".into());
        files.extend((0..=frames).map(|k| format!("garment-obj/garment_{k:05}.obj")));
    }
    for f in &files {
        let (a, b) = (std::fs::read(whole.join(f)), std::fs::read(cut.join(f)));
        let (a, b) = (a.unwrap(), b.unwrap_or_else(|e| panic!("{tag}: {f}: {e}")));
        assert!(
            a == b,
            "{tag}: {f} differs ({} and {} bytes)",
            a.len(),
            b.len()
        );
    }
    assert_eq!(
        stats_without_times(&whole),
        stats_without_times(&cut),
        "{tag}"
    );
    let jsonl = std::fs::read_to_string(cut.join("frames.jsonl")).unwrap();
    let judged = stats_without_times(&whole)["metrics"]["judged_frames"].as_u64();
    assert!(judged.is_some_and(|j| j >= 1), "{tag}: {judged:?}");
    assert_eq!(
        Some(jsonl.lines().count() as u64),
        judged,
        "{tag}: one line a judged frame"
    );
    let mut leftovers: Vec<_> = std::fs::read_dir(&cut)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') || n == FILE)
        .collect();
    if let Ok(objs) = std::fs::read_dir(cut.join("garment-obj")) {
        let hidden = objs.map(|e| e.unwrap().file_name().to_string_lossy().into_owned());
        leftovers.extend(hidden.filter(|n| n.starts_with('.')));
    }
    assert!(leftovers.is_empty(), "{tag}: left behind {leftovers:?}");
    let _ = (
        std::fs::remove_dir_all(&whole),
        std::fs::remove_dir_all(&cut),
    );
}

#[test]
fn the_demo_resumes_to_the_same_bytes() {
    // VBD, nearest-vertex collider, follower, PN refinement with fine collision.
    // With the caches for animation tools too.
    let s = demo(&[
        "output.pc2=true",
        "output.obj_sequence=true",
        "output.gif=true",
        "output.usd=true",
    ]);
    resumes_to_the_same_bytes("demo", s, 14, 4, 10);
}

#[test]
fn p1s_solver_with_wrinkles_and_the_exact_collider_resumes_to_the_same_bytes() {
    let s = demo(&[
        "cloth.solver=\"p1\"",
        "effects.wrinkles=true",
        "effects.body_collision=\"exact\"",
        "scene.pipelined=true",
    ]);
    resumes_to_the_same_bytes("p1", s, 9, 3, 7);
}

#[test]
fn xpbd_with_the_sdf_collider_resumes_to_the_same_bytes() {
    let s = demo(&["cloth.solver=\"xpbd\"", "effects.body_collision=\"sdf\""]);
    resumes_to_the_same_bytes("xpbd", s, 8, 3, 5);
}

#[test]
fn a_grabbed_cloth_on_an_object_resumes_to_the_same_bytes() {
    // P4: depth-map collider, a grab before and after the checkpoint.
    resumes_to_the_same_bytes("spot", from_file("cloth-on-spot.toml", &[]), 12, 5, 7);
}

#[test]
fn two_layers_with_bands_resume_to_the_same_bytes() {
    resumes_to_the_same_bytes("layered", from_file("layered-walk.toml", &[]), 8, 3, 6);
}

#[test]
fn a_makehuman_garment_on_a_captured_clip_resumes_to_the_same_bytes() {
    // Real assets: a skinned MakeHuman body on CMU 131_01, the casual suit's bands and pieces.
    crate::real_assets::data();
    let s = from_file("makehuman-casual-131.toml", &[]);
    resumes_to_the_same_bytes("casual", s, 6, 2, 5);
}

#[test]
fn a_checkpoint_of_another_scene_or_a_damaged_one_is_refused() {
    let dir = scratch("refused");
    let c = Checkpointing {
        every: 2,
        invocation: "test".into(),
    };
    let mut p = Pipeline::new(demo(&[])).unwrap();
    let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        p.run_checkpointed(&dir, Some(6), &c, |k, _| {
            if k == 3 {
                std::panic::panic_any("killed");
            }
        })
    }));
    let ck = Checkpoint::read(&dir).unwrap();
    let mut other = Pipeline::new(demo(&["effects.friction=0.4"])).unwrap();
    let e = other.resume_from(&dir, ck, 2, |_, _| {}).unwrap_err();
    assert!(
        matches!(
            e,
            ResumeError::Checkpoint(CheckpointError::SceneChanged { .. })
        ),
        "{e}"
    );
    assert!(e.to_string().contains("the scene changed"), "{e}");
    let path = dir.join(FILE);
    let mut bytes = std::fs::read(&path).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0x40;
    std::fs::write(&path, &bytes).unwrap();
    let e = Checkpoint::read(&dir).unwrap_err();
    assert!(matches!(e, CheckpointError::Damaged { .. }), "{e}");
    // A checkpoint of an earlier layout (its magic) and one cut after the magic are refused.
    let mut old = bytes.clone();
    old[..8].copy_from_slice(b"TRYONCK4");
    std::fs::write(&path, &old).unwrap();
    let e = Checkpoint::read(&dir).unwrap_err();
    assert!(matches!(e, CheckpointError::NotACheckpoint { .. }), "{e}");
    std::fs::write(&path, &bytes[..8]).unwrap();
    let e = Checkpoint::read(&dir).unwrap_err();
    assert!(matches!(e, CheckpointError::NotACheckpoint { .. }), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
