//! Folds drawn on a garment (P3, issue 22) through the pipeline: the shipped bloomer scene runs
//! and reports a retention per fold; a folded cloth's mass per unit area stays uniform and only
//! the bend springs across a line change; bad lines are errors naming the fold.

use cloth_dyn::model::ClothModel;
use cloth_dyn::params::ClothParams;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::grid_xz;
use tryon_pipeline::{Pipeline, Scene};

fn scene_file(name: &str) -> std::path::PathBuf {
    crate::end_to_end::repo().join("data/scenes").join(name)
}

/// The bloomer scene's folds are made, the run stays finite, and stats.json gets one
/// retention per fold, before and after the simulation.
#[test]
fn the_bloomer_scene_makes_six_folds_and_measures_each() {
    let scene = Scene::load_with_overrides(&scene_file("fold-bloomer.toml"), &[]).unwrap();
    assert_eq!(scene.fold.len(), 6);
    let mut p = Pipeline::new(scene).unwrap();
    assert_eq!(p.folds.folds.len(), 6);
    assert!(
        p.folds.bends.len() >= 6 * 5,
        "{} bend springs",
        p.folds.bends.len()
    );
    let run = p.run(Some(6), |_, _| {});
    let m = &run.stats.metrics;
    assert_eq!(m.non_finite_events, 0);
    assert_eq!(m.fold_retention.len(), 6);
    assert_eq!(m.fold_retention_shaped.len(), 6);
    for (end, shaped) in m.fold_retention.iter().zip(&m.fold_retention_shaped) {
        let (end, shaped) = (end.expect("measured"), shaped.expect("measured"));
        // As shaped, each ridge stands at least half its drawn height (constrained smoothing).
        assert!(shaped > 0.5 && shaped < 1.5, "shaped {shaped}");
        assert!(end.is_finite());
    }
}

/// After subdividing, each particle's mass over its share of the area is the same everywhere
/// (within 1%), and applying the fold's bend changes touches only the springs it names.
#[test]
fn a_folded_cloth_keeps_uniform_mass_per_area_and_only_crossing_springs_change() {
    let mesh = grid_xz(16, 16, 1.0, 1.0, 0.0);
    let line = fold::FoldLine {
        kind: fold::FoldKind::Ridge,
        points: vec![Vec3::new(-0.3, 0.0, 0.02), Vec3::new(0.3, 0.0, 0.05)],
        height: 0.03,
    };
    let params = fold::FoldParams::default();
    let f = fold::build(&mesh, &[line], &params).unwrap();
    let p = ClothParams {
        k_bend: 1.0,
        ..ClothParams::default()
    };
    let mut m = ClothModel::build(&f.mesh, &p, vec![]).unwrap();
    let ratios: Vec<Real> = m.mass.iter().zip(&m.area).map(|(a, b)| a / b).collect();
    let (lo, hi) = ratios
        .iter()
        .fold((Real::MAX, Real::MIN), |(a, b), &r| (a.min(r), b.max(r)));
    assert!(hi / lo < 1.01, "mass per area {lo}..{hi}");
    let edits = fold::bend_edits(&f, &params);
    let changes = tryon_pipeline::folding::bend_changes(&edits);
    let before = m.springs.clone();
    assert_eq!(m.change_bends(&changes), edits.len());
    let named: std::collections::HashSet<(u32, u32)> = edits.iter().map(|e| (e.a, e.b)).collect();
    for k in 0..before.len() {
        let (i, j) = (before.i[k].min(before.j[k]), before.i[k].max(before.j[k]));
        let changed = before.rest[k] != m.springs.rest[k];
        assert_eq!(
            changed,
            m.bend.contains(&k) && named.contains(&(i, j)),
            "spring {k}"
        );
    }
}

/// A 12-particle square above a sphere with `fold`, drawn on the square as placed.
fn with_fold(fold: &str) -> String {
    with_folding("[folding]\ndrape = 0.0\n", fold)
}

fn with_folding(folding: &str, fold: &str) -> String {
    with_folding_on(12, folding, fold)
}

/// The square of `n` x `n` particles on the sphere, with `folding` and `fold`.
fn with_folding_on(n: usize, folding: &str, fold: &str) -> String {
    format!(
        "[scene]\nname = \"f\"\nduration = 0.1\n[body]\nkind = \"sphere\"\n[garment]\nkind = \"square\"\n\
         particles = {n}\n[motion]\nkind = \"still\"\n{folding}{fold}"
    )
}

fn assemble(text: &str) -> Result<Pipeline, String> {
    let scene = Scene::parse(text, std::path::Path::new("f.toml")).map_err(|e| e.to_string())?;
    Pipeline::new(scene).map_err(|e| e.to_string())
}

#[test]
fn bad_fold_lines_are_errors_naming_the_fold_and_what_is_wrong() {
    let ok = "[[fold]]\nheight = 0.02\npoints = [[-0.3, 0.5, 0.01], [0.3, 0.5, 0.02]]\n";
    assert!(assemble(&with_fold(ok)).is_ok());
    let cases = [
        (
            "points = [[0.0, 0.5, 0.0]]",
            "fold 1: a line needs at least two points, it has 1",
        ),
        (
            "points = [[0.0, 0.5, 0.0], [0.3, 0.9, 0.0]]",
            "fold 1: point 1 is 0.400 m from the garment",
        ),
        (
            "points = [[0.0, 0.5, 0.0], [nan, 0.5, 0.0]]",
            "fold 1: point 1 is not finite",
        ),
    ];
    for (points, message) in cases {
        let bad = format!("{ok}[[fold]]\nheight = 0.02\n{points}\n");
        let e = assemble(&with_fold(&bad)).err().unwrap_or_default();
        assert!(e.contains(message), "{points}: {e}");
    }
    let e = assemble(&with_fold(
        "[[fold]]\nheight = 0.02\npoint = [[0.0, 0.5, 0.0]]\n",
    ))
    .err()
    .unwrap_or_default();
    assert!(e.contains("fold") && e.contains("point"), "{e}");
}

/// A line drawn in the canvas's pixels (P3's input) lands on the garment and is made into a fold
/// like a line given in metres; pixels off the garment, outside the canvas, or a line given both
/// ways are errors naming the fold.
#[test]
fn a_line_drawn_on_the_canvas_becomes_a_fold_and_bad_pixels_are_named() {
    // A square of 32 x 32 (cells of about 5 cm): on the 12 x 12 one a fold is not measurable
    // (its surroundings lie more than six heights out).
    let fine = |fold: &str| with_folding_on(32, "[folding]\ndrape = 0.0\n", fold);
    let plain = Scene::parse(&fine(""), std::path::Path::new("f.toml")).unwrap();
    let (canvas, image) = tryon_pipeline::canvas::picture(&plain).unwrap();
    let (w, h) = (canvas.width as usize, canvas.height as usize);
    // The garment's pixels: its colour's hue (blue), unlike the body and the grey background.
    let blue = |x: usize, y: usize| {
        let c = &image.rgb[(y * w + x) * 3..][..3];
        c[2] as i32 > c[0] as i32 + 30 && c[2] > c[1]
    };
    let cells: Vec<(usize, usize)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| blue(x, y))
        .collect();
    assert!(cells.len() > 1000, "{} garment pixels", cells.len());
    let y = cells.iter().map(|c| c.1).sum::<usize>() / cells.len();
    let row: Vec<usize> = cells.iter().filter(|c| c.1 == y).map(|c| c.0).collect();
    let (x0, x1) = (row[0], row[row.len() - 1]);
    let (a, b) = (x0 + (x1 - x0) / 4, x1 - (x1 - x0) / 4);
    assert!(blue(a, y) && blue(b, y));
    let line = format!("[[fold]]\nheight = 0.06\nscreen = [[{a}, {y}], [{b}, {y}]]\n");
    let p = assemble(&fine(&line)).unwrap();
    assert_eq!(p.folds.folds.len(), 1);
    let shaped = p.folds.shaped[0].expect("measured");
    assert!(shaped > 0.01, "the fold stands {shaped} m");
    // The fold's ridge runs across the square (x from one quarter to three quarters of the way).
    let ridge = &p.folds.folds[0].ridge;
    let xs: Vec<Real> = ridge
        .iter()
        .map(|&v| p.garment.positions[v as usize].x)
        .collect();
    let span = xs.iter().cloned().fold(Real::MIN, Real::max)
        - xs.iter().cloned().fold(Real::MAX, Real::min);
    assert!(span > 0.2, "the ridge spans {span} m");
    let cases = [
        (
            format!("screen = [[2, 2], [{b}, {y}]]"),
            "fold 0: screen point 0 [2.0, 2.0] shows no garment",
        ),
        (
            format!("screen = [[{a}, {y}], [5000, {y}]]"),
            "fold[0].screen",
        ),
        (
            format!(
                "screen = [[{a}, {y}], [{b}, {y}]]\npoints = [[0.0, 0.5, 0.0], [0.1, 0.5, 0.0]]"
            ),
            "not both",
        ),
        ("".to_string(), "fold[0].points"),
    ];
    for (keys, message) in cases {
        let e = assemble(&with_fold(&format!("[[fold]]\nheight = 0.02\n{keys}\n")))
            .err()
            .unwrap_or_default();
        assert!(e.contains(message), "{keys}: {e}");
    }
}

/// With `[folding] drape`, the fold is drawn on the garment as it hangs: the cloth starts from
/// the draped shape, which is not the placed one, while the garment's modelled shape (its rest
/// lengths) is the one the scene places, unfolded where the fold does not reach.
#[test]
fn a_fold_drawn_on_the_draped_garment_starts_there_and_keeps_the_cut() {
    // Points above the square's middle, snapped to wherever it hangs.
    let folding = "[folding]\ndrape = 0.5\nsnap = 0.5\n";
    let line = "[[fold]]\nheight = 0.02\npoints = [[-0.3, 0.5, 0.01], [0.3, 0.5, 0.02]]\n";
    let placed = assemble(&with_fold("")).unwrap();
    let draped = assemble(&with_folding(folding, line)).unwrap();
    let start = draped.folds.start.as_ref().expect("drawn on the drape");
    assert_eq!(&draped.cloth.positions, start);
    let n0 = placed.garment.positions.len();
    // The square sags over the sphere while it hangs: the start is far from the placed shape.
    let sag = (0..n0)
        .map(|v| (start[v] - placed.garment.positions[v]).norm())
        .fold(0.0, Real::max);
    assert!(sag > 0.05, "the drape moved the square {sag} m");
    // Away from the line, the modelled shape is the placed one.
    let far: Vec<usize> = (0..n0)
        .filter(|&v| (placed.garment.positions[v].z).abs() > 0.25)
        .collect();
    assert!(far.len() > 20);
    for v in far {
        let d = (draped.garment.positions[v] - placed.garment.positions[v]).norm();
        assert!(d < 1e-9, "vertex {v} moved {d} m in the modelled shape");
    }
}

/// A fold that only assembling finds wrong (off the garment) is placed at its `[[fold]]` line of
/// the scene file.
#[test]
fn a_fold_found_wrong_when_assembled_names_its_file_and_line() {
    let text = with_fold(
        "[[fold]]\nheight = 0.02\npoints = [[-0.3, 0.5, 0.01], [0.3, 0.5, 0.02]]\n\n\
         [[fold]]\nheight = 0.02\npoints = [[0.0, 0.5, 0.0], [0.3, 0.9, 0.0]]\n",
    );
    let second = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == "[[fold]]")
        .nth(1)
        .map(|(i, _)| i + 1)
        .unwrap();
    let dir = std::env::temp_dir().join(format!("tryon-fold-line-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("folds.toml");
    std::fs::write(&path, &text).unwrap();
    let scene = Scene::load_with_overrides(&path, &[]).unwrap();
    let e = Pipeline::new(scene)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    let _ = std::fs::remove_dir_all(&dir);
    let at = format!("{}:{second}: [[fold]] fold 1: point 1 is", path.display());
    assert!(e.starts_with(&at), "{e}\nexpected to start with {at}");
}
