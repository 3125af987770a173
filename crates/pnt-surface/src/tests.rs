//! Tests of the PN patch and the refiner: interpolation, flatness, shared edges, watertightness,
//! levels, and random coarse states (proptest).

use crate::refine::point_level;
use crate::{PnPatch, PnRefiner, RefineError};
use proptest::prelude::*;
use tryon_core::frames::{FineSurface, lattice_index, lattice_len};
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_core::mesh::{PolyMesh, grid_xz};
use tryon_core::shapes::icosphere;
use tryon_core::topology::Topology;

fn unit(x: Real, y: Real, z: Real) -> Vec3 {
    Vec3::new(x, y, z).normalize()
}

#[test]
fn a_patch_interpolates_its_corners_and_corner_normals() {
    let p = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.2, 0.0),
        Vec3::new(0.1, 0.0, 1.0),
    ];
    let n = [
        unit(0.1, 1.0, 0.0),
        unit(-0.3, 1.0, 0.1),
        unit(0.0, 1.0, -0.4),
    ];
    let patch = PnPatch::new(p, n);
    for k in 0..3 {
        let mut b = [0.0; 3];
        b[k] = 1.0;
        assert!((patch.position(b) - p[k]).norm() < 1e-15, "corner {k}");
        assert!((patch.normal(b) - n[k]).norm() < 1e-12, "corner normal {k}");
    }
    // Curved: the centre leaves the flat triangle's plane.
    let c = patch.position([1.0 / 3.0; 3]);
    let flat = (p[0] + p[1] + p[2]) / 3.0;
    assert!((c - flat).norm() > 1e-3);
}

#[test]
fn flat_input_with_equal_normals_stays_flat() {
    let mesh = grid_xz(5, 4, 1.0, 0.8, 0.3);
    let mut r = PnRefiner::new(&mesh, 3).unwrap();
    let normals = vec![Vec3::y(); mesh.positions.len()];
    let mut fine = FineSurface::default();
    r.evaluate(&mesh.positions, &normals, &mut fine);
    for (p, n) in fine.positions.iter().zip(&fine.normals) {
        assert!(
            (p.y - 0.3).abs() < 1e-14,
            "fine vertex off the plane: {p:?}"
        );
        assert!((n - Vec3::y()).norm() < 1e-14);
    }
    // And inside the coarse footprint.
    let (lo, hi) = mesh.positions.iter().fold(
        (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    assert!(
        fine.positions
            .iter()
            .all(|p| p.x >= lo.x - 1e-12 && p.x <= hi.x + 1e-12)
    );
    assert!(
        fine.positions
            .iter()
            .all(|p| p.z >= lo.z - 1e-12 && p.z <= hi.z + 1e-12)
    );
}

/// Every coarse edge shared by two triangles: both patches give the same points along it, and the
/// fine vertex there is one vertex used by both lattices.
#[test]
fn neighbouring_patches_share_their_edge_vertices_exactly() {
    let mut mesh = icosphere(1.0, 1, Vec3::zeros());
    for (k, p) in mesh.positions.iter_mut().enumerate() {
        *p *= 1.0 + 0.05 * ((k * 37 % 11) as Real / 11.0);
    }
    let (tris, _) = mesh.triangulate();
    let mut normals = Vec::new();
    vertex_normals(&mesh.positions, &tris, &mut normals);
    let level = 3;
    let mut r = PnRefiner::new(&mesh, level).unwrap();
    let mut fine = FineSurface::default();
    r.evaluate(&mesh.positions, &normals, &mut fine);
    let n = fine.segments;
    let per = lattice_len(n);
    // (edge) -> list of (fine vertex, point) seen from each triangle.
    let mut seen: std::collections::HashMap<(u32, u32, u32), (u32, Vec3)> = Default::default();
    let mut shared = 0;
    for (f, t) in tris.iter().enumerate() {
        let patch = r.patch(f).unwrap();
        for s in 1..n {
            for (a, b, i, j) in [
                (t[0], t[1], s, 0),
                (t[1], t[2], n - s, s),
                (t[2], t[0], 0, n - s),
            ] {
                let k = n - i - j;
                let bary = [
                    k as Real / n as Real,
                    i as Real / n as Real,
                    j as Real / n as Real,
                ];
                let q = patch.position(bary);
                let v = fine.lattice[f * per + lattice_index(n, i, j)];
                // Key: edge from the smaller end, steps from it.
                let steps = if (a, b) == (t[0], t[1]) {
                    i
                } else if (a, b) == (t[1], t[2]) {
                    j
                } else {
                    n - j
                };
                let key = if a < b {
                    (a, b, steps)
                } else {
                    (b, a, n - steps)
                };
                if let Some((v0, q0)) = seen.insert(key, (v, q)) {
                    assert_eq!(v0, v, "edge {key:?} has two fine vertices");
                    assert!((q0 - q).norm() < 1e-12, "edge {key:?}: {q0:?} vs {q:?}");
                    assert_eq!(fine.positions[v as usize], fine.positions[v0 as usize]);
                    shared += 1;
                }
            }
        }
    }
    assert_eq!(
        shared,
        120 * 7,
        "every interior edge point of the 120 edges seen twice"
    );
    // Watertight: the fine mesh of a closed coarse mesh is closed.
    let fm = PolyMesh::from_triangles(fine.positions.clone(), &fine.triangles).unwrap();
    assert!(Topology::build(&fm).unwrap().is_closed());
}

#[test]
fn counts_levels_and_the_coarse_vertices_come_first() {
    let mesh = icosphere(1.0, 1, Vec3::zeros()); // 42 vertices, 120 edges, 80 triangles
    for level in 0..=3u8 {
        let r = PnRefiner::new(&mesh, level).unwrap();
        let n = 1usize << level;
        let expected = 42 + 120 * (n - 1) + 80 * (n - 1) * n.saturating_sub(2) / 2;
        assert_eq!(r.fine_vertices(), expected, "level {level}");
        assert_eq!(r.triangles.len(), 80 * n * n);
        // Per level: level-l vertices are exactly the new points of the 2^l lattice.
        let mut by_level = vec![0usize; level as usize + 1];
        for s in &r.sources {
            by_level[s.level as usize] += 1;
        }
        let mut total = 0;
        for l in 0..=level as usize {
            let m = 1usize << l;
            let upto = 42 + 120 * (m - 1) + 80 * (m - 1) * m.saturating_sub(2) / 2;
            assert_eq!(
                total + by_level[l],
                upto,
                "level {level}, vertices of level {l}"
            );
            total = upto;
        }
    }
    assert_eq!(point_level(3, 4, 0), 1);
    assert_eq!(point_level(3, 2, 6), 2);
    assert_eq!(point_level(3, 1, 0), 3);
    assert_eq!(point_level(3, 8, 0), 0);
    let r = PnRefiner::new(&mesh, 0).unwrap();
    assert_eq!(r.fine_vertices(), 42);
    assert!(matches!(
        PnRefiner::new(&mesh, 7),
        Err(RefineError::Level { level: 7 })
    ));
}

/// On a sphere with its true normals, PN triangles come far closer to the sphere than the flat
/// coarse triangles do.
#[test]
fn pn_triangles_approximate_a_sphere_better_than_flat_ones() {
    let mesh = icosphere(1.0, 1, Vec3::zeros());
    let normals: Vec<Vec3> = mesh.positions.iter().map(|p| p.normalize()).collect();
    let mut fine = FineSurface::default();
    let worst = |fine: &FineSurface| {
        fine.positions
            .iter()
            .map(|p| (p.norm() - 1.0).abs())
            .fold(0.0, Real::max)
    };
    PnRefiner::new(&mesh, 3)
        .unwrap()
        .evaluate(&mesh.positions, &normals, &mut fine);
    let pn = worst(&fine);
    // The flat surface: the same lattice with every normal along its face (PN of a flat patch is flat).
    let (tris, _) = mesh.triangulate();
    let mut flat = 0.0;
    for t in &tris {
        let c = (mesh.positions[t[0] as usize]
            + mesh.positions[t[1] as usize]
            + mesh.positions[t[2] as usize])
            / 3.0;
        flat = Real::max(flat, 1.0 - c.norm());
    }
    assert!(pn < flat / 4.0, "PN radial error {pn}, flat {flat}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random coarse states (crumpled grids, random normals, some zero-length) never produce
    /// NaN, keep the coarse vertices exactly, and give unit normals.
    #[test]
    fn random_coarse_states_are_finite(
        level in 0u8..4,
        noise in prop::collection::vec(prop::array::uniform3(-0.3..0.3f64), 16),
        nrm in prop::collection::vec(prop::array::uniform3(-1.0..1.0f64), 16),
        collapse in 0usize..16,
    ) {
        let mesh = grid_xz(3, 3, 1.0, 1.0, 0.0);
        let mut r = PnRefiner::new(&mesh, level).unwrap();
        let mut x: Vec<Vec3> = mesh.positions.iter().zip(&noise).map(|(p, d)| p + Vec3::new(d[0], d[1], d[2])).collect();
        // A particle collapsed onto its neighbour (a zero-length edge).
        let nb = if collapse % 4 == 3 { collapse - 1 } else { collapse + 1 };
        x[collapse] = x[nb];
        let normals: Vec<Vec3> = nrm.iter().map(|d| Vec3::new(d[0], d[1], d[2]).try_normalize(1e-9).unwrap_or(Vec3::y())).collect();
        let mut fine = FineSurface::default();
        r.evaluate(&x, &normals, &mut fine);
        for (k, (p, n)) in fine.positions.iter().zip(&fine.normals).enumerate() {
            prop_assert!(p.iter().all(|c| c.is_finite()), "vertex {} is {:?}", k, p);
            prop_assert!((n.norm() - 1.0).abs() < 1e-9, "normal {} is {:?}", k, n);
        }
        prop_assert_eq!(&fine.positions[..16], &x[..]);
    }
}
