//! Tests of the detail model on hand-built fine surfaces: no forces no wrinkles, compression
//! restores length, dh >= 0 and no NaN under random coarse states (proptest), fine collision
//! against an analytic sphere, normal blending.

use crate::{Detail, DetailParams, WrinkleModel};
use proptest::prelude::*;
use tryon_core::frames::{CoarseFrame, Contact, FineSurface};
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_core::mesh::{PolyMesh, grid_xz};
use tryon_core::stages::Collider;

/// The PN-free refiner for tests: each coarse triangle's lattice evaluated linearly, normals +y
/// unless given. (pnt-surface is a sibling stage crate, so it is not used here.)
pub(crate) fn linear_fine(mesh: &PolyMesh, x: &[Vec3], level: u8) -> FineSurface {
    let (tris, _) = mesh.triangulate();
    let n = 1u32 << level;
    let per = tryon_core::frames::lattice_len(n);
    let mut fine = FineSurface {
        segments: n,
        coarse_triangles: tris.clone(),
        ..FineSurface::default()
    };
    let mut keyed: std::collections::HashMap<(u32, u32, u32), u32> = Default::default();
    fine.positions.extend_from_slice(x);
    fine.sources = (0..x.len())
        .map(|_| tryon_core::frames::FineVertexSource::default())
        .collect();
    for (f, t) in tris.iter().enumerate() {
        let mut lat = vec![0u32; per];
        for j in 0..=n {
            for i in 0..=n - j {
                let k = n - i - j;
                let bary = [
                    k as Real / n as Real,
                    i as Real / n as Real,
                    j as Real / n as Real,
                ];
                let idx = tryon_core::frames::lattice_index(n, i, j);
                let corner = [(k == n, t[0]), (i == n, t[1]), (j == n, t[2])];
                if let Some((_, v)) = corner.iter().find(|c| c.0) {
                    lat[idx] = *v;
                    fine.sources[*v as usize] = tryon_core::frames::FineVertexSource {
                        face: f as u32,
                        bary,
                        level: 0,
                    };
                    continue;
                }
                // Key edge points by their coarse edge so both triangles share them.
                let key = if j == 0 {
                    Some((t[0], t[1], i))
                } else if k == 0 {
                    Some((t[1], t[2], j))
                } else if i == 0 {
                    Some((t[2], t[0], n - j))
                } else {
                    None
                }
                .map(|(a, b, s)| if a < b { (a, b, s) } else { (b, a, n - s) });
                let p = x[t[0] as usize] * bary[0]
                    + x[t[1] as usize] * bary[1]
                    + x[t[2] as usize] * bary[2];
                let v = match key.and_then(|k| keyed.get(&k).copied()) {
                    Some(v) => v,
                    None => {
                        fine.positions.push(p);
                        fine.sources.push(tryon_core::frames::FineVertexSource {
                            face: f as u32,
                            bary,
                            level: 1,
                        });
                        let v = fine.positions.len() as u32 - 1;
                        if let Some(k) = key {
                            keyed.insert(k, v);
                        }
                        v
                    }
                };
                lat[idx] = v;
            }
        }
        for j in 0..n {
            for i in 0..n - j {
                let at = |i: u32, j: u32| lat[tryon_core::frames::lattice_index(n, i, j)];
                fine.triangles.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
                if i + j + 1 < n {
                    fine.triangles
                        .push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
        }
        fine.lattice.extend(lat);
    }
    let mut normals = Vec::new();
    vertex_normals(&fine.positions, &fine.triangles, &mut normals);
    // Facing +y for the sheets used here.
    fine.normals = normals
        .into_iter()
        .map(|n| if n.y < 0.0 { -n } else { n })
        .collect();
    fine
}

/// Spring forces along the coarse mesh's edges with the rest shape's lengths.
fn spring_forces(mesh: &PolyMesh, x: &[Vec3], k: Real) -> Vec<Vec3> {
    let (tris, _) = mesh.triangulate();
    let mut f = vec![Vec3::zeros(); x.len()];
    let mut seen = std::collections::HashSet::new();
    for t in &tris {
        for e in 0..3 {
            let (a, b) = (t[e].min(t[(e + 1) % 3]), t[e].max(t[(e + 1) % 3]));
            if !seen.insert((a, b)) {
                continue;
            }
            let (a, b) = (a as usize, b as usize);
            let rest = (mesh.positions[a] - mesh.positions[b]).norm();
            let d = x[b] - x[a];
            let l = d.norm();
            let fa = d / l * (k * (l - rest));
            f[a] += fa;
            f[b] -= fa;
        }
    }
    f
}

pub(crate) fn frame(x: &[Vec3], forces: Vec<Vec3>) -> CoarseFrame {
    let mut c = CoarseFrame::at_rest(x.to_vec());
    c.elastic_force = forces;
    c
}

#[test]
fn no_force_and_no_compression_give_no_height() {
    let mesh = grid_xz(4, 4, 1.0, 1.0, 0.0);
    let x = mesh.positions.clone();
    let mut d = Detail::new(
        &linear_fine(&mesh, &x, 2),
        &mesh.positions,
        DetailParams::default(),
    )
    .unwrap();
    for _ in 0..5 {
        let mut fine = linear_fine(&mesh, &x, 2);
        let reference = fine.positions.clone();
        d.wrinkle(&frame(&x, vec![Vec3::zeros(); x.len()]), &mut fine);
        assert!(d.height.iter().all(|h| *h == 0.0));
        assert_eq!(fine.positions, reference);
    }
}

/// A 8 x 4 sheet squeezed along x, most in the middle, with its spring forces there.
fn squeezed_sheet() -> (PolyMesh, Vec<Vec3>, Vec<Vec3>) {
    let mesh = grid_xz(8, 4, 1.0, 0.5, 0.0);
    let x: Vec<Vec3> = mesh
        .positions
        .iter()
        .map(|p| {
            Vec3::new(
                p.x * (0.8 - 0.15 * (std::f64::consts::PI * p.x).cos().abs()),
                p.y,
                p.z,
            )
        })
        .collect();
    let forces = spring_forces(&mesh, &x, 50.0);
    (mesh, x, forces)
}

/// A sheet squeezed along x, most in the middle, held by its spring forces: with wrinkles on,
/// the fine paths along compressed coarse edges come closer to their rest lengths (P1's force
/// model a little, the compression relief by more than half).
#[test]
fn compression_wrinkles_and_restores_length() {
    for (model, most) in [
        (WrinkleModel::Force, 0.99),
        (WrinkleModel::Compression, 0.5),
    ] {
        squeezed_sheet_wrinkles(model, most);
    }
}

fn squeezed_sheet_wrinkles(model: WrinkleModel, most: Real) {
    let (mesh, x, forces) = squeezed_sheet();
    let run = |wrinkles: bool| {
        let p = DetailParams {
            wrinkles,
            model,
            ..DetailParams::default()
        };
        let mut d = Detail::new(&linear_fine(&mesh, &x, 2), &mesh.positions, p).unwrap();
        let mut fine = FineSurface::default();
        for _ in 0..30 {
            fine = linear_fine(&mesh, &x, 2);
            d.wrinkle(&frame(&x, forces.clone()), &mut fine);
        }
        let (err, count) = d.length_error(&fine.positions);
        (err, count, d.stats.max_height, fine)
    };
    let (off, count, h_off, _) = run(false);
    let (on, count_on, h_on, fine) = run(true);
    assert_eq!(count, count_on);
    assert!(count > 10, "{count} compressed edges");
    assert_eq!(h_off, 0.0);
    assert!(h_on > 1e-4, "highest wrinkle {h_on} m");
    assert!(
        on < most * off,
        "{model:?}: length error with wrinkles {on}, without {off}"
    );
    assert!(
        fine.positions.iter().all(|p| p.y >= -1e-12),
        "dh >= 0 keeps the sheet above its reference"
    );
}

/// A sphere of radius r at c, exactly.
struct Sphere {
    c: Vec3,
    r: Real,
}

impl Collider for Sphere {
    fn name(&self) -> &'static str {
        "sphere"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities::NONE
    }
    fn update(&mut self, _body: &tryon_core::frames::BodyFrame) {}
    fn resolve(&mut self, points: &mut [Vec3], _contacts: &mut Vec<Contact>) {
        for p in points.iter_mut() {
            let d = *p - self.c;
            if d.norm() < self.r {
                *p = self.c + d.normalize() * self.r;
            }
        }
    }
    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        Some((p - self.c).norm() - self.r)
    }
}

/// A coarse sheet whose vertices sit on a sphere's top: the flat triangles between them cut into
/// it. After the fine collision no fine vertex is inside (beyond 1e-6 m), and only part of the
/// lattice was probed.
#[test]
fn fine_collision_lifts_the_lattice_out_of_a_sphere() {
    let mesh = grid_xz(6, 6, 1.2, 1.2, 0.0);
    let sphere = Sphere {
        c: Vec3::new(0.0, -0.5, 0.0),
        r: 0.9,
    };
    // Vertices within the sphere's cap are put on it (2 mm out); the rest stay flat at y = 0.
    let x: Vec<Vec3> = mesh
        .positions
        .iter()
        .map(|p| {
            let d = p - sphere.c;
            if d.norm() < sphere.r {
                sphere.c + d.normalize() * (sphere.r + 0.002)
            } else {
                *p
            }
        })
        .collect();
    let mut fine = linear_fine(&mesh, &x, 3);
    let total = fine.positions.len();
    let inside_before = fine
        .positions
        .iter()
        .filter(|p| sphere.signed_distance(p).unwrap() < 0.0)
        .count();
    assert!(
        inside_before > 20,
        "{inside_before} fine vertices start inside"
    );
    let mut d = Detail::new(
        &fine,
        &mesh.positions,
        DetailParams {
            wrinkles: false,
            ..DetailParams::default()
        },
    )
    .unwrap();
    let mut col = Sphere {
        c: sphere.c,
        r: sphere.r,
    };
    let coarse = frame(&x, vec![Vec3::zeros(); x.len()]);
    d.wrinkle(&coarse, &mut fine);
    d.fine_collision(&coarse, &mut fine, &mut col);
    let worst = fine
        .positions
        .iter()
        .map(|p| sphere.signed_distance(p).unwrap())
        .fold(Real::INFINITY, Real::min);
    assert!(worst > -1e-6, "deepest fine vertex {worst} m");
    assert!(d.stats.raised >= inside_before);
    assert!(
        d.stats.probed < total,
        "probed {} of {total}",
        d.stats.probed
    );
    // Heights of raised vertices are recorded and the normals blend toward the deformed surface.
    assert!(d.raise.iter().any(|r| *r > 0.0));
    d.blend_normals(&mut fine);
    assert!(fine.normals.iter().all(|n| (n.norm() - 1.0).abs() < 1e-9));
}

/// One coarse triangle whose corners are 12 mm off a 4 cm ball (beyond the 1 cm margin), but
/// which spans it: its flat lattice cuts up to 14 mm into it between them. P1's rule (probe
/// only below a touching vertex) probes none of them; the distance bound from the corners finds
/// them all. (The demo's first walking frame had such an edge midpoint 2.3 mm inside a thigh.)
#[test]
fn a_triangle_spanning_a_small_part_is_probed_though_its_corners_are_clear() {
    let (r, rho, lift): (Real, Real, Real) = (0.04, 0.045, 0.012);
    let h = ((r + lift) * (r + lift) - rho * rho).sqrt();
    let x: Vec<Vec3> = (0..3)
        .map(|k| {
            let a = std::f64::consts::TAU * k as Real / 3.0;
            Vec3::new(rho * a.cos(), h, rho * a.sin())
        })
        .collect();
    let mesh = PolyMesh::from_triangles(x.clone(), &[[0, 2, 1]]).unwrap();
    let ball = Sphere {
        c: Vec3::zeros(),
        r,
    };
    let mut fine = linear_fine(&mesh, &x, 2);
    let depth = |f: &FineSurface| {
        f.positions
            .iter()
            .map(|p| -ball.signed_distance(p).unwrap())
            .fold(Real::NEG_INFINITY, Real::max)
    };
    assert!(x.iter().all(|p| ball.signed_distance(p).unwrap() > 0.011));
    assert!(depth(&fine) > 0.010, "starts {} m deep", depth(&fine));
    let params = DetailParams {
        wrinkles: false,
        ..DetailParams::default()
    };
    let mut d = Detail::new(&fine, &mesh.positions, params).unwrap();
    let mut col = Sphere {
        c: Vec3::zeros(),
        r,
    };
    let coarse = frame(&x, vec![Vec3::zeros(); 3]);
    d.wrinkle(&coarse, &mut fine);
    d.fine_collision(&coarse, &mut fine, &mut col);
    assert!(depth(&fine) < 1e-6, "left {} m deep", depth(&fine));
    assert!(d.stats.raised > 0);
}

#[test]
fn bad_parameters_and_layouts_are_named() {
    let mesh = grid_xz(2, 2, 1.0, 1.0, 0.0);
    let fine = linear_fine(&mesh, &mesh.positions, 1);
    let e = Detail::new(
        &fine,
        &mesh.positions,
        DetailParams {
            h_normal: 0.0,
            ..DetailParams::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("h_normal"), "{e}");
    let e = Detail::new(
        &FineSurface::default(),
        &mesh.positions,
        DetailParams::default(),
    )
    .unwrap_err();
    assert!(e.to_string().contains("refine"), "{e}");
    let e = Detail::new(&fine, &mesh.positions[..3], DetailParams::default()).unwrap_err();
    assert!(e.to_string().contains("vertex"), "{e}");
    // A lattice whose neighbours no fine triangle joins (the triangles were lost).
    let mut torn = linear_fine(&mesh, &mesh.positions, 2);
    torn.triangles.clear();
    let e = Detail::new(&torn, &mesh.positions, DetailParams::default()).unwrap_err();
    assert!(e.to_string().contains("not joined"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// Random coarse states with random forces: heights stay >= 0 and everything finite, frame
    /// after frame.
    #[test]
    fn random_coarse_states_keep_heights_nonnegative_and_finite(
        noise in prop::collection::vec(prop::array::uniform3(-0.3..0.3f64), 25),
        force in prop::collection::vec(prop::array::uniform3(-50.0..50.0f64), 25),
        k_out in 0.0..5.0f64,
        force_model in any::<bool>(),
    ) {
        let mesh = grid_xz(4, 4, 1.0, 1.0, 0.0);
        let x: Vec<Vec3> = mesh.positions.iter().zip(&noise).map(|(p, d)| p + Vec3::new(d[0], d[1], d[2])).collect();
        let f: Vec<Vec3> = force.iter().map(|d| Vec3::new(d[0], d[1], d[2])).collect();
        let model = if force_model { WrinkleModel::Force } else { WrinkleModel::Compression };
        let p = DetailParams { k_out_plane: k_out, model, ..DetailParams::default() };
        let mut d = Detail::new(&linear_fine(&mesh, &x, 2), &mesh.positions, p).unwrap();
        let mut col = Sphere { c: Vec3::new(0.0, -1.0, 0.0), r: 0.9 };
        for _ in 0..4 {
            let mut fine = linear_fine(&mesh, &x, 2);
            let coarse = frame(&x, f.clone());
            d.wrinkle(&coarse, &mut fine);
            d.fine_collision(&coarse, &mut fine, &mut col);
            d.blend_normals(&mut fine);
            prop_assert!(d.height.iter().all(|h| *h >= 0.0 && h.is_finite()));
            prop_assert!(fine.positions.iter().all(|p| p.iter().all(|c| c.is_finite())));
            prop_assert!(fine.normals.iter().all(|n| (n.norm() - 1.0).abs() < 1e-9));
        }
    }
}

/// Normal blending gathers the deformed normal only at raised vertices; it must give what blending
/// over normals of the whole deformed surface (`vertex_normals`) gives.
#[test]
fn gathered_normals_match_the_whole_surface_normals() {
    let (mesh, x, forces) = squeezed_sheet();
    let mut d = Detail::new(
        &linear_fine(&mesh, &x, 2),
        &mesh.positions,
        DetailParams::default(),
    )
    .unwrap();
    let mut fine = FineSurface::default();
    for _ in 0..30 {
        fine = linear_fine(&mesh, &x, 2);
        d.wrinkle(&frame(&x, forces.clone()), &mut fine);
    }
    let raised = d.height.iter().filter(|h| **h > 0.0).count();
    assert!(raised > 0 && raised < d.height.len(), "{raised} raised");
    let mut whole = d.clone();
    whole.tri_count = usize::MAX; // forces the whole-surface path
    let (mut a, mut b) = (fine.clone(), fine);
    d.blend_normals(&mut a);
    whole.blend_normals(&mut b);
    for (i, (p, q)) in a.normals.iter().zip(&b.normals).enumerate() {
        assert!((p - q).norm() < 1e-12, "vertex {i}: {p:?} against {q:?}");
    }
}

/// The judgement's reference figures come from the reference surface alone: on the linear
/// refinement each coarse edge's fine path is the straight edge, so its compression and whether it
/// is within 2% of rest follow from the coarse positions; with wrinkles off the output is the
/// reference.
#[test]
fn the_length_judgement_reads_compression_from_the_reference() {
    let (mesh, x, forces) = squeezed_sheet();
    let (tris, _) = mesh.triangulate();
    let mut edges = std::collections::BTreeSet::new();
    for t in &tris {
        for k in 0..3 {
            let (a, b) = (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]));
            edges.insert((a as usize, b as usize));
        }
    }
    let compression: Vec<Real> = (edges.iter())
        .map(|&(a, b)| {
            let rest = (mesh.positions[a] - mesh.positions[b]).norm();
            1.0 - (x[a] - x[b]).norm() / rest
        })
        .filter(|c| *c > 1e-12)
        .collect();
    let within = compression.iter().filter(|c| **c <= 0.02).count();
    let mean = compression.iter().sum::<Real>() / compression.len() as Real;
    let run = |wrinkles: bool| {
        let p = DetailParams {
            wrinkles,
            ..DetailParams::default()
        };
        let mut d = Detail::new(&linear_fine(&mesh, &x, 2), &mesh.positions, p).unwrap();
        let mut fine = linear_fine(&mesh, &x, 2);
        for _ in 0..10 {
            fine = linear_fine(&mesh, &x, 2);
            d.wrinkle(&frame(&x, forces.clone()), &mut fine);
        }
        d.length_judgement(&fine.positions)
    };
    for wrinkles in [false, true] {
        let j = run(wrinkles);
        assert_eq!(j.edges, compression.len());
        assert!(
            (j.reference_error - mean).abs() < 1e-9,
            "{j:?}, mean {mean}"
        );
        let share = within as Real / compression.len() as Real;
        assert!((j.reference_restored - share).abs() < 1e-12, "{j:?}");
        if !wrinkles {
            assert!((j.error - j.reference_error).abs() < 1e-12);
            assert_eq!(j.restored, j.reference_restored);
        }
    }
    assert!(run(true).error < run(false).error);
}
