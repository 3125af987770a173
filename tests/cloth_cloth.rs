//! Issue 21's hard cases for the cloth's contact with itself: a sheet dropped on a ball folds
//! onto itself as it slides off, and no two of its triangles may cross in any frame (judged by
//! the referee, `tryon_pipeline::crossings`, which shares no code with the solver's contacts).

use tryon_pipeline::{Pipeline, Scene};

fn drape(n: u32, self_collision: bool) -> tryon_pipeline::RunOutput {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes/drape-sphere.toml");
    let sets: Vec<String> = [
        "cloth.solver=\"vbd\"".to_string(),
        format!("garment.particles={n}"),
        format!("effects.self_collision={self_collision}"),
    ]
    .into();
    let scene = Scene::load_with_overrides(&file, &sets).unwrap_or_else(|e| panic!("{e}"));
    let mut p = Pipeline::new(scene).unwrap_or_else(|e| panic!("{e}"));
    p.run(Some(150), |_, _| {})
}

#[test]
fn a_sheet_falling_into_folds_on_a_ball_never_passes_through_itself() {
    let on = drape(32, true);
    for f in &on.frames {
        assert!(f.garment.iter().all(|x| x.iter().all(|c| c.is_finite())));
    }
    let m = &on.stats.metrics;
    assert_eq!(m.non_finite_events + m.rollbacks, 0);
    assert_eq!(on.stats.metrics.judged_frames, 150);
    let crossed: Vec<(usize, usize)> = on
        .stats
        .per_frame
        .iter()
        .filter(|f| f.cloth_intersections > 0)
        .map(|f| (f.frame, f.cloth_intersections))
        .collect();
    assert!(
        crossed.is_empty(),
        "frames with crossing triangles: {crossed:?}"
    );
    assert!(m.cloth_min_gap_m > 0.0);
    // Not vacuous: without it the same sheet passes through itself where it folds.
    let off = drape(32, false);
    assert!(
        off.stats.metrics.cloth_intersections > 0,
        "the sheet did not fold onto itself"
    );
}
