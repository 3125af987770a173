//! The referee against parry's own queries: on bodies with concave folds, moved and bent after the
//! referee was built (so its hierarchy is refitted, not rebuilt), every signed distance equals
//! the one parry's oriented `TriMesh` gives for the same shape.

use crate::ExactCollider;
use parry3d_f64::math::Point;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};
use proptest::prelude::*;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::shapes::icosphere;
use tryon_core::stages::Collider;

/// An icosphere whose radius ripples with direction (concave folds).
fn bumpy(sub: u32, amp: Real, waves: Real) -> PolyMesh {
    let mut m = icosphere(0.4, sub, Vec3::zeros());
    for p in &mut m.positions {
        let u = p.normalize();
        *p = u * 0.4 * (1.0 + amp * (waves * u.x).sin() * (waves * u.y).cos());
    }
    m
}

/// parry's signed distance to the mesh `positions` / `triangles` (negative inside).
fn parry_distance(positions: &[Vec3], triangles: &[[u32; 3]], p: &Vec3) -> Real {
    let pts: Vec<Point<Real>> = positions.iter().map(|q| Point::from(*q)).collect();
    let mesh = TriMesh::with_flags(pts, triangles.to_vec(), TriMeshFlags::ORIENTED)
        .expect("a closed mesh");
    let (proj, _) = mesh.project_local_point_and_get_location(&Point::from(*p), false);
    let d = (proj.point.coords - p).norm();
    if proj.is_inside { -d } else { d }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    #[test]
    fn signed_distances_match_parrys_after_the_body_moves(
        amp in 0.0..0.25f64,
        waves in 2.0..5.0f64,
        bend in 0.0..0.6f64,
        shift in prop::array::uniform3(-0.3..0.3f64),
        points in prop::collection::vec(prop::array::uniform3(-0.7..0.7f64), 1..40),
    ) {
        let rest = bumpy(2, amp, waves);
        let mut referee = ExactCollider::new(&rest, 0.0).expect("body");
        // Bent about the y axis by an angle growing with height, then moved.
        let moved: Vec<Vec3> = rest
            .positions
            .iter()
            .map(|p| {
                let a = bend * p.y;
                Vec3::new(p.x * a.cos() + p.z * a.sin(), p.y, -p.x * a.sin() + p.z * a.cos())
                    + Vec3::from(shift)
            })
            .collect();
        referee.update(&BodyFrame { time: 0.1, positions: moved.clone(), velocities: Vec::new() });
        for q in &points {
            let p = Vec3::from(*q);
            let ours = referee.signed_distance(&p).expect("finite");
            let theirs = parry_distance(&moved, &referee.body.triangles, &p);
            prop_assert!((ours.abs() - theirs.abs()).abs() < 1e-9, "{} vs {}", ours, theirs);
            if theirs.abs() > 1e-6 {
                prop_assert_eq!(ours.signum(), theirs.signum(), "{} vs {} at {:?}", ours, theirs, p);
            }
        }
    }
}

#[test]
fn a_point_on_an_edge_or_a_vertex_is_judged_by_its_pseudo_normal() {
    // Points just inside and just outside, off every corner and edge midpoint of a small
    // icosphere (where the closest feature is a vertex or an edge, not a face).
    let m = icosphere(0.2, 1, Vec3::zeros());
    let referee = ExactCollider::new(&m, 0.0).expect("body");
    let mut probes = m.positions.clone();
    for t in &referee.body.triangles {
        probes.push((m.positions[t[0] as usize] + m.positions[t[1] as usize]) * 0.5);
    }
    for q in probes {
        for (scale, inside) in [(0.99, true), (1.01, false)] {
            let d = referee.signed_distance(&(q * scale)).expect("finite");
            assert_eq!(d < 0.0, inside, "{q:?} x {scale}: {d}");
        }
    }
}

#[test]
fn a_point_beside_a_sharp_tip_is_outside() {
    // A tall thin pyramid (a spike). Beside its tip, a point's closest feature is the tip vertex,
    // and the face on the far side has it behind its plane: only the vertex's pseudo-normal says
    // outside. Tried from the four sides, so no choice of one face gets them all right.
    let apex = Vec3::new(0.0, 0.0, 1.0);
    let w = 0.1;
    let base = [
        Vec3::new(-w, -w, 0.0),
        Vec3::new(w, -w, 0.0),
        Vec3::new(w, w, 0.0),
        Vec3::new(-w, w, 0.0),
    ];
    let mut positions = base.to_vec();
    positions.push(apex);
    let mut triangles = vec![[0u32, 2, 1], [0, 3, 2]];
    for k in 0..4u32 {
        triangles.push([k, (k + 1) % 4, 4]);
    }
    let centre = Vec3::new(0.0, 0.0, 0.25);
    for t in &mut triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        if (b - a).cross(&(c - a)).dot(&((a + b + c) / 3.0 - centre)) < 0.0 {
            t.swap(1, 2);
        }
    }
    let mesh = PolyMesh::from_triangles(positions, &triangles).expect("a closed pyramid");
    let referee = ExactCollider::new(&mesh, 0.0).expect("body");
    for side in [Vec3::x(), -Vec3::x(), Vec3::y(), -Vec3::y()] {
        let p = apex + side * 0.05 + Vec3::new(0.0, 0.0, 0.01);
        let pr = referee.project(&p).expect("finite");
        assert!(
            (pr.point - apex).norm() < 1e-12,
            "the tip is the closest point"
        );
        assert!(pr.distance > 0.0, "{p:?} judged inside: {}", pr.distance);
        let inside = apex * 0.5;
        assert!(referee.signed_distance(&inside).expect("finite") < 0.0);
    }
}

#[test]
fn a_body_frame_with_a_non_finite_vertex_is_no_panic() {
    // The refitted hierarchy and the swept test take a shape with a NaN vertex without panicking,
    // and a point far from the broken corner still gets a finite answer from the referee.
    let m = icosphere(0.2, 2, Vec3::zeros());
    let mut positions = m.positions.clone();
    positions[0] = Vec3::new(Real::NAN, 0.0, 0.0);
    let frame = BodyFrame {
        time: 0.1,
        positions,
        velocities: Vec::new(),
    };
    let mut referee = ExactCollider::new(&m, 0.0).expect("body");
    referee.update(&frame);
    let far_from_vertex_0 = -m.positions[0] * 2.0;
    let d = referee
        .signed_distance(&far_from_vertex_0)
        .expect("an answer");
    assert!(d.is_finite() && d > 0.0, "{d}");
    let mut tracker = crate::NearestVertexCollider::new(&m, 0.002).expect("body");
    tracker.update(&frame);
    let start = [far_from_vertex_0, Vec3::zeros()];
    let mut end = [Vec3::zeros(), far_from_vertex_0];
    let mut contacts = Vec::new();
    tracker.sweep(&start, &mut end, [0.0, 1.0], &mut contacts);
    assert!(end.iter().all(|p| p.iter().all(|c| c.is_finite())));
}

#[test]
fn probes_are_the_signed_distances_on_any_thread_count() {
    let body = bumpy(3, 0.15, 5.0);
    let mut exact = ExactCollider::new(&body, 0.002).unwrap();
    // Points on rays through the body: inside, on and outside its rippled surface.
    let points: Vec<Vec3> = (0..500)
        .map(|k| {
            let a = k as Real * 0.731;
            let dir = Vec3::new(a.cos() * (0.3 * a).sin(), (0.3 * a).cos(), a.sin()).normalize();
            dir * (0.2 + 0.0007 * k as Real)
        })
        .collect();
    let which: Vec<u32> = (0..points.len() as u32).rev().step_by(2).collect();
    let mut per_thread = Vec::new();
    for threads in [1, 2, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let mut out = Vec::new();
        pool.install(|| exact.probe(&points, &which, &mut out));
        per_thread.push(out);
    }
    for (k, &i) in which.iter().enumerate() {
        let want = parry_distance(&body.positions, &exact.body.triangles, &points[i as usize]);
        assert!((per_thread[0][k].distance - want).abs() < 1e-9, "point {i}");
        for out in &per_thread[1..] {
            assert_eq!(out[k], per_thread[0][k], "point {i}");
        }
    }
}

#[test]
fn a_projection_started_from_any_face_finds_the_same_nearest_point() {
    let body = bumpy(3, 0.15, 5.0);
    let exact = ExactCollider::new(&body, 0.002).unwrap();
    let faces = exact.body.triangles.len() as u32;
    for k in 0..200 {
        let a = k as Real * 1.37;
        let dir = Vec3::new(a.sin() * (0.5 * a).cos(), (0.5 * a).sin(), a.cos()).normalize();
        let p = dir * (0.25 + 0.001 * k as Real);
        let plain = exact.project(&p).unwrap();
        // Some other face, the right one, and no face.
        for hint in [(k * 97) % faces, plain.face, crate::exact::NONE] {
            let from = exact.project_from(&p, hint).unwrap();
            assert!(
                (from.distance - plain.distance).abs() < 1e-12,
                "point {k}, hint {hint}"
            );
            assert!(
                (from.point - plain.point).norm() < 1e-12,
                "point {k}, hint {hint}"
            );
        }
    }
}

#[test]
fn a_nearest_point_on_an_edge_is_the_same_bits_from_any_starting_face() {
    // Points off the middle of every edge (and off every corner) of a bumpy body, where the
    // nearest point lies on an edge shared by two faces: the answer must not depend on the face
    // the search starts from, to the last bit, or a run's result would depend on its history.
    let body = bumpy(2, 0.15, 4.0);
    let exact = ExactCollider::new(&body, 0.002).unwrap();
    let (x, tris) = (&exact.body.positions, &exact.body.triangles);
    let faces = tris.len() as u32;
    let mut on_edges = 0;
    for (f, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (x[t[k] as usize], x[t[(k + 1) % 3] as usize]);
            // Out along the edge's normal and the corner's, nudged off the body's symmetry
            // planes (mirrored faces would tie at two different points).
            let n = exact.body.face_normals[f];
            let nudge = Vec3::new((f as Real).sin(), (k as Real + 0.5).cos(), 0.3) * 1e-7;
            for p in [
                (a + b) * 0.5 + n * 0.004,
                a + n * 0.003,
                (a * 0.3 + b * 0.7) + n * 0.002,
            ] {
                let p = p + nudge;
                let plain = exact.project(&p).unwrap();
                on_edges += usize::from(plain.bary.iter().filter(|&&w| w > 0.0).count() == 2);
                for hint in [f as u32, (f as u32 * 97 + 13) % faces, crate::exact::NONE] {
                    let from = exact.project_from(&p, hint).unwrap();
                    assert_eq!(
                        from.distance.to_bits(),
                        plain.distance.to_bits(),
                        "face {f}"
                    );
                    let same = (0..3).all(|i| from.point[i].to_bits() == plain.point[i].to_bits());
                    assert!(same, "face {f} edge {k} hint {hint}: {plain:?} {from:?}");
                }
            }
        }
    }
    assert!(
        on_edges > tris.len(),
        "only {on_edges} points landed on an edge"
    );
}

#[test]
fn a_point_probed_again_after_the_body_moved_is_searched_again() {
    // The collider keeps what it found per point; asked again at the same place it must still
    // answer for the body's new shape, not the old one.
    let body = bumpy(2, 0.1, 3.0);
    let mut exact = ExactCollider::new(&body, 0.0).unwrap();
    let points = vec![Vec3::new(0.0, 0.45, 0.0), Vec3::new(0.3, 0.0, 0.3)];
    let all = [0, 1];
    let mut first = Vec::new();
    exact.probe(&points, &all, &mut first);
    let mut again = Vec::new();
    exact.probe(&points, &all, &mut again);
    assert_eq!(first, again);
    let moved: Vec<Vec3> = body.positions.iter().map(|p| p * 1.1).collect();
    exact.update(&BodyFrame {
        time: 0.1,
        positions: moved,
        velocities: Vec::new(),
    });
    let mut after = Vec::new();
    exact.probe(&points, &all, &mut after);
    for (k, p) in points.iter().enumerate() {
        let want = exact.project(p).unwrap().distance;
        assert_eq!(after[k].distance, want, "point {k}");
        assert!(
            (after[k].distance - first[k].distance).abs() > 0.01,
            "point {k}"
        );
    }
    // The same after the referee's own query (`signed_distances`) for the same set.
    let d = exact.signed_distances(&points);
    assert_eq!(d, vec![Some(after[0].distance), Some(after[1].distance)]);
}

#[test]
fn the_exact_collider_finds_a_body_vertex_poking_through_a_cloth_triangle() {
    // A ball with one vertex pushed 6 mm out (a nipple); a cloth triangle 3 mm over the ball
    // around it, its corners probed first (the walk starts from their nearest faces).
    let mut m = icosphere(0.2, 3, Vec3::zeros());
    let top = (0..m.positions.len())
        .max_by(|&a, &b| m.positions[a].y.total_cmp(&m.positions[b].y))
        .unwrap();
    m.positions[top] *= 1.0 + 0.006 / 0.2;
    let mut exact = ExactCollider::new(&m, 0.0).unwrap();
    let up = m.positions[top].normalize();
    let (e1, e2) = (
        up.cross(&Vec3::x()).normalize(),
        up.cross(&up.cross(&Vec3::x())).normalize(),
    );
    let centre = up * 0.203;
    let cloth: Vec<Vec3> = (0..3)
        .map(|k| {
            let a = std::f64::consts::TAU * k as Real / 3.0;
            centre + (e1 * a.cos() + e2 * a.sin()) * 0.03
        })
        .collect();
    let mut probes = Vec::new();
    exact.probe(&cloth, &[0, 1, 2], &mut probes);
    let mut pokes = Vec::new();
    exact.pokes(&cloth, &[[0, 1, 2]], &[0], (0.001, 0.01), &mut pokes);
    let p = pokes
        .iter()
        .find(|p| (p.point - m.positions[top]).norm() < 1e-12);
    let p = p.expect("the pushed vertex pokes through");
    assert_eq!(p.triangle, 0);
    assert!(p.bary.iter().all(|&w| w >= 0.0));
    // Nothing else of the ball is within 1 mm under the triangle or through it.
    assert_eq!(pokes.len(), 1, "{pokes:?}");
}

/// Probes within a reach, asked again after the points moved a little on the same shape (what
/// the cloth solver does between its probes and its fail-safe): a point the whole search puts
/// nearer than the reach gets the whole search's distance, any other a distance of at least the
/// reach; nothing inside is reported outside, however it was answered (from what was found
/// before, by a search cut off at the reach, or in full).
#[test]
fn probes_within_a_reach_agree_with_the_whole_search_after_small_moves() {
    let mesh = bumpy(3, 0.15, 5.0);
    let mut c = ExactCollider::new(&mesh, 0.002).unwrap();
    let reach = 0.03;
    let mut s = 0x2545_f491_4f6c_dd1d_u64;
    let mut rand = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as Real / (1u64 << 53) as Real * 2.0 - 1.0
    };
    let mut points: Vec<Vec3> = (0..400)
        .map(|_| {
            let dir = Vec3::new(rand(), rand(), rand()).normalize();
            dir * (0.3 + 0.2 * (rand() + 1.0) / 2.0)
        })
        .collect();
    let all: Vec<u32> = (0..points.len() as u32).collect();
    let mut out = Vec::new();
    for round in 0..6 {
        c.probe_near(&points, &all, reach, &mut out);
        for (k, p) in points.iter().enumerate() {
            let whole = c.project(p).unwrap().distance;
            let got = out[k].distance;
            if whole < reach {
                assert_eq!(got.to_bits(), whole.to_bits(), "round {round}, point {k}");
            } else {
                assert!(got >= reach, "round {round}, point {k}: {got} for {whole}");
            }
        }
        for p in &mut points {
            *p += Vec3::new(rand(), rand(), rand()) * 0.003;
        }
    }
}

#[test]
fn a_point_inside_is_found_inside_whatever_face_its_search_starts_from() {
    // A search cut off at 1 cm took a point with nothing that near for outside when the face it
    // started from (where the point was last time) said so; but only the nearest feature's
    // pseudo-normal tells the side, and on a body with folds another face can say "outside" for a
    // point deep inside: a refined kimono vertex 32 mm inside the mannequin was left there.
    let body = bumpy(2, 0.25, 5.0);
    let col = ExactCollider::new(&body, 0.002).unwrap();
    let mut checked = 0;
    for k in 0..24 {
        let a = k as Real * 0.7;
        let dir = Vec3::new(
            a.cos() * (1.3 * a).sin(),
            (1.3 * a).cos(),
            a.sin() * (1.3 * a).sin(),
        );
        let p = dir.normalize() * 0.3;
        let whole = col.project(&p).unwrap().distance;
        if whole > -0.02 {
            continue;
        }
        checked += 1;
        for hint in 0..body.faces.len() as u32 {
            match col.search(&p, hint, 0.01) {
                crate::exact::Near::Found(pr) => assert_eq!(pr.distance, whole, "hint {hint}"),
                other => panic!("{p:?} is {whole} m inside; from face {hint}: {other:?}"),
            }
        }
    }
    assert!(checked > 10, "{checked} points deep inside");
}
