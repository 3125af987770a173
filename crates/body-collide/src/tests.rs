//! Property tests of the colliders and body following against the exact referee.

use crate::{
    BodyFollower, BodyMesh, DepthMapCollider, ExactCollider, FollowParams, NearestVertexCollider,
    SdfCollider, SurfaceBinding,
};
use proptest::prelude::*;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Iso3, Real, UnitQuat, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::shapes::{icosphere, scale_about};
use tryon_core::stages::Collider;

/// A random closed convex body: an icosphere scaled into an ellipsoid, rotated and moved.
pub(crate) fn body_strategy() -> impl Strategy<Value = PolyMesh> {
    (
        1u32..4,
        prop::array::uniform3(0.1..0.5f64),
        prop::array::uniform3(-1.0..1.0f64),
        prop::array::uniform3(-3.0..3.0f64),
    )
        .prop_map(|(sub, r, c, rot)| {
            let center = Vec3::new(c[0], c[1], c[2]);
            let mut m = icosphere(1.0, sub, center);
            scale_about(&mut m, center, Vec3::new(r[0], r[1], r[2]));
            let q = UnitQuat::from_scaled_axis(Vec3::new(rot[0], rot[1], rot[2]));
            for p in &mut m.positions {
                *p = center + q * (*p - center);
            }
            m
        })
}

/// Points scattered through the body's neighbourhood (about half of them inside).
pub(crate) fn points_near(m: &PolyMesh, seeds: &[[f64; 3]]) -> Vec<Vec3> {
    let c: Vec3 = m.positions.iter().sum::<Vec3>() / m.positions.len() as Real;
    seeds
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let anchor = m.positions[(i * 7919) % m.positions.len()];
            c + (anchor - c) * (0.2 + 1.2 * (s[0] + 1.0) / 2.0) + Vec3::new(s[1], s[2], s[0]) * 0.02
        })
        .collect()
}

pub(crate) fn seeds() -> impl Strategy<Value = Vec<[f64; 3]>> {
    prop::collection::vec(prop::array::uniform3(-1.0..1.0f64), 1..120)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// After resolution no point is inside the body by the exact referee.
    #[test]
    fn nothing_inside_after_resolution(m in body_strategy(), s in seeds(), shift in prop::array::uniform3(-0.2..0.2f64)) {
        let referee = ExactCollider::new(&m, 0.0).unwrap();
        let mut tracker = NearestVertexCollider::new(&m, 0.0).unwrap();
        let pts = points_near(&m, &s);
        // A first call elsewhere so the second one starts from stale nearest vertices.
        let mut first: Vec<Vec3> = pts.iter().map(|p| p + Vec3::new(shift[0], shift[1], shift[2])).collect();
        tracker.resolve(&mut first, &mut Vec::new());
        let mut pts2 = pts.clone();
        let mut contacts = Vec::new();
        tracker.resolve(&mut pts2, &mut contacts);
        for (k, p) in pts2.iter().enumerate() {
            let d = referee.signed_distance(p).unwrap();
            prop_assert!(d >= -1e-9, "point {} at {:?} still {} inside", k, p, d);
        }
        for c in &contacts {
            let before = referee.signed_distance(&pts[c.point as usize]).unwrap();
            prop_assert!(c.depth >= -before - 1e-9);
        }
    }

    /// On a sphere the hill-climb converges to the true nearest vertex from any start.
    #[test]
    fn tracking_finds_the_brute_force_nearest(sub in 1u32..5, r in 0.1..1.0f64, s in seeds(), s2 in seeds()) {
        let m = icosphere(r, sub, Vec3::new(0.3, 1.0, -0.2));
        let mut tracker = NearestVertexCollider::new(&m, 0.0).unwrap();
        tracker.cull_margin = Real::INFINITY;
        let start = points_near(&m, &s2);
        let pts = points_near(&m, &s);
        let n = pts.len().min(start.len());
        tracker.track(&start[..n]);
        tracker.track(&pts[..n]);
        for (k, p) in pts[..n].iter().enumerate() {
            let brute = tracker.body.nearest_vertex_brute(p);
            let dt = (tracker.body.positions[tracker.nearest[k] as usize] - p).norm();
            let db = (tracker.body.positions[brute as usize] - p).norm();
            prop_assert!(dt <= db + 1e-12, "point {}: tracked {} at {}, brute {} at {}", k, tracker.nearest[k], dt, brute, db);
        }
    }

    /// A rigid motion of the body moves followed points by exactly that motion.
    #[test]
    fn following_is_exact_under_rigid_motion(m in body_strategy(), s in seeds(), rot in prop::array::uniform3(-3.0..3.0f64), tr in prop::array::uniform3(-1.0..1.0f64)) {
        let body = BodyMesh::new(&m).unwrap();
        let referee = ExactCollider::new(&m, 0.0).unwrap();
        // Points within the full-follow band, on both sides of the surface.
        let pts: Vec<Vec3> = points_near(&m, &s)
            .into_iter()
            .filter_map(|p| {
                let pr = referee.project(&p)?;
                let n = (p - pr.point).try_normalize(1e-12)?;
                Some(pr.point + n * 0.004 * s[0][0])
            })
            .collect();
        let mut follower = BodyFollower::new(body, FollowParams { near: 0.01, far: 0.02 });
        follower.record(&pts);
        let iso = Iso3::new(Vec3::new(tr[0], tr[1], tr[2]), Vec3::new(rot[0], rot[1], rot[2]));
        let frame = BodyFrame { time: 0.0, positions: m.positions.iter().map(|p| iso.rotation * p + iso.translation.vector).collect(), velocities: vec![] };
        let mut moved = pts.clone();
        follower.apply(&frame, &mut moved).unwrap();
        let weights = follower.weights();
        let full = weights.iter().filter(|w| **w == 1.0).count();
        prop_assert!(2 * full >= pts.len(), "only {} of {} points within 4 mm are attached", full, pts.len());
        for ((p, q), w) in pts.iter().zip(&moved).zip(&weights) {
            let expected = iso.rotation * p + iso.translation.vector;
            if *w == 1.0 {
                prop_assert!((q - expected).norm() < 1e-9, "followed to {:?}, rigid motion gives {:?}", q, expected);
            } else if *w == 0.0 {
                prop_assert_eq!(p, q);
            }
        }
    }
}

#[test]
fn referee_signs_match_the_sphere() {
    let m = icosphere(0.5, 4, Vec3::zeros());
    let referee = ExactCollider::new(&m, 0.0).unwrap();
    for (p, inside) in [
        (Vec3::new(0.1, 0.2, 0.0), true),
        (Vec3::new(0.6, 0.0, 0.1), false),
        (Vec3::zeros(), true),
    ] {
        let d = referee.signed_distance(&p).unwrap();
        assert_eq!(d < 0.0, inside, "{p:?}: {d}");
        // The tessellated sphere lies within 0.5% of the analytic one.
        assert!((d - (p.norm() - 0.5)).abs() < 0.005, "{p:?}: {d}");
    }
}

#[test]
fn thickness_keeps_points_off_the_surface_and_reports_contacts() {
    let m = icosphere(0.3, 3, Vec3::zeros());
    let mut tracker = NearestVertexCollider::new(&m, 0.002).unwrap();
    let referee = ExactCollider::new(&m, 0.0).unwrap();
    let mut pts = vec![
        Vec3::new(0.0, 0.25, 0.0),
        Vec3::new(0.0, 0.301, 0.0),
        Vec3::new(0.0, 0.5, 0.0),
    ];
    let mut contacts = Vec::new();
    tracker.resolve(&mut pts, &mut contacts);
    assert_eq!(
        contacts.len(),
        2,
        "the deep point and the one inside the skin"
    );
    assert!((contacts[0].depth - 0.05).abs() < 0.005);
    assert!(contacts[0].normal.y > 0.9);
    for p in &pts[..2] {
        let d = referee.signed_distance(p).unwrap();
        assert!(
            (0.002 - 1e-12..0.0025).contains(&d),
            "point at {d} from the surface, expected the 2 mm skin (a face plane lies outside a convex body)"
        );
    }
    assert_eq!(pts[2], Vec3::new(0.0, 0.5, 0.0));
}

#[test]
fn wrong_body_frames_are_rejected_not_panicking() {
    let m = icosphere(0.3, 1, Vec3::zeros());
    let mut tracker = NearestVertexCollider::new(&m, 0.0).unwrap();
    tracker.update(&BodyFrame {
        time: 0.0,
        positions: vec![Vec3::zeros(); 3],
        velocities: vec![],
    });
    assert_eq!(tracker.rejected_frames, 1);
    let mut pts = vec![Vec3::zeros()];
    tracker.resolve(&mut pts, &mut Vec::new());
    // Moved out onto a face of the level-1 icosphere (face centres lie 0.28 m from its centre).
    assert!(pts[0].norm() > 0.27, "{:?}", pts[0]);
}

proptest! {
    /// A surface binding reproduces its point on the body it was made on, and moves with the
    /// body's rigid motions exactly.
    #[test]
    fn bindings_ride_rigid_motion(m in body_strategy(), s in seeds(), rot in prop::array::uniform3(-3.0..3.0f64), tr in prop::array::uniform3(-1.0..1.0f64)) {
        let mut body = BodyMesh::new(&m).unwrap();
        let pts = points_near(&m, &s);
        let bound: Vec<SurfaceBinding> = pts.iter().map(|p| SurfaceBinding::bind(&body, p).unwrap()).collect();
        for (p, b) in pts.iter().zip(&bound) {
            prop_assert!((b.position(&body) - p).norm() < 1e-9);
        }
        let iso = Iso3::new(Vec3::new(tr[0], tr[1], tr[2]), Vec3::new(rot[0], rot[1], rot[2]));
        let frame = BodyFrame { time: 0.0, positions: m.positions.iter().map(|p| iso.rotation * p + iso.translation.vector).collect(), velocities: vec![] };
        body.set_frame(&frame).unwrap();
        for (p, b) in pts.iter().zip(&bound) {
            let expected = iso.rotation * p + iso.translation.vector;
            prop_assert!((b.position(&body) - expected).norm() < 1e-9);
        }
    }

    /// The tracker's probes agree with the referee in sign wherever the referee is clear of the
    /// surface, and report a unit normal; the referee's own probes match its signed distance.
    #[test]
    fn probes_agree_with_the_referee(m in body_strategy(), s in seeds()) {
        let mut referee = ExactCollider::new(&m, 0.0).unwrap();
        let mut tracker = NearestVertexCollider::new(&m, 0.0).unwrap();
        let pts = points_near(&m, &s);
        let which: Vec<u32> = (0..pts.len() as u32).rev().collect();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        tracker.probe(&pts, &which, &mut a);
        referee.probe(&pts, &which, &mut b);
        prop_assert_eq!(a.len(), which.len());
        for ((k, pa), pb) in which.iter().zip(&a).zip(&b) {
            let d = referee.signed_distance(&pts[*k as usize]).unwrap();
            prop_assert!((pb.distance - d).abs() < 1e-12);
            if d.abs() > 1e-3 {
                prop_assert_eq!(pa.distance < 0.0, d < 0.0, "point {}: tracker {}, referee {}", k, pa.distance, d);
            }
            // Far from the body (outside its culling box) a probe is FAR, with no normal.
            prop_assert!(pa.distance == Real::INFINITY || (pa.normal.norm() - 1.0).abs() < 1e-9);
        }
    }

    /// `probe_near`'s shortcuts (the height over a convex fan's highest plane) change nothing a
    /// caller within `reach` can see: points nearer than `reach` get the full probe's distance and
    /// normal, the others a distance of at least `reach`.
    #[test]
    fn near_probes_match_full_probes_within_reach(m in body_strategy(), s in seeds(), reach in 0.001..0.05f64) {
        let pts = points_near(&m, &s);
        let which: Vec<u32> = (0..pts.len() as u32).collect();
        let (mut full, mut near) = (Vec::new(), Vec::new());
        NearestVertexCollider::new(&m, 0.0).unwrap().probe(&pts, &which, &mut full);
        NearestVertexCollider::new(&m, 0.0).unwrap().probe_near(&pts, &which, reach, &mut near);
        for (k, (f, n)) in full.iter().zip(&near).enumerate() {
            if f.distance < reach {
                prop_assert!((f.distance - n.distance).abs() < 1e-9, "point {}: {} vs {}", k, f.distance, n.distance);
                prop_assert!((f.normal - n.normal).norm() < 1e-6, "point {}: normals {:?} vs {:?}", k, f.normal, n.normal);
            } else {
                prop_assert!(n.distance >= reach, "point {}: {} under reach {}", k, n.distance, reach);
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The grid field follows a moved body: after an update to a rigidly moved body, it stays
    /// within one cell diagonal of the referee inside the band (the distance is 1-Lipschitz, so each
    /// node is within that of the true value), is never much shallower deeper inside, and agrees in sign wherever the referee is a cell diagonal clear of
    /// the surface. Resolution then leaves no point deeper than a cell diagonal.
    #[test]
    fn sdf_follows_the_referee(m in body_strategy(), s in seeds(), rot in prop::array::uniform3(-3.0..3.0f64), tr in prop::array::uniform3(-1.0..1.0f64), res in 24usize..64) {
        let mut sdf = SdfCollider::new(&m, 0.0, res).unwrap();
        let iso = Iso3::new(Vec3::new(tr[0], tr[1], tr[2]), Vec3::new(rot[0], rot[1], rot[2]));
        let moved: Vec<Vec3> = m.positions.iter().map(|p| iso.rotation * p + iso.translation.vector).collect();
        sdf.update(&BodyFrame { time: 0.0, positions: moved.clone(), velocities: vec![] });
        let mm = PolyMesh { positions: moved, ..m.clone() };
        let referee = ExactCollider::new(&mm, 0.0).unwrap();
        let diag = sdf.cell_size() * 3f64.sqrt();
        let mut pts = points_near(&mm, &s);
        for p in &pts {
            let d = referee.signed_distance(p).unwrap();
            let g = sdf.signed_distance(p).unwrap();
            let band = sdf.band as Real * sdf.cell_size();
            if d.abs() <= band - diag {
                prop_assert!((g - d).abs() <= diag + 1e-9, "grid {} referee {} (cell {})", g, d, sdf.cell_size());
            } else if d < 0.0 {
                // Deeper, node values are distances to some triangle: never shallower than the truth.
                prop_assert!(g <= d + diag + 1e-9, "grid {} referee {} (cell {})", g, d, sdf.cell_size());
            }
            if d.abs() > diag {
                prop_assert_eq!(g < 0.0, d < 0.0);
            }
        }
        let mut contacts = Vec::new();
        sdf.resolve(&mut pts, &mut contacts);
        for p in &pts {
            let d = referee.signed_distance(p).unwrap();
            prop_assert!(d >= -diag, "left {} inside (cell {})", d, sdf.cell_size());
        }
        for c in &contacts {
            prop_assert!((c.normal.norm() - 1.0).abs() < 1e-9);
            prop_assert!((c.bary.iter().sum::<Real>() - 1.0).abs() < 1e-9);
        }
    }

    /// On a convex body six depth maps see every surface point, so a resolved point is outside by
    /// the referee up to the pixel size, and the inside test agrees with the referee away from the
    /// surface.
    #[test]
    fn depth_maps_resolve_a_convex_body(m in body_strategy(), s in seeds(), res in 64usize..256) {
        let referee = ExactCollider::new(&m, 0.0).unwrap();
        let mut maps = DepthMapCollider::new(&m, 0.0, res).unwrap();
        let px = maps.pixel_size();
        let mut pts = points_near(&m, &s);
        for p in &pts {
            let d = referee.signed_distance(p).unwrap();
            let e = maps.signed_distance(p).unwrap();
            if d.abs() > 2.0 * px {
                prop_assert_eq!(e < 0.0, d < 0.0, "maps {} referee {} (pixel {})", e, d, px);
            }
        }
        let mut contacts = Vec::new();
        maps.resolve(&mut pts, &mut contacts);
        for p in &pts {
            let d = referee.signed_distance(p).unwrap();
            prop_assert!(d >= -2.0 * px, "left {} inside (pixel {})", d, px);
        }
    }
}

#[test]
fn sdf_and_depth_maps_resolve_a_sphere_to_millimetres() {
    let m = icosphere(0.3, 4, Vec3::zeros());
    let referee = ExactCollider::new(&m, 0.0).unwrap();
    // The grid steps along its gradient; the depth maps push along the plane of the face one view
    // sees, which for a point 10 cm deep is not the nearest direction, so they overshoot more.
    let mut colliders: Vec<(Box<dyn Collider>, Real)> = vec![
        (Box::new(SdfCollider::new(&m, 0.002, 128).unwrap()), 0.006),
        (
            Box::new(DepthMapCollider::new(&m, 0.002, 512).unwrap()),
            0.015,
        ),
    ];
    for (c, most) in &mut colliders {
        let mut pts: Vec<Vec3> = (0..200)
            .map(|i| {
                let a = i as Real * 2.399_963;
                let z = 1.0 - 2.0 * (i as Real + 0.5) / 200.0;
                let r = (1.0 - z * z).sqrt();
                Vec3::new(r * a.cos(), z, r * a.sin()) * (0.2 + 0.09 * (i % 3) as Real / 2.0)
            })
            .collect();
        let mut contacts = Vec::new();
        c.resolve(&mut pts, &mut contacts);
        assert_eq!(contacts.len(), 200, "{}: every point was inside", c.name());
        for p in &pts {
            let d = referee.signed_distance(p).unwrap();
            assert!(
                (0.0..*most).contains(&d),
                "{}: point left {d} m from the surface, expected 0..{most}",
                c.name()
            );
        }
    }
}

/// A body in two pieces (an object on a table): a point tracked near one piece and then moved into
/// the other is still found inside, though no hill-climb leads from one piece to the other.
#[test]
fn tracking_sees_every_piece_of_the_body() {
    // Pieces of different sizes, the point first tracked near the smaller one: the track it starts
    // with is then not on the largest piece (spot on its table, before this was fixed, had no
    // track on the table, and the cloth fell through it).
    for (first, second) in [(3, 3), (2, 4), (4, 2)] {
        let a = icosphere(0.2, first, Vec3::zeros());
        let b = icosphere(0.2, second, Vec3::new(1.0, 0.0, 0.0));
        let base = a.positions.len() as u32;
        let mut m = a.clone();
        m.positions.extend_from_slice(&b.positions);
        m.faces.extend(b.faces.iter().map(|f| match f {
            tryon_core::mesh::Face::Tri(t) => tryon_core::mesh::Face::Tri(t.map(|v| v + base)),
            tryon_core::mesh::Face::Quad(q) => tryon_core::mesh::Face::Quad(q.map(|v| v + base)),
        }));
        for (start, inside, centre) in [
            (Vec3::new(0.25, 0.0, 0.0), Vec3::new(0.9, 0.0, 0.0), 1.0),
            (Vec3::new(0.75, 0.0, 0.0), Vec3::new(0.1, 0.0, 0.0), 0.0),
        ] {
            let mut tracker = NearestVertexCollider::new(&m, 0.0).unwrap();
            let mut pts = vec![start];
            tracker.resolve(&mut pts, &mut Vec::new());
            // Now inside the other piece.
            pts[0] = inside;
            let mut contacts = Vec::new();
            tracker.resolve(&mut pts, &mut contacts);
            assert_eq!(
                contacts.len(),
                1,
                "subdivisions {first}/{second}: the point inside the other piece was missed"
            );
            assert!(
                (pts[0] - Vec3::new(centre, 0.0, 0.0)).norm() > 0.19,
                "{:?}",
                pts[0]
            );
        }
    }
}

/// The referee takes non-finite points without panicking: it has nothing to say about them, and
/// still resolves the finite points after them.
#[test]
fn the_referee_skips_non_finite_points() {
    let sphere = icosphere(0.5, 3, Vec3::zeros());
    let mut referee = ExactCollider::new(&sphere, 0.0).unwrap();
    let mut pts = vec![
        Vec3::new(Real::NAN, 0.0, 0.0),
        Vec3::new(0.0, Real::INFINITY, 0.0),
        Vec3::new(0.0, 0.1, 0.0),
    ];
    assert!(referee.signed_distance(&pts[0]).is_none());
    let mut contacts = Vec::new();
    referee.resolve(&mut pts, &mut contacts);
    assert_eq!(contacts.len(), 1);
    assert_eq!(contacts[0].point, 2);
    assert!(referee.signed_distance(&pts[2]).unwrap() > -1e-9);
    let mut probes = Vec::new();
    referee.probe(&pts, &[0, 1, 2], &mut probes);
    assert_eq!(probes[0], tryon_core::stages::Probe::FAR);
}

/// A closed body with concave folds: an icosphere whose radius ripples with direction.
fn bumpy_sphere(sub: u32, amp: Real, waves: Real) -> PolyMesh {
    let mut m = icosphere(0.4, sub, Vec3::zeros());
    for p in &mut m.positions {
        let u = p.normalize();
        let r = 0.4 * (1.0 + amp * (waves * u.x).sin() * (waves * u.y).cos());
        *p = u * r;
    }
    m
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// On a body with concave folds (where P1's test alone misses points, and its push along one
    /// plane's normal can leave a point behind the fold's other side), resolution leaves nothing
    /// inside by the referee deeper than the convexity tolerance allows: a fan concave by less
    /// than `FLAT` times an edge counts as convex (a few micrometres here; the fold it guards
    /// against left points 2 mm inside).
    #[test]
    fn nothing_inside_a_concave_body_after_resolution(amp in 0.05..0.25f64, waves in 2.0..5.0f64, s in seeds()) {
        let m = bumpy_sphere(4, amp, waves);
        let referee = ExactCollider::new(&m, 0.0).unwrap();
        let mut tracker = NearestVertexCollider::new(&m, 0.0).unwrap();
        // Points within a few centimetres of the surface, on both sides.
        let mut pts: Vec<Vec3> = s
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let q = m.positions[(i * 7919) % m.positions.len()];
                q + Vec3::new(r[0], r[1], r[2]) * 0.03
            })
            .collect();
        let longest = m.triangulate().0.iter().flat_map(|t| {
            (0..3).map(|e| (m.positions[t[e] as usize] - m.positions[t[(e + 1) % 3] as usize]).norm())
        }).fold(0.0, Real::max);
        let tolerance = crate::tracker::FLAT * longest;
        prop_assert!(tolerance < 1e-5);
        let inside_before = pts.iter().filter(|p| referee.signed_distance(p).unwrap() < -tolerance).count();
        let mut contacts = Vec::new();
        tracker.resolve(&mut pts, &mut contacts);
        prop_assert!(contacts.len() >= inside_before, "{} contacts for {} points inside", contacts.len(), inside_before);
        for (k, p) in pts.iter().enumerate() {
            let d = referee.signed_distance(p).unwrap();
            prop_assert!(d > -tolerance, "point {} still {} m inside (tolerance {})", k, -d, tolerance);
        }
    }

    /// `resolve` skips a point that has moved less than its clearance since it was last found
    /// outside. Moved again by up to 2 cm (some into the body, some by less than their clearance),
    /// and then with the body moved into them, the points still end up outside by the referee.
    #[test]
    fn skipping_points_by_clearance_misses_nothing(amp in 0.05..0.25f64, waves in 2.0..5.0f64, s in seeds(), s2 in seeds(), shift in prop::array::uniform3(-0.02..0.02f64)) {
        let mut m = bumpy_sphere(4, amp, waves);
        let mut tracker = NearestVertexCollider::new(&m, 0.001).unwrap();
        let mut pts: Vec<Vec3> = s
            .iter()
            .enumerate()
            .map(|(i, r)| m.positions[(i * 7919) % m.positions.len()] + Vec3::new(r[0], r[1], r[2]) * 0.03)
            .collect();
        let mut contacts = Vec::new();
        tracker.resolve(&mut pts, &mut contacts);
        for (p, r) in pts.iter_mut().zip(s2.iter().cycle()) {
            *p += Vec3::new(r[0], r[1], r[2]) * 0.02;
        }
        tracker.resolve(&mut pts, &mut contacts);
        let referee = ExactCollider::new(&m, 0.0).unwrap();
        for (k, p) in pts.iter().enumerate() {
            let d = referee.signed_distance(p).unwrap();
            prop_assert!(d > -1e-6, "moved: point {} {} m inside", k, -d);
        }
        let dx = Vec3::new(shift[0], shift[1], shift[2]);
        m.positions.iter_mut().for_each(|p| *p += dx);
        tracker.update(&BodyFrame { time: 0.0, positions: m.positions.clone(), velocities: Vec::new() });
        tracker.resolve(&mut pts, &mut contacts);
        let referee = ExactCollider::new(&m, 0.0).unwrap();
        for (k, p) in pts.iter().enumerate() {
            let d = referee.signed_distance(p).unwrap();
            prop_assert!(d > -1e-6, "body moved: point {} {} m inside", k, -d);
        }
    }
}

/// The tracker's probes and projection run each point on its own in parallel and write the
/// results back in order: on a body with concave folds (where the fans' convexity cache, shared
/// by the threads, is filled as points reach them), two rounds of probes and projections, with
/// the points moved between, give bitwise the same on one thread as on three.
#[test]
fn the_tracker_probes_and_resolves_the_same_on_any_thread_count() {
    let m = bumpy_sphere(4, 0.2, 4.0);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut tracker = NearestVertexCollider::new(&m, 0.002).unwrap();
            // 3,000 points within 3 cm of the surface on both sides: many chunks per thread.
            let mut pts: Vec<Vec3> = (0..3000)
                .map(|i| {
                    let q = m.positions[(i * 7919) % m.positions.len()];
                    let s = (i as Real * 0.37).sin();
                    let c = (i as Real * 0.91).cos();
                    q + Vec3::new(s, c, s * c) * 0.03
                })
                .collect();
            let which: Vec<u32> = (0..pts.len() as u32).collect();
            let (mut probes, mut contacts) = (Vec::new(), Vec::new());
            let mut log = Vec::new();
            for round in 0..2 {
                tracker.probe_near(&pts, &which, 0.01, &mut probes);
                log.push(format!("{probes:?}"));
                contacts.clear();
                tracker.resolve(&mut pts, &mut contacts);
                log.push(format!("{contacts:?}"));
                for (i, p) in pts.iter_mut().enumerate() {
                    *p += Vec3::new(0.004, -0.003, 0.002) * ((i + round) as Real * 0.13).sin();
                }
            }
            (pts, log)
        })
    };
    let one = run(1);
    // It did work: some points were inside and were pushed out.
    assert!(one.1[1].len() > 100, "no contacts: {}", one.1[1]);
    for threads in [2, 3] {
        assert!(run(threads) == one, "{threads} threads differ from one");
    }
}

/// The field follows a moved body, and a frame that does not move the body leaves it as it was.
#[test]
fn the_sdf_follows_a_moved_body_and_keeps_its_field_for_a_still_one() {
    let m = icosphere(0.3, 3, Vec3::zeros());
    let mut sdf = SdfCollider::new(&m, 0.0, 32).unwrap();
    let p = Vec3::new(0.0, 0.33, 0.0);
    let (d0, _) = sdf.sample(&p).unwrap();
    let still = BodyFrame {
        time: 0.1,
        positions: m.positions.clone(),
        velocities: Vec::new(),
    };
    sdf.update(&still);
    assert_eq!(sdf.sample(&p).unwrap().0, d0);
    let up = Vec3::new(0.0, 0.02, 0.0);
    let moved = BodyFrame {
        time: 0.2,
        positions: m.positions.iter().map(|x| x + up).collect(),
        velocities: Vec::new(),
    };
    sdf.update(&moved);
    let (d1, _) = sdf.sample(&p).unwrap();
    // 3 cm above a 30 cm ball, then 1 cm above it (the field's error is well under a cell).
    assert!(
        (d0 - 0.03).abs() < 0.005 && (d1 - 0.01).abs() < 0.005,
        "{d0} then {d1}"
    );
}
