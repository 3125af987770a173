//! P2's kimono end to end (`tryon kimono`'s job): fitted to wearers who are not among the family's
//! targets, Table 1's errors within issue 23's bounds, the print squarer after its correction
//! than before, and the outputs readable: a GLB that passes the Khronos validator, two pictures
//! and fit.json with Table 1.

use crate::end_to_end::{khronos_errors, scratch_dir};
use tryon_pipeline::kimono::{KimonoError, Targets, Wearer, fit_kimono, write_kimono};
use tryon_pipeline::kimono_wear::store::dir_shapes;

/// The worn target shapes in the repository's data/kimono.
fn worn_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/kimono")
}

/// Wearers the family was not built from (its targets are in `kimono::family::TARGETS`).
const UNSEEN: [[f64; 4]; 5] = [
    [1.50, 0.82, 0.64, 0.88],
    [1.57, 0.88, 0.70, 0.96],
    [1.62, 0.84, 0.64, 0.90],
    [1.68, 0.94, 0.76, 1.02],
    [1.75, 0.90, 0.70, 0.97],
];

#[test]
fn unseen_wearers_fit_within_the_issues_bounds_and_the_print_is_corrected() {
    for m in UNSEEN {
        let w = Wearer::new(m[0], m[1], m[2], m[3]);
        let k = fit_kimono(&w, Targets::Flat).unwrap_or_else(|e| panic!("{m:?}: {e}"));
        let r = &k.report;
        assert_eq!(r.dimensions.len(), 17);
        assert!(r.mean_rel_error <= 0.01, "{m:?}: mean {}", r.mean_rel_error);
        assert!(r.max_rel_error <= 0.03, "{m:?}: max {}", r.max_rel_error);
        assert!(r.mean_rel_error < r.initial_mean_rel_error, "{m:?}");
        let (before, after) = (r.print.before[0], r.print.after[0]);
        assert!(
            after < before && after < 1.04,
            "{m:?}: aspect {before} -> {after}"
        );
        assert!(
            (r.print.after[1] - 1.0).abs() < 0.015,
            "{m:?}: scale {}",
            r.print.after[1]
        );
    }
}

/// On the worn targets (data/kimono, made by the cloth solver) the fit misses the issue's bounds
/// (measured over UNSEEN: mean 0.42-1.43%, max 2.7-13.1%, the back collar's width, which the worn
/// shapes crumple) but stays within P2's own mean (3.50%); the print is squarer after the
/// correction than before.
#[test]
fn unseen_wearers_fit_on_the_worn_targets_within_p2s_mean_error() {
    let dir = worn_dir();
    let text = dir_shapes(&dir);
    for m in UNSEEN {
        let w = Wearer::new(m[0], m[1], m[2], m[3]);
        let k = fit_kimono(&w, Targets::Worn(&text)).unwrap_or_else(|e| panic!("{m:?}: {e}"));
        let r = &k.report;
        assert_eq!(r.targets, "worn");
        assert!(
            r.mean_rel_error <= 0.035,
            "{m:?}: mean {}",
            r.mean_rel_error
        );
        assert!(r.max_rel_error <= 0.15, "{m:?}: max {}", r.max_rel_error);
        assert!(r.mean_rel_error < r.initial_mean_rel_error, "{m:?}");
        assert!(r.print.after[0] < r.print.before[0], "{m:?}: {:?}", r.print);
        assert!(k.positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
    }
}

#[test]
fn the_outputs_read_back_and_the_glb_passes_the_validator() {
    let dir = scratch_dir("kimono");
    let k = fit_kimono(&Wearer::new(1.62, 0.84, 0.64, 0.90), Targets::Flat).unwrap();
    write_kimono(&dir, &k, (120, 140)).unwrap();
    for f in ["before.png", "after.png"] {
        let d = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(dir.join(f)).unwrap(),
        ));
        let r = d.read_info().unwrap();
        assert_eq!((r.info().width, r.info().height), (120, 140), "{f}");
    }
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("fit.json")).unwrap()).unwrap();
    let dims = json["dimensions"].as_array().unwrap();
    assert_eq!(dims.len(), 17);
    assert_eq!(dims[0]["name"], "right sleeve length");
    for d in dims {
        for key in ["target_m", "initial_m", "fitted_m", "rel_error"] {
            assert!(d[key].as_f64().is_some_and(f64::is_finite), "{key} in {d}");
        }
    }
    let text = khronos_errors(&dir.join("kimono.glb"));
    assert!(text.contains(": 0 errors"), "{text}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_measurement_out_of_range_is_named() {
    let e = fit_kimono(&Wearer::new(1.62, 0.84, 0.64, 1.5), Targets::Flat).unwrap_err();
    assert!(matches!(e, KimonoError::Measurements(_)));
    assert!(e.to_string().contains("`hip` = 1.5"), "{e}");
}

/// The extent in x of `points` to each side: (the most negative x, the most positive).
fn reach_x(points: &[tryon_core::math::Vec3]) -> (f64, f64) {
    points.iter().fold((0.0, 0.0), |(lo, hi), p| {
        (f64::min(lo, p.x), f64::max(hi, p.x))
    })
}

#[test]
fn the_kimono_scene_starts_worn_tied_and_with_the_arms_in_the_sleeves() {
    let path = crate::end_to_end::repo().join("data/scenes/kimono-walk.toml");
    let scene = tryon_pipeline::Scene::load(&path).unwrap();
    let mut p = tryon_pipeline::Pipeline::new(scene).unwrap_or_else(|e| panic!("{e}"));
    let tied: Vec<u32> = p.bands.as_ref().map_or(Vec::new(), |b| b.vertices.clone());
    assert!(tied.len() >= 20, "{} vertices tied to the body", tied.len());
    // Tied at the cord and under the bust (the datejime): the tied rows span the waist to the
    // chest, 0.74-1.09 m on this wearer; the cord's and band head's rows alone, 0.74-0.94 m.
    let heights = tied.iter().map(|&v| p.garment.positions[v as usize].y);
    let (low, high) = heights.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y), b.max(y))
    });
    assert!(high - low > 0.27, "tied rows from {low} to {high} m");
    let out = p.run(Some(3), |_, _| {});
    let m = &out.stats.metrics;
    assert!(m.max_penetration_m < 0.003, "{} m", m.max_penetration_m);
    assert_eq!(m.detached_share, 0.0);
    assert_eq!((m.rollbacks, m.non_finite_events), (0, 0));
    // Put on with the arms raised: each sleeve reaches along its arm (a sleeve that slid off
    // the arm hangs from the shoulder, half as far out).
    let last = out.frames.last().unwrap();
    let body = p.body_at(last.pose.as_ref());
    let (b, g) = (reach_x(&body), reach_x(&last.garment));
    assert!(
        g.0 < 0.75 * b.0 && g.1 > 0.75 * b.1,
        "body {b:?}, kimono {g:?}"
    );
}
