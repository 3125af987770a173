//! Issue 24's in-range settings that never finished or exhausted memory: each is refused before
//! the costly stages are built, naming the key to change and the limit to raise.

use crate::tradeoff_scenes::scene;
use tryon_pipeline::budget::Limits;
use tryon_pipeline::build::AssembleError;
use tryon_pipeline::{Options, Pipeline, Scene};

fn refused(s: Scene) -> String {
    match Pipeline::new(s) {
        Err(e @ AssembleError::Budget(_)) => e.to_string(),
        Err(e) => panic!("refused for another reason: {e}"),
        Ok(p) => panic!("accepted: {:?}", p.estimate),
    }
}

#[test]
fn p1_with_spring_damping_1e9_or_stiffnesses_1e9_is_refused_by_its_substeps() {
    let p1 = "cloth.solver=\"p1\"";
    for sets in [
        vec![p1, "cloth.spring_damping=1e9"],
        vec![p1, "cloth.spring_damping=100"],
        vec![
            p1,
            "cloth.k_stretch=1e9",
            "cloth.k_shear=1e9",
            "cloth.k_bend=1e9",
        ],
    ] {
        let text = refused(scene("demo-dress-walk.toml", &sets));
        assert!(text.contains("substeps a frame"), "{sets:?}: {text}");
        assert!(text.contains("cloth.spring_damping"), "{text}");
        assert!(text.contains("--limit substeps=N"), "{text}");
    }
}

#[test]
fn an_hour_at_1000_fps_is_refused_by_its_frames_and_a_short_run_of_it_is_not() {
    let s = scene(
        "demo-dress-walk.toml",
        &["scene.fps=1000", "scene.duration=3600"],
    );
    let text = refused(s.clone());
    assert!(
        text.contains("frames: about 3600000") && text.contains("--frames"),
        "{text}"
    );
    let short = Options {
        frames: Some(10),
        ..Options::default()
    };
    let p = Pipeline::with_options(s, &short).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.estimate.frames, 10);
}

#[test]
fn a_256_sheet_refined_four_times_is_refused_before_it_is_refined() {
    let s = scene(
        "drape-sphere.toml",
        &["garment.particles=256", "effects.refine=4"],
    );
    let text = refused(s);
    assert!(
        text.contains("fine vertices: about 16") && text.contains("effects.refine"),
        "{text}"
    );
}

#[test]
fn a_raised_limit_lets_a_refused_scene_through() {
    let s = scene(
        "demo-dress-walk.toml",
        &["cloth.solver=\"p1\"", "cloth.spring_damping=3"],
    );
    let text = refused(s.clone());
    let needed: usize = text
        .split("about ")
        .nth(1)
        .and_then(|t| t.split(',').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no estimate in {text}"));
    let mut limits = Limits::default();
    limits.set(&format!("substeps={needed}")).unwrap();
    let options = Options {
        limits,
        ..Options::default()
    };
    let p = Pipeline::with_options(s, &options).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.estimate.substeps, needed);
}
