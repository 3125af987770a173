//! Tests of the arm clearance: the envelope's depth, and arms hanging into wide hips opened just
//! enough, smoothly.

use super::*;
use tryon_core::pose::mannequin_joints as J;

/// A body: a vertical cylinder of `radius` from y = 0.5 to 1.3 around the y axis.
fn cylinder(radius: Real) -> Vec<Vec3> {
    let mut pts = Vec::new();
    for i in 0..=40 {
        let y = 0.5 + 0.8 * i as Real / 40.0;
        for k in 0..64 {
            let a = k as Real / 64.0 * std::f64::consts::TAU;
            pts.push(Vec3::new(radius * a.cos(), y, radius * a.sin()));
        }
    }
    pts
}

/// A skeleton with the mannequin's names: pelvis at (0, 1, 0), shoulders at x = +-0.15, y = 1.4,
/// arms hanging straight down (elbow 0.3 m, wrist 0.55 m below the shoulder), legs below, the
/// head joint at y = 1.6.
fn rig() -> (Skeleton, Vec<Vec3>) {
    let joints: [(&str, Option<usize>, [Real; 3]); 18] = [
        (J::PELVIS, None, [0.0, 1.0, 0.0]),
        (J::SPINE1, Some(0), [0.0, 1.2, 0.0]),
        (J::CLAVICLE_L, Some(1), [0.05, 1.4, 0.0]),
        (J::UPPERARM_L, Some(2), [0.15, 1.4, 0.0]),
        (J::FOREARM_L, Some(3), [0.15, 1.1, 0.0]),
        (J::HAND_L, Some(4), [0.15, 0.85, 0.0]),
        (J::CLAVICLE_R, Some(1), [-0.05, 1.4, 0.0]),
        (J::UPPERARM_R, Some(6), [-0.15, 1.4, 0.0]),
        (J::FOREARM_R, Some(7), [-0.15, 1.1, 0.0]),
        (J::HAND_R, Some(8), [-0.15, 0.85, 0.0]),
        (J::THIGH_L, Some(0), [0.1, 0.95, 0.0]),
        (J::SHIN_L, Some(10), [0.1, 0.5, 0.0]),
        (J::FOOT_L, Some(11), [0.1, 0.08, 0.0]),
        (J::THIGH_R, Some(0), [-0.1, 0.95, 0.0]),
        (J::SHIN_R, Some(13), [-0.1, 0.5, 0.0]),
        (J::FOOT_R, Some(14), [-0.1, 0.08, 0.0]),
        (J::NECK, Some(1), [0.0, 1.5, 0.0]),
        (J::HEAD, Some(16), [0.0, 1.6, 0.0]),
    ];
    let names: Vec<String> = joints.iter().map(|j| j.0.to_string()).collect();
    let parents: Vec<Option<usize>> = joints.iter().map(|j| j.1).collect();
    let rest: Vec<Vec3> = joints.iter().map(|j| Vec3::from(j.2)).collect();
    let rest_offsets = (0..rest.len())
        .map(|j| parents[j].map_or(rest[j], |p| rest[j] - rest[p]))
        .collect();
    let s = Skeleton {
        names,
        parents,
        rest_offsets,
    };
    (s, rest)
}

fn motion(s: &Skeleton, frames: usize) -> Retargeted {
    Retargeted {
        skeleton: s.clone(),
        frame_time: 1.0 / 30.0,
        poses: vec![Pose::rest(s.names.len()); frames],
        ratio: 1.0,
        source_origin: Vec3::zeros(),
        target_origin: Vec3::zeros(),
        source_scheme: "test",
        target_scheme: "test",
        skipped_frames: 0,
        ease_frames: 0,
        source_times: Vec::new(),
        unreachable_frames: 0,
        clearance: Clearance::default(),
    }
}

#[test]
fn the_envelope_measures_depth_inside_its_sections_and_nothing_outside() {
    let e = Envelope::new(&cylinder(0.2), 1.35).unwrap();
    let d = e.depth(&Vec3::new(0.1, 0.9, 0.0), 0.0);
    assert!((d - 0.1).abs() < 0.01, "depth {d}");
    let d = e.depth(&Vec3::new(0.0, 0.9, -0.18), 0.05);
    assert!((d - 0.07).abs() < 0.01, "depth with margin {d}");
    assert_eq!(e.depth(&Vec3::new(0.3, 0.9, 0.0), 0.05), 0.0);
    assert_eq!(
        e.depth(&Vec3::new(0.0, 1.6, 0.0), 0.05),
        0.0,
        "above the top"
    );
    assert_eq!(
        e.depth(&Vec3::new(0.0, 0.2, 0.0), 0.05),
        0.0,
        "below the bottom"
    );
    assert!(Envelope::new(&cylinder(0.2), 0.0).is_none());
}

#[test]
fn arms_hanging_into_wide_hips_are_opened_just_enough_to_clear_them() {
    let (s, rest) = rig();
    let tips = vec![None; rest.len()];
    let margin = 0.03;
    // Hips of radius 0.2: the hanging wrist (x = 0.15) is 5 cm inside, 8 cm short of the margin.
    let e = Envelope::new(&cylinder(0.2), 1.3).unwrap();
    let mut m = motion(&s, 10);
    let report = keep_arms_clear(&mut m, &rest, &tips, &e, margin, 2);
    assert_eq!(report.frames_opened, 20, "both arms in every frame");
    // The elbow binds: 0.3 m below the shoulder and 8 cm short, it needs asin(0.08 / 0.3) = 15.5
    // degrees (whole degrees: 16).
    assert!(
        (15.5..=17.0).contains(&report.max_open_deg),
        "opened {} degrees",
        report.max_open_deg
    );
    for pose in &m.poses {
        let (_, p) = forward(&s, &rest, pose);
        for j in [4, 5, 8, 9] {
            assert!(e.depth(&p[j], margin) == 0.0, "joint {j} at {}", p[j]);
        }
        // Opened outward about the shoulder: the wrists at 0.15 + 0.55 sin 16 deg = 0.30 from the
        // midline and 0.55 (1 - cos 16 deg) = 2.1 cm higher.
        assert!(
            (p[5].x - 0.30).abs() < 0.01 && (p[9].x + 0.30).abs() < 0.01,
            "{} {}",
            p[5],
            p[9]
        );
        assert!((p[5].y - 0.871).abs() < 0.003);
        // The rest of the body is untouched.
        assert_eq!(pose.local_rotations[0], UnitQuat::identity());
        assert_eq!(pose.local_rotations[10], UnitQuat::identity());
    }
    // Narrow hips: nothing to do.
    let e = Envelope::new(&cylinder(0.08), 1.3).unwrap();
    let mut m = motion(&s, 10);
    let report = keep_arms_clear(&mut m, &rest, &tips, &e, margin, 2);
    assert_eq!(report, Clearance::default());
    assert!(m.poses.iter().all(|p| p == &Pose::rest(s.names.len())));
}

#[test]
fn the_smoothed_opening_never_falls_below_the_need_and_ramps_without_jumps() {
    let mut need = vec![0.0; 30];
    need[15] = 0.2;
    need[16] = 0.1;
    let s = smooth_max(&need, 3);
    for k in 0..30 {
        assert!(s[k] >= need[k]);
    }
    let steps = s
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0, Real::max);
    assert!(steps <= 0.2 / 7.0 + 1e-12, "largest step {steps}");
    assert_eq!(s[0], 0.0);
    assert_eq!(s[29], 0.0);
}

/// The right arm posed with its wrist at `w` (world), the elbow out to the side: its upper arm's
/// and forearm's local rotations.
fn reach_to(s: &Skeleton, rest: &[Vec3], w: Vec3) -> Pose {
    let (sh, el, wr) = (7, 8, 9);
    let (lu, lf) = ((rest[el] - rest[sh]).norm(), (rest[wr] - rest[el]).norm());
    let d = w - rest[sh];
    let l = d.norm();
    let x = (lu * lu - lf * lf + l * l) / (2.0 * l);
    let h = (lu * lu - x * x).max(0.0).sqrt();
    let dn = d / l;
    let side = Vec3::new(-1.0, 0.0, 0.0);
    let perp = (side - dn * dn.dot(&side)).normalize();
    let elbow = rest[sh] + dn * x + perp * h;
    let down = Vec3::new(0.0, -1.0, 0.0);
    let gu = UnitQuat::rotation_between(&down, &(elbow - rest[sh])).unwrap();
    let gf = UnitQuat::rotation_between(&down, &(w - elbow)).unwrap();
    let mut pose = Pose::rest(s.names.len());
    pose.local_rotations[sh] = gu;
    pose.local_rotations[el] = gu.inverse() * gf;
    pose
}

#[test]
fn a_hand_retargeted_into_the_face_is_moved_out_of_the_head() {
    let (s, rest) = rig();
    let tips = vec![None; rest.len()];
    // A head, an ellipsoid 16 x 22 x 18 cm around (0, 1.7, 0), and a body too narrow to need any
    // opening.
    let (c, r) = (Vec3::new(0.0, 1.7, 0.0), Vec3::new(0.08, 0.11, 0.09));
    let mut surface = Vec::new();
    for i in 0..=24 {
        let lat = std::f64::consts::PI * i as Real / 24.0;
        for k in 0..48 {
            let lon = std::f64::consts::TAU * k as Real / 48.0;
            let u = Vec3::new(lat.sin() * lon.cos(), lat.cos(), lat.sin() * lon.sin());
            surface.push(c + u.component_mul(&r));
        }
    }
    let head = Head::new(17, &surface).unwrap();
    assert!((head.centre - c).norm() < 1e-9);
    assert!(
        head.contains(&(c + Vec3::new(0.0, 0.0, 0.085)), 0.0),
        "the face"
    );
    assert!(
        !head.contains(&(c + Vec3::new(0.0, 0.0, 0.12)), 0.0),
        "in front of it"
    );
    assert!(
        head.contains(&(c + Vec3::new(0.0, 0.0, 0.12)), 0.04),
        "within the margin"
    );
    assert!(
        !head.contains(&(c + Vec3::new(0.0, -0.2, 0.0)), 0.03),
        "below the chin"
    );
    let mut e = Envelope::new(&cylinder(0.08), 1.3).unwrap();
    let mut m = motion(&s, 10);
    let wrist = Vec3::new(-0.03, 1.66, 0.05);
    m.poses[3..7].fill(reach_to(&s, &rest, wrist));
    let (_, p) = forward(&s, &rest, &m.poses[4]);
    assert!((p[9] - wrist).norm() < 1e-9, "posed: wrist at {}", p[9]);
    assert!(head.contains(&p[9], 0.0), "the wrist starts in the head");
    // Without the head nothing moves.
    let mut bare = m.clone();
    assert_eq!(
        keep_arms_clear(&mut bare, &rest, &tips, &e, 0.03, 2),
        Clearance::default()
    );
    e.head = Some(head.clone());
    let report = keep_arms_clear(&mut m, &rest, &tips, &e, 0.03, 2);
    assert!(report.frames_opened > 0 && report.max_open_deg > 0.0);
    for pose in &m.poses[3..7] {
        let (_, p) = forward(&s, &rest, pose);
        let tip = p[9] + (p[9] - p[8]) * 0.4;
        for x in [p[8], p[9], tip, (p[8] + p[9]) / 2.0] {
            assert!(!head.contains(&x, HEAD_MARGIN), "{x} in the head");
        }
        // Opened away from the midline, not across the face.
        assert!(p[9].x < wrist.x, "wrist at {}", p[9]);
        // The left arm and the rest of the body are untouched.
        assert_eq!(pose.local_rotations[3], UnitQuat::identity());
        assert_eq!(pose.local_rotations[0], UnitQuat::identity());
    }
}
