//! The kimono mesh, the fit and the print correction, each against what it must keep.

use crate::family::{BASE, TARGETS, flat_family};
use crate::mesh::{Part, sub};
use crate::*;
use proptest::prelude::*;
use std::collections::HashMap;
use tryon_core::math::{Real, Vec3};

fn family() -> &'static family::Family {
    static F: std::sync::OnceLock<family::Family> = std::sync::OnceLock::new();
    F.get_or_init(|| flat_family().unwrap())
}

#[test]
fn the_kimono_is_one_sewn_consistently_wound_surface() {
    let k = &family().base;
    let mut uses: HashMap<(u32, u32), Vec<(u32, u32)>> = HashMap::new();
    for t in &k.triangles {
        assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
        for i in 0..3 {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            uses.entry((a.min(b), a.max(b))).or_default().push((a, b));
        }
    }
    for (e, u) in &uses {
        assert!(u.len() <= 2, "edge {e:?} has {} triangles", u.len());
        if u.len() == 2 {
            assert_ne!(
                u[0], u[1],
                "edge {e:?}: both triangles walk it the same way"
            );
        }
    }
    // One piece: every vertex reached from vertex 0 over the edges.
    let mut seen = vec![false; k.positions.len()];
    let mut stack = vec![0u32];
    seen[0] = true;
    while let Some(v) = stack.pop() {
        for (&(a, b), _) in uses.iter().filter(|((a, b), _)| *a == v || *b == v) {
            let o = if a == v { b } else { a };
            if !seen[o as usize] {
                seen[o as usize] = true;
                stack.push(o);
            }
        }
    }
    assert!(
        seen.iter().all(|&s| s),
        "the parts are not all sewn together"
    );
    // Every one of the eight parts is there.
    for p in [
        Part::RightSleeve,
        Part::LeftSleeve,
        Part::RightBody,
        Part::LeftBody,
        Part::RightOkumi,
        Part::LeftOkumi,
        Part::Collar,
        Part::OverCollar,
    ] {
        assert!(k.part.contains(&p), "{p:?} missing");
    }
}

#[test]
fn every_size_has_the_same_topology_and_measures_its_own_dimensions() {
    let fam = family();
    for w in TARGETS.iter().chain([
        &BASE,
        &Wearer::new(1.40, 0.70, 0.50, 0.75),
        &Wearer::new(1.85, 1.3, 1.2, 1.24),
    ]) {
        let d = tailor(w).unwrap();
        let k = build(&d, &fam.layout).unwrap();
        assert!(k.triangles == fam.base.triangles, "{w:?}: another topology");
        assert!(
            k.dimensions
                .iter()
                .zip(&fam.base.dimensions)
                .all(|(a, b)| a.edges == b.edges)
        );
        let table = d.table();
        for (i, s) in k.dimensions.iter().enumerate() {
            let (want, got) = (table[s.table_index].1, k.measure(i, &k.positions));
            // The flat kimono's seams step 1 cm between its layers: at most 2% on the shortest sets.
            assert!(
                (got - want).abs() <= 0.02 * want,
                "{w:?} {}: {got} for {want}",
                s.name
            );
        }
    }
}

#[test]
fn uvs_lie_on_the_bolt_and_the_flat_print_is_square() {
    let k = &family().base;
    for uv in &k.uvs {
        assert!(
            uv[0] >= -1e-9 && uv[0] <= dims::BOLT_WIDTH + 1e-9,
            "{uv:?} off the bolt"
        );
        assert!(uv[1] >= -1e-9, "{uv:?}");
    }
    let a = print_aspect(k, &k.positions, &k.uvs).expect("shapes of the mesh");
    assert!(a.mean < 1.01 && (a.scale - 1.0).abs() < 0.01, "{a:?}");
    // A vertex on a seam between parts has a UV on each side.
    assert!(k.uvs.len() > k.positions.len());
}

#[test]
fn one_weight_at_one_reproduces_that_target() {
    let fam = family();
    for t in [0, 4, 9] {
        let w: Vec<Vec<Real>> = (0..sub::COUNT)
            .map(|_| {
                (0..TARGETS.len())
                    .map(|k| if k == t { 1.0 } else { 0.0 })
                    .collect()
            })
            .collect();
        let x = blend(&fam.base, &fam.base.positions, &fam.targets, &w);
        let worst = x
            .iter()
            .zip(&fam.targets[t])
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, Real::max);
        assert!(worst < 1e-12, "target {t}: {worst}");
    }
}

#[test]
fn fitting_a_target_size_recovers_its_dimensions() {
    let fam = family();
    let d = tailor(&TARGETS[6]).unwrap();
    let f = fit(
        &fam.base,
        &fam.base.positions,
        &fam.targets,
        &d,
        &FitParams::default(),
    )
    .unwrap();
    let table = d.table();
    let mut sum = 0.0;
    for (k, s) in fam.base.dimensions.iter().enumerate() {
        let want = table[s.table_index].1;
        let e = (f.measured[k] - want).abs() / want;
        assert!(e < 0.03, "{}: {} for {want}", s.name, f.measured[k]);
        sum += e;
    }
    assert!(sum / fam.base.dimensions.len() as Real <= 0.01);
}

#[test]
fn bad_shapes_are_refused_by_name() {
    let fam = family();
    let d = tailor(&BASE).unwrap();
    let p = FitParams::default();
    assert_eq!(
        fit(&fam.base, &fam.base.positions, &[], &d, &p).unwrap_err(),
        FitError::NoTargets
    );
    let mut short = fam.targets.clone();
    short[3].pop();
    assert!(
        fit(&fam.base, &fam.base.positions, &short, &d, &p)
            .unwrap_err()
            .to_string()
            .contains("target 3")
    );
    let mut nan = fam.targets.clone();
    nan[1][7].x = Real::NAN;
    assert!(matches!(
        fit(&fam.base, &fam.base.positions, &nan, &d, &p),
        Err(FitError::NonFinite { vertex: 7, .. })
    ));
}

#[test]
fn the_print_correction_restores_a_square_print() {
    // The initial kimono stretched 12% along its length and 3% across: its print squares become
    // oblong; corrected, they are square again and at the print's own scale.
    let k = &family().base;
    let after: Vec<Vec3> = k
        .positions
        .iter()
        .map(|p| Vec3::new(p.x * 1.03, p.y * 1.12, p.z))
        .collect();
    let before = print_aspect(k, &after, &k.uvs).expect("shapes of the mesh");
    let uv = correct_print(k, &k.positions, &after, &PrintParams::default())
        .expect("shapes of the mesh");
    let fixed = print_aspect(k, &after, &uv).expect("shapes of the mesh");
    assert!(before.mean > 1.07, "{before:?}");
    assert!(
        fixed.mean < 1.03 && (fixed.scale - 1.0).abs() < 0.015,
        "{fixed:?} (before {before:?})"
    );
}

#[test]
fn shapes_that_are_not_the_meshs_are_errors_not_panics() {
    let k = &family().base;
    let n = k.positions.len();
    let short = &k.positions[..n - 1];
    let p = PrintParams::default();
    assert_eq!(
        correct_print(k, short, &k.positions, &p),
        Err(PrintError::Count {
            what: "the shape before",
            found: n - 1,
            expected: n
        })
    );
    let mut bad = k.positions.clone();
    bad[7].y = Real::NAN;
    assert_eq!(
        correct_print(k, &k.positions, &bad, &p),
        Err(PrintError::NonFinite {
            what: "the shape after",
            index: 7
        })
    );
    assert!(matches!(
        print_aspect(k, short, &k.uvs),
        Err(PrintError::Count { .. })
    ));
    assert!(matches!(
        print_aspect(k, &k.positions, &k.uvs[1..]),
        Err(PrintError::Count {
            what: "the UVs",
            ..
        })
    ));
    let msg = print_aspect(k, &bad, &k.uvs).unwrap_err().to_string();
    assert_eq!(msg, "the positions, entry 7: not finite");
    assert!(k.measure(0, short.get(..3).unwrap()).is_nan());
    assert!(k.measure(k.dimensions.len(), &k.positions).is_nan());
    assert!(k.measure(0, &k.positions) > 0.0);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    #[test]
    fn the_fit_is_finite_and_within_its_bounds(h in 1.40..1.85f64, b in 0.0..1.0f64, hp in 0.0..1.0f64, wa in 0.0..1.0f64) {
        let w = Wearer::new(h, 0.70 + 0.6 * b, 0.50 + 0.7 * wa, 0.75 + 0.49 * hp);
        let d = tailor(&w).unwrap();
        let fam = family();
        let p = FitParams::default();
        let f = fit(&fam.base, &fam.base.positions, &fam.targets, &d, &p).unwrap();
        for w in f.weights.iter().flatten() {
            prop_assert!(w.is_finite() && *w >= p.bounds.0 && *w <= p.bounds.1, "{w}");
        }
        prop_assert!(f.positions.iter().all(|x| x.iter().all(|c| c.is_finite())));
        prop_assert!(f.measured.iter().all(|m| m.is_finite() && *m > 0.0));
    }
}
