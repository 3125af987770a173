//! Tests of the cloth's contact with itself: pairs found and bounded, layers left out or kept at their modelled distance, the energy's push and friction, untangling, and (proptest, judged by parry) no crossing within the bounds.
use super::*;
use parry3d_f64::math::{Isometry, Point};
use parry3d_f64::query::intersection_test;
use parry3d_f64::shape::Triangle;
use proptest::prelude::*;
use tryon_core::math::Mat3;
use tryon_core::stages::Probe;

/// Two square sheets of n x n cells of side `s`, the second `gap` above the first.
fn two_sheets(n: u32, s: Real, gap: Real) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut x = Vec::new();
    let mut t = Vec::new();
    for (layer, z) in [0.0, gap].into_iter().enumerate() {
        let base = layer as u32 * (n + 1) * (n + 1);
        for j in 0..=n {
            for i in 0..=n {
                x.push(Vec3::new(i as Real * s, j as Real * s, z));
            }
        }
        let id = |i: u32, j: u32| base + j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    (x, t)
}

/// Crossing pairs of triangles sharing no vertex, by parry (independent of this module; boxes
/// first).
pub(crate) fn crossings(x: &[Vec3], t: &[[u32; 3]]) -> usize {
    let boxes: Vec<(Vec3, Vec3)> = t
        .iter()
        .map(|f| {
            let p = f.map(|i| x[i as usize]);
            (p[0].inf(&p[1]).inf(&p[2]), p[0].sup(&p[1]).sup(&p[2]))
        })
        .collect();
    let tri = |f: &[u32; 3]| {
        let p = |i: u32| Point::from(x[i as usize]);
        Triangle::new(p(f[0]), p(f[1]), p(f[2]))
    };
    let id = Isometry::identity();
    let mut n = 0;
    for a in 0..t.len() {
        for b in a + 1..t.len() {
            let ((alo, ahi), (blo, bhi)) = (boxes[a], boxes[b]);
            if (0..3).any(|k| alo[k] > bhi[k] || blo[k] > ahi[k]) {
                continue;
            }
            if t[a].iter().any(|v| t[b].contains(v)) {
                continue;
            }
            if intersection_test(&id, &tri(&t[a]), &id, &tri(&t[b])).unwrap_or(false) {
                n += 1;
            }
        }
    }
    n
}

#[test]
fn layers_a_few_millimetres_apart_are_found_and_bound_their_vertices() {
    let (x, t) = two_sheets(4, 0.02, 0.003);
    let mut sc = SelfContacts::new(&t, &x, SelfParams::default());
    sc.detect(&x, &[0.02; 50], |_| 1e4);
    // Every vertex of either sheet is 3 mm from the other: bounded by share * 3 mm.
    for b in &sc.bound {
        assert!((b - 0.3 * 0.003).abs() < 1e-12, "{b}");
    }
    // 3 mm is beyond the 2 mm thickness: no normal force yet, but near enough to keep.
    assert!(!sc.stencils.is_empty());
    assert!(sc.stencils.iter().all(|s| s.lambda == 0.0));
    // A lone sheet's own vertices are not bounded by their in-plane neighbours beyond one ring
    // more than share * cell: nothing nearer than a cell's height.
    let (x1, t1) = two_sheets(4, 0.02, 1.0);
    let mut one = SelfContacts::new(&t1, &x1, SelfParams::default());
    one.detect(&x1, &[0.02; 50], |_| 1e4);
    assert!(
        one.bound.iter().all(|b| *b >= 0.3 * 0.0141),
        "{:?}",
        one.bound
    );
}

#[test]
fn layers_modelled_touching_are_left_out_and_near_ones_keep_their_distance() {
    let (x, t) = two_sheets(3, 0.02, 0.0001);
    let mut sc = SelfContacts::new(&t, &x, SelfParams::default());
    sc.detect(&x, &[0.02; 50], |_| 1e4);
    assert!(sc.stencils.is_empty());
    // Modelled 1 mm apart: held at 0.9 mm, not pushed to the 2 mm thickness.
    let (x, t) = two_sheets(3, 0.02, 0.001);
    let mut sc = SelfContacts::new(&t, &x, SelfParams::default());
    sc.detect(&x, &[0.02; 50], |_| 1e4);
    assert!(!sc.stencils.is_empty());
    for st in &sc.stencils {
        assert!((st.thickness - 0.0009).abs() < 1e-12, "{}", st.thickness);
        assert_eq!(st.lambda, 0.0);
    }
}

#[test]
fn the_penalty_pushes_the_layers_apart_and_friction_opposes_their_slide() {
    let (mut x, t) = two_sheets(2, 0.02, 0.003);
    // Modelled 3 mm apart (beyond the thickness), then pressed together.
    let mut sc = SelfContacts::new(&t, &x, SelfParams::default());
    // The upper sheet is pressed to 1 mm over the lower.
    let upper = x.len() / 2;
    x[upper..].iter_mut().for_each(|p| p.z = 0.001);
    sc.detect(&x, &[0.02; 50], |_| 1e4);
    let v = upper + 4; // the middle vertex of the upper sheet
    let (mut f, mut h) = (Vec3::zeros(), Mat3::zeros());
    sc.add(v, &x, (1e4, 1e-4), &mut f, &mut h);
    assert!(f.z > 0.0 && f.x.abs() < 1e-9 && f.y.abs() < 1e-9, "{f:?}");
    assert!(h[(2, 2)] > 0.0);
    // Slid along +x: friction pulls it back.
    x[v].x += 0.001;
    let (mut g, mut h2) = (Vec3::zeros(), Mat3::zeros());
    sc.add(v, &x, (1e4, 1e-4), &mut g, &mut h2);
    assert!(g.x < 0.0, "{g:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Whatever each vertex tries to do, clamped to its bound no two triangles that were apart
    /// cross afterwards.
    #[test]
    fn no_step_within_the_bounds_makes_the_layers_cross(
        gap in 0.0025..0.02,
        moves in proptest::collection::vec([-0.03..0.03f64, -0.03..0.03f64, -0.03..0.03f64], 32),
    ) {
        let (x0, t) = two_sheets(3, 0.02, gap);
        let mut sc = SelfContacts::new(&t, &x0, SelfParams::default());
        sc.detect(&x0, &[0.02; 32], |_| 1e4);
        let mut x = x0.clone();
        for (i, xi) in x.iter_mut().enumerate() {
            let m = moves[i % moves.len()];
            *xi += Vec3::new(m[0], m[1], m[2]);
        }
        sc.clamp_all(&mut x, |_| false);
        prop_assert_eq!(crossings(&x, &t), 0);
    }
}

#[test]
fn unclamped_the_same_moves_do_cross() {
    // The property above is not vacuous: the upper sheet's middle pushed 2 cm down crosses.
    let (x0, t) = two_sheets(3, 0.02, 0.004);
    let mut x = x0.clone();
    let upper = x.len() / 2;
    x[upper + 5].z = -0.02;
    assert!(crossings(&x, &t) > 0);
    let mut sc = SelfContacts::new(&t, &x0, SelfParams::default());
    sc.detect(&x0, &[0.02; 32], |_| 1e4);
    sc.clamp_all(&mut x, |_| false);
    assert_eq!(crossings(&x, &t), 0);
}

#[test]
fn layers_modelled_through_each_other_are_pulled_apart_outer_outward() {
    // Two sheets over a floor (z = 0, normal +z): the upper one at 4 mm, except that its middle
    // row dips to 1 mm under the lower one at 3 mm, so they pass through each other.
    let (mut x, t) = two_sheets(4, 0.02, 0.004);
    let upper = x.len() / 2;
    x[..upper].iter_mut().for_each(|p| p.z = 0.003);
    for i in 0..5 {
        x[upper + 2 * 5 + i].z = 0.001;
    }
    assert!(crossings(&x, &t) > 0);
    let mut sc = SelfContacts::new(&t, &x, SelfParams::default());
    assert!(!sc.crossing_triangles(&x).is_empty());
    let probes: Vec<Probe> = x
        .iter()
        .map(|p| Probe {
            distance: p.z,
            normal: Vec3::z(),
        })
        .collect();
    let before = x.clone();
    let r = sc.untangle(&mut x, &probes, (0.002, 30), |_| false);
    assert_eq!(crossings(&x, &t), 0, "{r:?}");
    assert_eq!((r.crossings_after, r.near_after), (0, 0), "{r:?}");
    assert!(r.crossings_before > 0);
    // Only upward moves; the lower sheet (inner, nearer the floor) stays put where the upper
    // one's dip is not under it... every move is along +z.
    for (a, b) in x.iter().zip(&before) {
        assert!(a.z >= b.z && (a.x, a.y) == (b.x, b.y));
    }
}
