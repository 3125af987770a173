//! Tests of the parametric mannequin: a closed oriented manifold of the right size whose girths,
//! measured by slicing, are the requested ones; weights that skin; a posed body that stays whole.

use crate::JOINT_NAMES;
use crate::girth::girth_at;
use crate::mannequin::Mannequin;
use crate::skin::SkinnedBody;
use std::collections::HashSet;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, UnitQuat, Vec3};
use tryon_core::measure::Measurements;
use tryon_core::pose::Pose;
use tryon_core::stages::BodyModel;
use tryon_core::topology::Topology;

fn closed_and_oriented(m: &Mannequin) {
    m.mesh.validate().unwrap();
    let topo = Topology::build(&m.mesh).unwrap();
    assert!(topo.boundary_edges.is_empty(), "open edges");
    let (tris, _) = m.mesh.triangulate();
    let mut half: HashSet<(u32, u32)> = HashSet::new();
    for t in &tris {
        for e in 0..3 {
            assert!(
                half.insert((t[e], t[(e + 1) % 3])),
                "edge {:?} twice in one direction",
                (t[e], t[(e + 1) % 3])
            );
        }
    }
    let x = &m.mesh.positions;
    let vol: Real = tris
        .iter()
        .map(|t| x[t[0] as usize].dot(&x[t[1] as usize].cross(&x[t[2] as usize])) / 6.0)
        .sum();
    // A person of 55-80 kg at about 1 kg/l.
    assert!(vol > 0.045 && vol < 0.09, "volume {vol} m^3");
}

#[test]
fn default_mannequin_is_a_closed_manifold_of_the_right_size() {
    let m = Mannequin::new(&Measurements::default()).unwrap();
    let n = m.mesh.positions.len();
    assert!((5_000..=15_000).contains(&n), "{n} vertices");
    closed_and_oriented(&m);
    assert_eq!(m.skeleton.names.len(), JOINT_NAMES.len());
    assert!(JOINT_NAMES.len() >= 20);
    let lo = m
        .mesh
        .positions
        .iter()
        .fold(Vec3::repeat(Real::MAX), |a, p| a.inf(p));
    let hi = m
        .mesh
        .positions
        .iter()
        .fold(Vec3::repeat(Real::MIN), |a, p| a.sup(p));
    assert!(
        lo.y.abs() < 1e-9 && (hi.y - 1.65).abs() < 1e-9,
        "{lo:?} {hi:?}"
    );
}

#[test]
fn girths_by_slicing_match_the_measurements() {
    for m in [
        Measurements::default(),
        Measurements {
            height: 1.80,
            bust: 1.02,
            waist: 0.86,
            hip: 1.00,
            shoulder_width: 0.44,
            arm_length: 0.62,
            inseam: 0.84,
        },
        Measurements {
            height: 1.55,
            bust: 0.80,
            waist: 0.60,
            hip: 0.90,
            shoulder_width: 0.34,
            arm_length: 0.50,
            inseam: 0.70,
        },
    ] {
        let body = Mannequin::new(&m).unwrap();
        closed_and_oriented(&body);
        let (tris, _) = body.mesh.triangulate();
        let lm = body.landmarks;
        for (name, h, want) in [
            ("hip", lm.hip, m.hip),
            ("waist", lm.waist, m.waist),
            ("bust", lm.bust, m.bust),
        ] {
            let got = girth_at(&body.mesh.positions, &tris, h, 0.0, 0.0).unwrap();
            assert!(
                (got / want - 1.0).abs() < 0.01,
                "{name}: sliced {got} vs {want}"
            );
        }
        // Arm length: shoulder point (arm root) to wrist joint.
        let ua = body
            .skeleton
            .names
            .iter()
            .position(|s| s == "upperarm_l")
            .unwrap();
        let hand = body
            .skeleton
            .names
            .iter()
            .position(|s| s == "hand_l")
            .unwrap();
        let arm = (body.joint_rest[hand] - body.joint_rest[ua]).norm();
        assert!((arm / m.arm_length - 1.0).abs() < 0.1, "arm {arm}");
    }
}

#[test]
fn weights_are_four_normalised_influences() {
    let m = Mannequin::new(&Measurements::default()).unwrap();
    assert_eq!(m.skin.len(), m.mesh.positions.len());
    for (j, w) in m.skin.joints.iter().zip(&m.skin.weights) {
        let s: Real = w.iter().sum();
        assert!((s - 1.0).abs() < 1e-12);
        assert!(w.iter().all(|&x| x >= 0.0));
        assert!(j.iter().all(|&x| (x as usize) < JOINT_NAMES.len()));
    }
}

/// The default mannequin and its skinned body (no press).
fn skinned_mannequin() -> (Mannequin, SkinnedBody) {
    let m = Mannequin::new(&Measurements::default()).unwrap();
    let (tris, _) = m.mesh.triangulate();
    let body = SkinnedBody::new(
        m.mesh.positions.clone(),
        tris,
        m.skeleton.clone(),
        m.joint_rest.clone(),
        m.skin.clone(),
    );
    (m, body)
}

#[test]
fn rest_pose_skins_to_the_rest_mesh_and_a_bent_pose_stays_finite() {
    let (m, mut body) = skinned_mannequin();
    let mut frame = Default::default();
    body.pose(&Pose::rest(22), &mut frame);
    let tryon_core::frames::BodyFrame { positions, .. } = &frame;
    for (a, b) in positions.iter().zip(&m.mesh.positions) {
        assert!((a - b).norm() < 1e-12);
    }
    let mut pose = Pose::rest(22);
    pose.time = 0.1;
    pose.local_rotations[15] = UnitQuat::from_axis_angle(&Vec3::x_axis(), 1.0);
    pose.local_rotations[7] = UnitQuat::from_axis_angle(&Vec3::z_axis(), -0.3);
    pose.root_translation = Vec3::new(0.0, 0.0, 0.1);
    body.pose(&pose, &mut frame);
    assert!(frame.positions.iter().all(tryon_core::math::is_finite));
    assert_eq!(frame.velocities.len(), frame.positions.len());
    // The posed mesh is still a valid mesh (finite, no degenerate face).
    let posed = tryon_core::mesh::PolyMesh {
        positions: frame.positions.clone(),
        faces: m.mesh.faces.clone(),
    };
    assert!(posed.validate().is_ok());
}

/// The mannequin with its arms swung into the torso, its parts set for the press.
fn pressed_mannequin() -> (SkinnedBody, Pose) {
    let (m, mut body) = skinned_mannequin();
    // Parts by strongest joint: each arm from its upper arm down, the rest the torso.
    let parts: Vec<u8> = (0..m.mesh.positions.len())
        .map(|v| {
            let (js, ws) = (m.skin.joints[v], m.skin.weights[v]);
            let k = (0..4).max_by(|&a, &b| ws[a].total_cmp(&ws[b])).unwrap_or(0);
            match js[k] {
                7..=9 => 1,
                11..=13 => 2,
                _ => 0,
            }
        })
        .collect();
    body.press = Some(crate::press::Press { parts, gap: 0.004 });
    let mut pose = Pose::rest(22);
    for (j, angle) in [(7, -0.6), (11, 0.6), (8, -0.3), (12, 0.3)] {
        pose.local_rotations[j] = UnitQuat::from_axis_angle(&Vec3::z_axis(), angle);
    }
    (body, pose)
}

/// The press's moves carried back to the rest mesh (`skin_offsets_at`, what the GLB stores as the
/// body's morph targets) skin to the pressed body: plain skinning of the offset rest mesh equals
/// the pressed shape, with the arms swung into the torso so that the press has work to do.
#[test]
fn skin_offsets_skin_to_the_pressed_body() {
    let (body, pose) = pressed_mannequin();
    let mut pressed = Vec::new();
    body.shape_at(&pose, &mut pressed);
    let mut offsets = Vec::new();
    body.skin_offsets_at(&pose, &mut offsets);
    assert!(
        offsets.len() > 20,
        "the pose presses too little: {}",
        offsets.len()
    );
    let mut plain = body.clone();
    plain.press = None;
    for &(v, d) in &offsets {
        plain.rest_positions[v as usize] += d;
    }
    let mut skinned = Vec::new();
    plain.skin_into(&pose, &mut skinned);
    let worst = skinned
        .iter()
        .zip(&pressed)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, Real::max);
    assert!(worst < 1e-9, "{worst}");
}

/// A shape kept by `shape_next` is what `pose` gives for that pose, press counts included, and
/// is not taken for another pose.
#[test]
fn a_shape_made_for_the_next_pose_is_the_posed_body() {
    let (mut body, pose) = pressed_mannequin();
    let mut fresh = body.clone();
    let mut end = Vec::new();
    body.shape_next(&pose, &mut end);
    let (mut a, mut b) = (BodyFrame::default(), BodyFrame::default());
    body.pose(&pose, &mut a);
    fresh.pose(&pose, &mut b);
    assert_eq!(a.positions, b.positions);
    assert_eq!(a.positions, end);
    assert_eq!(body.corrections(), fresh.corrections());
    assert!(body.corrections().is_some_and(|c| c.moved > 20));
    // Kept for one pose only: another pose is skinned afresh.
    let mut other = pose.clone();
    other.local_rotations[7] = UnitQuat::identity();
    body.shape_next(&pose, &mut end);
    body.pose(&other, &mut a);
    fresh.pose(&other, &mut b);
    assert_eq!(a.positions, b.positions);
    assert_ne!(a.positions, end);
}

/// A body holding still (frames of one pose, each shaped by `shape_next` then posed) keeps its
/// shape without skinning again, and is the freshly skinned body every frame, press counts
/// included; the first new pose after it is skinned afresh.
#[test]
fn a_body_holding_still_keeps_its_shape_and_moves_when_the_pose_does() {
    let (mut body, pose) = pressed_mannequin();
    let mut fresh = body.clone();
    let mut other = pose.clone();
    other.local_rotations[7] = UnitQuat::identity();
    let (mut end, mut want) = (Vec::new(), Vec::new());
    let (mut a, mut b) = (BodyFrame::default(), BodyFrame::default());
    for (k, p) in [&pose, &pose, &pose, &other, &other, &pose]
        .into_iter()
        .enumerate()
    {
        let mut p = p.clone();
        p.time = k as Real / 30.0;
        body.shape_next(&p, &mut end);
        fresh.shape_at(&p, &mut want);
        assert_eq!(end, want, "frame {k}");
        body.pose(&p, &mut a);
        fresh.pose(&p, &mut b);
        assert_eq!(a.positions, b.positions, "frame {k}");
        assert_eq!(a.velocities, b.velocities, "frame {k}");
    }
    assert_eq!(body.corrections(), fresh.corrections());
}
