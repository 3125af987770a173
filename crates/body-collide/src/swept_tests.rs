//! Tests of swept body collision: tunnelling through a thin part in one step, a fast part
//! sweeping over a still point, and (proptest) no point outside a convex body at a step's start
//! is inside it at the end, judged by the exact referee.

use crate::{ExactCollider, NearestVertexCollider};
use proptest::prelude::*;
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3};
use tryon_core::shapes::icosphere;
use tryon_core::stages::Collider;

const SKIN: Real = 0.002;

fn ball(r: Real, c: Vec3) -> NearestVertexCollider {
    NearestVertexCollider::new(&icosphere(r, 2, c), SKIN).expect("icosphere")
}

#[test]
fn a_point_passing_through_a_thin_part_in_one_step_is_stopped_on_its_near_side() {
    // A finger-thin part (1 cm across) and a point that crosses it whole in one step.
    let mut c = ball(0.005, Vec3::zeros());
    let start = [Vec3::new(0.0, 0.0, 0.05)];
    let mut end = [Vec3::new(0.001, 0.0, -0.05)];
    // The projection alone sees nothing: the point ends outside, on the far side.
    let mut projected = end;
    let mut contacts = Vec::new();
    c.resolve(&mut projected, &mut contacts);
    assert_eq!(projected, end, "tunnelled: the end is outside");
    assert!(c.sweep(&start, &mut end, [1.0, 1.0], &mut contacts));
    assert_eq!(contacts.len(), 1);
    assert!(
        end[0].z > 0.004 && end[0].z < 0.02,
        "stopped on the near side, a skin out: {:?}",
        end[0]
    );
    assert!(c.signed_distance(&end[0]).unwrap() > 0.0);
}

#[test]
fn a_part_sweeping_over_a_still_point_pushes_it_ahead() {
    // A 3 cm ball moves 20 cm up in one update, through a point 2 cm above its top.
    let mesh = icosphere(0.03, 2, Vec3::zeros());
    let mut c = NearestVertexCollider::new(&mesh, SKIN).expect("icosphere");
    let up = Vec3::new(0.0, 0.0, 0.2);
    c.update(&BodyFrame {
        time: 0.1,
        positions: mesh.positions.iter().map(|p| p + up).collect(),
        velocities: Vec::new(),
    });
    let start = [Vec3::new(0.0, 0.0, 0.05)];
    let mut end = start;
    let mut contacts: Vec<Contact> = Vec::new();
    assert!(c.sweep(&start, &mut end, [0.0, 1.0], &mut contacts));
    assert_eq!(contacts.len(), 1);
    // Out along the normal of the facet it hit: ahead of the ball's centre, a skin outside.
    let d = c.signed_distance(&end[0]).unwrap();
    assert!(
        end[0].z > 0.2 && d > 0.0,
        "ahead of the ball: {:?}, {d}",
        end[0]
    );
    // With the body held at its new shape, the same point is left where it was (below the
    // ball, outside): only the move itself is swept.
    let mut still = start;
    contacts.clear();
    c.sweep(&start, &mut still, [1.0, 1.0], &mut contacts);
    assert!(contacts.is_empty() && still == start);
}

#[test]
fn a_point_leaving_the_body_is_let_go() {
    let mut c = ball(0.05, Vec3::zeros());
    let start = [Vec3::new(0.0, 0.0, 0.01)];
    let mut end = [Vec3::new(0.0, 0.0, 0.2)];
    let mut contacts = Vec::new();
    c.sweep(&start, &mut end, [1.0, 1.0], &mut contacts);
    assert!(contacts.is_empty());
    assert_eq!(end[0], Vec3::new(0.0, 0.0, 0.2));
}

#[test]
fn non_finite_paths_are_left_alone() {
    let mut c = ball(0.05, Vec3::zeros());
    let start = [Vec3::new(Real::NAN, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.2)];
    let mut end = [Vec3::zeros(), Vec3::new(0.0, 0.0, -0.2)];
    let mut contacts = Vec::new();
    c.sweep(&start, &mut end, [1.0, 1.0], &mut contacts);
    assert_eq!(end[0], Vec3::zeros());
    assert_eq!(contacts.len(), 1, "the finite path is still stopped");
}

fn unit(v: [f64; 3]) -> Vec3 {
    Vec3::from(v).try_normalize(1e-9).unwrap_or(Vec3::x())
}

proptest! {
    /// However far a point moves in one step and however far the ball moves under it, a point
    /// outside at the start is outside at the end (judged by the exact referee on the ball's new
    /// shape).
    #[test]
    fn a_point_outside_at_the_start_is_never_inside_at_the_end(
        dirs in prop::collection::vec((prop::array::uniform3(-1.0..1.0f64), 0.0..0.3f64, prop::array::uniform3(-0.4..0.4f64)), 1..24),
        shift in prop::array::uniform3(-0.3..0.3f64),
    ) {
        let r = 0.1;
        let mesh = icosphere(r, 2, Vec3::zeros());
        let mut c = NearestVertexCollider::new(&mesh, SKIN).expect("icosphere");
        let moved: Vec<Vec3> = mesh.positions.iter().map(|p| p + Vec3::from(shift)).collect();
        let frame = BodyFrame { time: 0.1, positions: moved.clone(), velocities: Vec::new() };
        c.update(&frame);
        let mut referee = ExactCollider::new(&mesh, 0.0).expect("icosphere");
        let start: Vec<Vec3> = dirs.iter().map(|(d, h, _)| unit(*d) * (r + 0.001 + h)).collect();
        let mut end: Vec<Vec3> = dirs.iter().zip(&start).map(|((_, _, m), s)| s + Vec3::from(*m)).collect();
        let mut contacts = Vec::new();
        c.sweep(&start, &mut end, [0.0, 1.0], &mut contacts);
        referee.update(&frame);
        for (i, p) in end.iter().enumerate() {
            let d = referee.signed_distance(p).expect("finite");
            prop_assert!(d >= -1e-9, "point {} ends {} inside", i, -d);
        }
    }
}

#[test]
fn the_sweep_is_the_same_on_any_thread_count() {
    // Points falling through a moving ball from a ring of directions, on 1, 2 and 3 threads.
    let mesh = icosphere(0.1, 3, Vec3::zeros());
    let shift = Vec3::new(0.03, -0.02, 0.05);
    let frame = BodyFrame {
        time: 0.1,
        positions: mesh.positions.iter().map(|p| p + shift).collect(),
        velocities: Vec::new(),
    };
    let start: Vec<Vec3> = (0..500)
        .map(|k| {
            let a = k as Real * 0.7;
            let b = k as Real * 0.013;
            Vec3::new(a.cos() * b.cos(), a.sin() * b.cos(), b.sin()) * 0.15
        })
        .collect();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| {
            let mut c = NearestVertexCollider::new(&mesh, SKIN).expect("icosphere");
            c.update(&frame);
            let mut end: Vec<Vec3> = start.iter().map(|p| p * 0.2).collect();
            let mut contacts = Vec::new();
            c.sweep(&start, &mut end, [0.0, 1.0], &mut contacts);
            (end, contacts)
        })
    };
    let one = run(1);
    assert!(
        one.1.len() > 100,
        "most points are stopped: {}",
        one.1.len()
    );
    assert_eq!(one, run(2));
    assert_eq!(one, run(3));
}

#[test]
fn the_exact_collider_sweeps_a_moving_part_as_the_tracker_does() {
    // The ball of the test above, its move swept by both colliders: the same stop.
    let mesh = icosphere(0.03, 2, Vec3::zeros());
    let up = Vec3::new(0.0, 0.0, 0.2);
    let frame = BodyFrame {
        time: 0.1,
        positions: mesh.positions.iter().map(|p| p + up).collect(),
        velocities: Vec::new(),
    };
    let mut tracker = NearestVertexCollider::new(&mesh, SKIN).expect("icosphere");
    let mut exact = ExactCollider::new(&mesh, SKIN).expect("icosphere");
    let start = [Vec3::new(0.0, 0.0, 0.05)];
    let mut ends = Vec::new();
    for c in [&mut tracker as &mut dyn Collider, &mut exact] {
        c.update(&frame);
        let (mut end, mut contacts) = (start, Vec::new());
        assert!(
            c.sweep(&start, &mut end, [0.0, 1.0], &mut contacts),
            "{}",
            c.name()
        );
        assert_eq!(contacts.len(), 1, "{}", c.name());
        ends.push(end[0]);
    }
    assert_eq!(ends[0], ends[1]);
    assert!(exact.signed_distance(&ends[1]).unwrap() > 0.0 && ends[1].z > 0.2);
}
