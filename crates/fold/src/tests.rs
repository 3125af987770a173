//! Tests of building folds: subdivision keeps the mesh whole, the ridge is a chain of edges, the
//! constraint keeps the ridge's height while plain smoothing lowers it, only springs across the
//! line change, and bad lines are errors naming the fold.

use super::*;
use proptest::prelude::*;
use tryon_core::mesh::grid_xz;
use tryon_core::shapes::icosphere;

/// A 1 m sheet of 20 x 20 quads in the XZ plane, facing +Y.
fn sheet() -> PolyMesh {
    grid_xz(20, 20, 1.0, 1.0, 0.0)
}

fn ridge(points: &[[Real; 3]], height: Real) -> FoldLine {
    FoldLine {
        kind: FoldKind::Ridge,
        points: points.iter().map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
        height,
    }
}

/// A ridge across the sheet's middle, slightly off the grid lines.
fn across() -> FoldLine {
    ridge(
        &[[-0.4, 0.0, 0.013], [0.0, 0.0, 0.031], [0.4, 0.0, 0.017]],
        0.04,
    )
}

fn edges(mesh: &PolyMesh) -> std::collections::HashSet<(u32, u32)> {
    let mut out = std::collections::HashSet::new();
    for f in &mesh.faces {
        let vs = f.vertices();
        for k in 0..vs.len() {
            let (a, b) = (vs[k], vs[(k + 1) % vs.len()]);
            out.insert((a.min(b), a.max(b)));
        }
    }
    out
}

fn height_of(f: &Folded, k: usize) -> Real {
    let (tris, _) = f.mesh.triangulate();
    fold_height(
        &f.mesh.positions,
        &tris,
        &f.folds[k].ridge,
        4,
        f.folds[k].drawn,
    )
    .expect("a measurable fold")
}

#[test]
fn subdivision_keeps_the_sheet_manifold_and_the_ridge_a_chain_of_edges() {
    let mesh = sheet();
    let before = Topology::build(&mesh).unwrap();
    let f = subdivide(&mesh, &[across()], &FoldParams::default()).unwrap();
    let after = Topology::build(&f.mesh).expect("manifold after the split");
    // The line stays inside the sheet: its open boundary is the same length.
    assert_eq!(before.boundary_edges.len(), after.boundary_edges.len());
    let ridge = &f.folds[0].ridge;
    assert!(
        ridge.len() >= 30,
        "{} crossings for 0.8 m over 5 cm cells",
        ridge.len()
    );
    let e = edges(&f.mesh);
    for w in ridge.windows(2) {
        assert!(
            e.contains(&(w[0].min(w[1]), w[0].max(w[1]))),
            "{w:?} not joined"
        );
    }
    // Vertices off the line keep their places; every vertex on it is on the ridge.
    for (v, p) in mesh.positions.iter().enumerate() {
        assert!(f.is_new[v] || f.mesh.positions[v] == *p);
    }
    assert_eq!(f.is_new.iter().filter(|b| **b).count(), ridge.len());
    // Spiky: the new vertices stand the drawn height above the plane over the line's middle,
    // less toward its ends, none at them.
    let ys: Vec<Real> = ridge
        .iter()
        .map(|&v| f.mesh.positions[v as usize].y)
        .collect();
    let middle = &ys[ys.len() / 4..3 * ys.len() / 4];
    assert!(middle.iter().all(|y| (y - 0.04).abs() < 1e-12), "{ys:?}");
    assert!(
        ys[0].abs() < 1e-12 && ys[ys.len() - 1].abs() < 1e-12,
        "{ys:?}"
    );
    assert!(ys.iter().all(|y| (0.0..=0.04 + 1e-12).contains(y)));
    // Total area of the flat sheet kept by the split (measured before displacement).
    let flat = {
        let mut m = f.mesh.clone();
        m.positions.iter_mut().for_each(|p| p.y = 0.0);
        assert!(
            Topology::build(&m).is_ok(),
            "no face folded flat to nothing"
        );
        (0..m.faces.len()).map(|i| m.face_area(i)).sum::<Real>()
    };
    assert!((flat - 1.0).abs() < 1e-9, "{flat}");
}

#[test]
fn a_fold_on_a_closed_surface_leaves_it_closed() {
    let ball = icosphere(0.3, 3, Vec3::zeros());
    let line = ridge(
        &[[-0.25, 0.2, 0.1], [0.0, 0.3, 0.05], [0.25, 0.2, 0.0]],
        0.02,
    );
    let f = subdivide(&ball, &[line], &FoldParams::default()).unwrap();
    let topo = Topology::build(&f.mesh).expect("manifold");
    assert!(topo.is_closed());
    assert!(f.folds[0].ridge.len() > 5);
    // Outward: the ridge's middle ends farther from the centre than the sphere.
    let r = &f.folds[0].ridge;
    for &v in &r[r.len() / 4..3 * r.len() / 4] {
        assert!(f.mesh.positions[v as usize].norm() > 0.31);
    }
}

#[test]
fn the_constraint_keeps_the_ridge_height_and_plain_smoothing_lowers_it() {
    let base = FoldParams {
        rounds: vec![],
        ..FoldParams::default()
    };
    let spiky = build(&sheet(), &[across()], &base).unwrap();
    let h0 = height_of(&spiky, 0);
    assert!((h0 - 0.04).abs() < 1e-9, "spiky {h0}");
    let with = |r: Round| FoldParams {
        rounds: vec![r; 6],
        ..base.clone()
    };
    let held = build(&sheet(), &[across()], &with(Round::Constrained)).unwrap();
    let plain = build(&sheet(), &[across()], &with(Round::Plain)).unwrap();
    let (hc, hp) = (height_of(&held, 0), height_of(&plain, 0));
    assert!(hc > 0.95 * h0, "constrained {hc} of {h0}");
    assert!(hp < 0.5 * h0, "plain {hp} of {h0}");
    // Constrained smoothing widened the fold: old vertices next to the ridge were drawn up.
    let lifted = held
        .mesh
        .positions
        .iter()
        .zip(&held.is_new)
        .filter(|(p, n)| !**n && p.y > 0.005)
        .count();
    assert!(lifted > 20, "{lifted}");
}

#[test]
fn a_valley_goes_in_and_measures_negative() {
    let mut line = across();
    line.kind = FoldKind::Valley;
    let f = build(&sheet(), &[line], &FoldParams::default()).unwrap();
    assert!(f.folds[0].drawn < 0.0);
    let h = height_of(&f, 0);
    assert!(h < -0.03, "{h}");
    assert!(fold_retention(h, f.folds[0].drawn) > 0.75);
}

#[test]
fn only_bend_springs_across_the_line_change() {
    let f = build(&sheet(), &[across()], &FoldParams::default()).unwrap();
    let edits = bend_edits(&f, &FoldParams::default());
    assert!(edits.len() + 2 >= f.folds[0].ridge.len(), "{}", edits.len());
    // The line runs along x near z = 0.02: each spring joins a vertex on either side of it, and
    // neither end is on the ridge.
    let line_z = |x: Real| {
        if x < 0.0 {
            0.013 + (0.031 - 0.013) * (x + 0.4) / 0.4
        } else {
            0.031 + (0.017 - 0.031) * x / 0.4
        }
    };
    for e in &edits {
        let (a, b) = (
            f.mesh.positions[e.a as usize],
            f.mesh.positions[e.b as usize],
        );
        assert!(!f.is_new[e.a as usize] && !f.is_new[e.b as usize]);
        let (sa, sb) = (a.z - line_z(a.x), b.z - line_z(b.x));
        assert!(sa * sb < 0.0, "{a:?} {b:?} on one side");
        assert_eq!((e.rest_scale, e.stiffness_scale), (0.9, 10.0));
    }
}

#[test]
fn holding_the_fold_changes_the_springs_across_its_smoothed_region() {
    let line = FoldParams::default();
    let whole = FoldParams {
        hold: Hold::Fold,
        ..FoldParams::default()
    };
    let f = build(&sheet(), &[across()], &line).unwrap();
    let crossing = bend_edits(&f, &line);
    let held = bend_edits(&f, &whole);
    // Every spring across the line is among them, and many more beside it.
    for e in &crossing {
        assert!(
            held.iter().any(|h| (h.a, h.b) == (e.a, e.b)),
            "{e:?} left out"
        );
    }
    assert!(
        held.len() > 3 * crossing.len(),
        "{} vs {}",
        held.len(),
        crossing.len()
    );
    // None reaches past the smoothed region: both ends within one edge of it (a bend spring
    // joins the two vertices opposite an edge whose ends are in the region).
    let ring = ring_of(&f.mesh);
    let near =
        |v: u32| f.region[v as usize] || ring[v as usize].iter().any(|&u| f.region[u as usize]);
    for e in &held {
        assert!(near(e.a) && near(e.b), "{e:?} outside the fold");
    }
    let outside = f.region.iter().filter(|r| !**r).count();
    assert!(outside > 100, "the region is the whole sheet");
}

#[test]
fn a_fold_amid_cloth_rougher_than_it_or_far_coarser_is_not_measured() {
    let f = build(&sheet(), &[across()], &FoldParams::default()).unwrap();
    let (tris, _) = f.mesh.triangulate();
    let ridge = &f.folds[0].ridge;
    let drawn = f.folds[0].drawn;
    let on = |x: &[Vec3]| fold_height(x, &tris, ridge, 4, drawn);
    assert!(on(&f.mesh.positions).is_some());
    // The cloth around the fold bumped up and down by up to `a` (deterministic noise).
    let bumped = |a: Real| {
        let mut r = 12345u64;
        let mut x = f.mesh.positions.clone();
        for (p, inside) in x.iter_mut().zip(&f.region) {
            r = r
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            if !inside {
                p.y += a * ((r >> 33) as Real / (1u64 << 31) as Real * 2.0 - 1.0);
            }
        }
        x
    };
    // Bumps of a tenth of the fold's height leave it measurable, and measured near its height;
    // bumps as tall as the fold make it not measurable.
    let h = on(&bumped(0.1 * drawn)).expect("a fold amid small bumps is measured");
    let clean = on(&f.mesh.positions).unwrap();
    assert!((h - clean).abs() < 0.15 * drawn, "{h} vs {clean}");
    assert_eq!(on(&bumped(drawn)), None);
    // A fold low beside the cells it is drawn on (2 cm on 5 cm cells): its surroundings lie
    // about ten heights out, another part of the garment, and it is not measured.
    let mut low = across();
    low.height = 0.02;
    let f = build(&sheet(), &[low], &FoldParams::default()).unwrap();
    let (tris, _) = f.mesh.triangulate();
    let g = &f.folds[0];
    assert_eq!(
        fold_height(&f.mesh.positions, &tris, &g.ridge, 4, g.drawn),
        None
    );
}

#[test]
fn bad_lines_are_errors_naming_the_fold() {
    let p = FoldParams::default();
    let m = sheet();
    let ok = across();
    let mut lines = vec![ok.clone(), ridge(&[[0.0, 0.0, 0.3]], 0.02)];
    let e = subdivide(&m, &lines, &p).unwrap_err();
    assert_eq!(e, FoldError::TooFewPoints { fold: 1, count: 1 });
    lines[1] = ridge(&[[0.0, 0.0, 0.3], [Real::NAN, 0.0, 0.3]], 0.02);
    assert!(matches!(
        subdivide(&m, &lines, &p),
        Err(FoldError::NonFinitePoint {
            fold: 1,
            point: 1,
            ..
        })
    ));
    for h in [0.0, -0.01, Real::NAN, 2.0] {
        lines[1] = ridge(&[[0.0, 0.0, 0.3], [0.2, 0.0, 0.3]], h);
        assert!(
            matches!(
                subdivide(&m, &lines, &p),
                Err(FoldError::BadHeight { fold: 1, .. })
            ),
            "{h}"
        );
    }
    lines[1] = ridge(&[[0.0, 0.0, 0.3], [0.2, 0.5, 0.3]], 0.02);
    let e = subdivide(&m, &lines, &p).unwrap_err();
    assert!(
        matches!(
            e,
            FoldError::OffGarment {
                fold: 1,
                point: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(e.to_string().contains("fold 1: point 1 is 0.500 m"), "{e}");
    // 2 cm past the sheet's edge is snapped onto it.
    lines[1] = ridge(&[[0.0, 0.0, 0.3], [0.52, 0.0, 0.3]], 0.02);
    assert!(subdivide(&m, &lines, &p).is_ok());
    // Across a slot cut into the sheet: the line would leave the cloth.
    let mut slotted = m.clone();
    slotted.faces.retain(|f| {
        let c = f
            .vertices()
            .iter()
            .map(|&v| m.positions[v as usize])
            .sum::<Vec3>()
            / 4.0;
        !(c.x.abs() < 0.1 && c.z > 0.2)
    });
    lines[1] = ridge(&[[-0.3, 0.0, 0.35], [0.3, 0.0, 0.35]], 0.02);
    let e = subdivide(&slotted, &lines, &p).unwrap_err();
    assert_eq!(
        e,
        FoldError::LeavesGarment {
            fold: 1,
            segment: 0
        }
    );
    lines[1] = ridge(&[[0.0, 0.0, 0.3], [0.2, 0.0, 0.3], [0.05, 0.0, 0.31]], 0.02);
    assert!(matches!(
        subdivide(&m, &lines, &p),
        Err(FoldError::SelfCrossing {
            fold: 1,
            segment: 1
        })
    ));
    lines[1] = ridge(&[[0.0, 0.0, -0.2], [0.0, 0.0, 0.2]], 0.02);
    let along = subdivide(&m, &lines[1..], &p).unwrap();
    // Drawn along a grid line, the fold takes the grid's vertices: nothing is added.
    assert_eq!(along.mesh.positions.len(), m.positions.len());
    assert!(
        along.folds[0].ridge.len() >= 6,
        "{:?}",
        along.folds[0].ridge
    );
    assert_eq!(
        subdivide(&m, &lines, &p).unwrap_err(),
        FoldError::CrossesFold { fold: 1, other: 0 }
    );
    lines[1] = ridge(&[[0.101, 0.0, 0.301], [0.102, 0.0, 0.302]], 0.02);
    assert!(matches!(
        subdivide(&m, &lines, &p),
        Err(FoldError::TooShort {
            fold: 1,
            crossed: 0
        })
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Random lines on random sheets either build a fold with finite positions and a manifold
    /// mesh, or are refused with an error; never NaN, never a panic.
    #[test]
    fn random_lines_on_random_sheets_never_give_nan(
        nx in 2usize..16, nz in 2usize..16,
        pts in proptest::collection::vec((-0.7f64..0.7, -0.05f64..0.05, -0.7f64..0.7), 2..6),
        height in 0.001f64..0.2,
        rounds in proptest::collection::vec(any::<bool>(), 0..5),
        valley in any::<bool>(),
        sorted in any::<bool>(),
    ) {
        let mesh = grid_xz(nx, nz, 1.0, 1.0, 0.0);
        let mut pts = pts;
        if sorted {
            // Most lines a person draws run one way.
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
        let line = FoldLine {
            kind: if valley { FoldKind::Valley } else { FoldKind::Ridge },
            points: pts.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect(),
            height,
        };
        let p = FoldParams {
            rounds: rounds.iter().map(|&c| if c { Round::Constrained } else { Round::Plain }).collect(),
            snap: 0.3,
            ..FoldParams::default()
        };
        if let Ok(f) = build(&mesh, &[line], &p) {
            prop_assert!(f.mesh.positions.iter().all(|v| v.iter().all(|c| c.is_finite())));
            prop_assert!(Topology::build(&f.mesh).is_ok());
            let e = edges(&f.mesh);
            for w in f.folds[0].ridge.windows(2) {
                prop_assert!(e.contains(&(w[0].min(w[1]), w[0].max(w[1]))));
            }
            for b in bend_edits(&f, &p) {
                prop_assert!(b.a < b.b && (b.b as usize) < f.mesh.positions.len());
            }
        }
    }
}

/// Each added vertex was made on its recorded original edge (its spiky position is there, raised
/// by the line's height along the sheet's normal), and carrying the fold onto the same sheet
/// moved gives the folded sheet moved, onto itself the folded sheet.
#[test]
fn added_vertices_come_from_their_edges_and_a_fold_carries_onto_a_moved_sheet() {
    let mesh = sheet();
    let f = subdivide(&mesh, &[across()], &FoldParams::default()).unwrap();
    let n0 = mesh.positions.len();
    assert_eq!(f.made_on.len(), f.mesh.positions.len() - n0);
    assert!(!f.made_on.is_empty());
    for (k, &(a, b, t)) in f.made_on.iter().enumerate() {
        let (xa, xb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
        assert!(
            (xa - xb).norm() < 0.08,
            "an edge of the 5 cm grid (or its diagonal)"
        );
        assert!(t > 0.0 && t < 1.0);
        let on_edge = xa + (xb - xa) * t;
        let x = f.mesh.positions[n0 + k];
        // The spiky fold: straight up from the edge by the drawn height (tapered at the ends).
        assert!((x.x - on_edge.x).abs() < 1e-12 && (x.z - on_edge.z).abs() < 1e-12);
        assert!(x.y >= -1e-12 && x.y <= 0.04 + 1e-12);
    }
    let folded = build(&mesh, &[across()], &FoldParams::default()).unwrap();
    let same = folded.carried(&mesh.positions, &mesh.positions).unwrap();
    assert_eq!(same, folded.mesh.positions);
    let lift = Vec3::new(0.1, 1.0, -0.2);
    let moved: Vec<Vec3> = mesh.positions.iter().map(|p| p + lift).collect();
    let carried = folded.carried(&mesh.positions, &moved).unwrap();
    for (c, x) in carried.iter().zip(&folded.mesh.positions) {
        assert!((c - (x + lift)).norm() < 1e-12);
    }
    assert!(folded.carried(&mesh.positions, &moved[1..]).is_none());
    // Turned about an axis in the sheet's plane, the fold turns with it: the folded sheet turned.
    let turn = tryon_core::math::UnitQuat::from_axis_angle(&Vec3::x_axis(), 0.5);
    let turned: Vec<Vec3> = mesh.positions.iter().map(|p| turn * p).collect();
    let carried = folded.carried(&mesh.positions, &turned).unwrap();
    for (c, x) in carried.iter().zip(&folded.mesh.positions) {
        assert!((c - turn * x).norm() < 1e-9, "{c} against {}", turn * x);
    }
}
