//! Issue 21's hard cases for the cloth's contact with itself: a sheet dropped on a ball folds
//! onto itself as it slides off, and no two of its triangles may cross in any frame (judged by
//! the referee, `body_collide::crossings`, which shares no code with the solver's contacts).

use tryon_pipeline::{Pipeline, Scene};

fn drape(n: u32, self_collision: bool) -> tryon_pipeline::RunOutput {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes/drape-sphere.toml");
    let sets: Vec<String> = [
        "cloth.solver=\"vbd\"".to_string(),
        format!("garment.particles={n}"),
        format!("effects.self_collision={self_collision}"),
        "output.referee_share=1".to_string(),
    ]
    .into();
    let scene = Scene::load_with_overrides(&file, &sets).unwrap_or_else(|e| panic!("{e}"));
    let mut p = Pipeline::new(scene).unwrap_or_else(|e| panic!("{e}"));
    p.run(Some(150), |_, _| {})
}

/// Every frame and every garment finite, and no frame with crossing triangle pairs (the referee).
fn assert_no_crossings(out: &tryon_pipeline::RunOutput) {
    for f in &out.frames {
        assert!(f.garment.iter().all(|x| x.iter().all(|c| c.is_finite())));
    }
    let crossed: Vec<(usize, usize)> = out
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
}

#[test]
fn a_sheet_falling_into_folds_on_a_ball_never_passes_through_itself() {
    let on = drape(32, true);
    let m = &on.stats.metrics;
    assert_eq!(m.non_finite_events + m.rollbacks, 0);
    assert_eq!(on.stats.metrics.judged_frames, 150);
    assert_no_crossings(&on);
    assert!(m.cloth_min_gap_m > 0.0);
    // Not vacuous: without it the same sheet passes through itself where it folds.
    let off = drape(32, false);
    assert!(
        off.stats.metrics.cloth_intersections > 0,
        "the sheet did not fold onto itself"
    );
}

/// The layered mannequin scene (a slip under the dress) at a run: a shorter stride period and
/// larger leg swings than its walk, for `seconds`, with contact between the garments (and of each
/// with itself) on or off.
fn layered_run(cloth_collision: bool, seconds: f64) -> tryon_pipeline::RunOutput {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes/layered-walk.toml");
    let sets: Vec<String> = [
        "motion.period=0.7".to_string(),
        "motion.hip_deg=32".to_string(),
        "motion.knee_deg=75".to_string(),
        "motion.arm_deg=30".to_string(),
        format!("scene.duration={seconds}"),
        format!("effects.cloth_collision={cloth_collision}"),
        format!("effects.self_collision={cloth_collision}"),
        "output.referee_share=1".to_string(),
    ]
    .into();
    let scene = Scene::load_with_overrides(&file, &sets).unwrap_or_else(|e| panic!("{e}"));
    let mut p = Pipeline::new(scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(p.wear.len(), 2, "two garments");
    p.run(None, |_, _| {})
}

#[test]
fn two_garments_on_a_running_body_never_pass_through_each_other() {
    let on = layered_run(true, 2.0);
    let m = &on.stats.metrics;
    assert_eq!(m.non_finite_events, 0);
    assert_eq!(m.garments, 2);
    assert!(m.judged_frames >= 60);
    assert_no_crossings(&on);
    // Both stay on the body.
    assert!(m.detached_share < 0.01, "detached {}", m.detached_share);
    // Not vacuous: the same run without contact between them passes the slip through the dress.
    let off = layered_run(false, 2.0);
    assert!(
        off.stats.metrics.cloth_intersections > 0,
        "the garments never met"
    );
}

/// The layered MakeHuman scene's garments as dressed (before any step): crossing pairs of
/// triangles between the two garments, what placing the outer moved, and the garments' ranges.
fn dressed(text: &str, file: &std::path::Path) -> (usize, Vec<garment_fit::LayerPlacement>) {
    let scene = Scene::parse(text, file).unwrap_or_else(|e| panic!("{e}"));
    let p = Pipeline::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let (tris, _) = p.garment.triangulate();
    let first = p.wear[0].particles.end;
    let between = body_collide::crossings::crossings(&p.garment.positions, &tris)
        .iter()
        .filter(|[a, b]| (tris[*a as usize][0] < first) != (tris[*b as usize][0] < first))
        .count();
    (between, p.layered.clone())
}

#[test]
fn a_suit_worn_over_another_is_dressed_outside_it() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/scenes/makehuman-layered-131.toml");
    let text = std::fs::read_to_string(&file).unwrap();
    let (between, layered) = dressed(&text, &file);
    assert_eq!(layered[0].moved, 0, "the inner suit stays as fitted");
    assert!(
        layered[1].moved > 0 && layered[1].farthest < 0.06,
        "{layered:?}"
    );
    // Fitted to the skin one by one, the two suits cut through each other; dressed, few pairs
    // are left for the solver's untangling (which moves no vertex more than two gaps).
    let same = text.replace("layer = 1", "layer = 0");
    let (crossed, unmoved) = dressed(&same, &file);
    assert_eq!(unmoved[1].moved, 0);
    assert!(
        crossed > 100 && between * 20 < crossed,
        "{between} crossing pairs between the suits dressed, {crossed} fitted"
    );
}

/// Crossing triangle pairs of the dressed garment before the first step: all, and those between
/// two of its separate pieces.
fn dressed_pieces(scene: &str, self_collision: bool) -> (usize, usize) {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let sets = vec![format!("effects.self_collision={self_collision}")];
    let scene = Scene::load_with_overrides(&file, &sets).unwrap_or_else(|e| panic!("{e}"));
    let p = Pipeline::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let (tris, _) = p.garment.triangulate();
    let piece = garment_fit::components(&p.garment);
    let pairs = body_collide::crossings::crossings(&p.garment.positions, &tris);
    let of = |t: u32| piece[tris[t as usize][0] as usize];
    let between = pairs.iter().filter(|[a, b]| of(*a) != of(*b)).count();
    (pairs.len(), between)
}

#[test]
fn a_garments_pieces_modelled_through_each_other_start_apart() {
    // The casual suit's waist patch passes through its shorts as modelled; the elegant suit's
    // jacket through its skirt's waistband. With the cloth meeting itself, each piece is worn
    // over the one beneath before the first step.
    for scene in [
        "../data/scenes/makehuman-casual-131.toml",
        "../data/scenes/makehuman-dress-walk.toml",
    ] {
        let (_, modelled) = dressed_pieces(scene, false);
        let (_, worn) = dressed_pieces(scene, true);
        assert!(
            modelled >= 20,
            "{scene}: {modelled} pairs between pieces as modelled"
        );
        assert_eq!(worn, 0, "{scene}: pairs between pieces when worn");
    }
    let (all, _) = dressed_pieces("../data/scenes/makehuman-casual-131.toml", true);
    assert_eq!(all, 0, "the casual suit starts with no crossing pair");
}
