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
/// arms hanging straight down (elbow 0.3 m, wrist 0.55 m below the shoulder), legs below.
fn rig() -> (Skeleton, Vec<Vec3>) {
    let joints: [(&str, Option<usize>, [Real; 3]); 16] = [
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
