//! Retargeting on the shared clips: onto an identical skeleton it reproduces the source; CMU 10_04
//! and 131_01 onto the MakeHuman body keep the (scaled) ankle paths and the upper body's bone
//! directions, and stay finite.

use crate::real_assets::data;
use body_model::{MakeHumanBody, joint_transforms};
use mocap_retarget::{Placement, RetargetOptions, Rig, retarget};
use tryon_core::assets::MotionClip;
use tryon_core::math::{Real, Vec3};
use tryon_core::pose::Pose;
use tryon_io::{MhRig, load_makehuman, read_bvh};

fn clip(name: &str) -> MotionClip {
    read_bvh(&data().join("cmu-mocap-bvh").join(name), None).unwrap()
}

/// World joint positions of `pose` on a rig.
fn positions(rig: &Rig, pose: &Pose) -> Vec<Vec3> {
    joint_transforms(&rig.skeleton, &rig.rest, pose).1
}

fn index(rig: &Rig, name: &str) -> usize {
    rig.skeleton.names.iter().position(|n| n == name).unwrap()
}

fn makehuman_rig() -> Rig {
    let a = load_makehuman(&data(), MhRig::CmuMb).unwrap();
    let b = MakeHumanBody::build(&a, 0.5, None).unwrap();
    let tips = b.joint_tails.iter().map(|t| Some(*t)).collect();
    Rig::new(b.skeleton, b.joint_rest, tips)
}

/// Output at the clip's own rate, so that output frames fall on source frames.
fn at_source_rate(c: &MotionClip) -> RetargetOptions {
    RetargetOptions {
        fps: c.fps(),
        ease_in: 0.0,
        ..RetargetOptions::default()
    }
}

#[test]
fn identical_skeleton_reproduces_the_source() {
    let c = clip("10_04.bvh");
    let rig = Rig::from_clip(&c);
    let opt = RetargetOptions {
        placement: Placement::Source,
        skip_synthetic: false,
        ..at_source_rate(&c)
    };
    let r = retarget(&c, &rig, &opt).unwrap();
    assert_eq!(r.poses.len(), c.frames.len());
    assert!((r.ratio - 1.0).abs() < 1e-12);
    let mut worst: Real = 0.0;
    for (p, s) in r.poses.iter().zip(&c.frames) {
        let (a, b) = (positions(&rig, p), positions(&rig, s));
        for (x, y) in a.iter().zip(&b) {
            worst = worst.max((x - y).norm());
        }
    }
    // Ten micrometres: the knee of a nearly straight leg comes from sqrt(l1^2 - a^2), which turns
    // rounding into about 1e-6 m.
    eprintln!("identical skeleton: joints within {worst:.2e} m");
    assert!(worst < 1e-5, "joints differ by {worst} m");
}

/// Ankle errors (m) per frame: the target's FK ankle against the source ankle mapped by the
/// reported scale and origins, shifted across the floor by the target hip joint's offset from the
/// mapped source hip joint.
fn ankle_errors(c: &MotionClip, rig: &Rig) -> (Vec<Real>, mocap_retarget::Retargeted) {
    let r = retarget(c, rig, &at_source_rate(c)).unwrap();
    let src = Rig::from_clip(c);
    let pairs = [
        ("LeftFoot", "LeftFoot", "LeftUpLeg", "LeftUpLeg"),
        ("RightFoot", "RightFoot", "RightUpLeg", "RightUpLeg"),
    ];
    let names = if c.skeleton.names.iter().any(|n| n == "LeftAnkle") {
        [
            ("LeftAnkle", "LeftFoot", "LeftHip", "LeftUpLeg"),
            ("RightAnkle", "RightFoot", "RightHip", "RightUpLeg"),
        ]
    } else {
        pairs
    };
    let errs = r
        .poses
        .iter()
        .zip(&r.source_times)
        .map(|(p, t)| {
            let frame = (t / c.frame_time).round() as usize;
            let sp = positions(&src, &c.frames[frame]);
            let tp = positions(rig, p);
            names
                .iter()
                .map(|(s, t, sh, th)| {
                    let map = |p: Vec3| r.target_origin + (p - r.source_origin) * r.ratio;
                    let mut shift = tp[index(rig, th)] - map(sp[index(&src, sh)]);
                    shift.y = 0.0;
                    let want = map(sp[index(&src, s)]) + shift;
                    (tp[index(rig, t)] - want).norm()
                })
                .fold(0.0, Real::max)
        })
        .collect();
    (errs, r)
}

#[test]
fn cmu_walk_on_makehuman_keeps_scaled_ankles_and_upper_body() {
    let rig = makehuman_rig();
    let c = clip("10_04.bvh");
    let (errs, r) = ankle_errors(&c, &rig);
    assert_eq!(r.skipped_frames, 1, "10_04's frame 0 is a synthetic T-pose");
    let within = errs.iter().filter(|e| **e <= 0.01).count() as Real / errs.len() as Real;
    let mut sorted = errs.clone();
    sorted.sort_by(Real::total_cmp);
    eprintln!(
        "10_04 -> MakeHuman: ratio {:.3}, {} frames, ankle error median {:.2e} m, max {:.4} m, {:.1}% within 1 cm, {} frames out of reach",
        r.ratio,
        errs.len(),
        sorted[sorted.len() / 2],
        sorted[sorted.len() - 1],
        within * 100.0,
        r.unreachable_frames
    );
    assert!(
        within >= 0.99,
        "{:.1}% of frames within 1 cm",
        within * 100.0
    );

    // Upper body: every bone points where the source's points (after rest alignment).
    let src = Rig::from_clip(&c);
    let bones = [
        ("LeftArm", "LeftForeArm"),
        ("LeftForeArm", "LeftHand"),
        ("RightArm", "RightForeArm"),
        ("RightForeArm", "RightHand"),
        ("LeftShoulder", "LeftArm"),
        ("Spine", "Spine1"),
        ("Neck1", "Head"),
    ];
    let mut worst: Real = 0.0;
    for (p, t) in r.poses.iter().zip(&r.source_times) {
        let sp = positions(&src, &c.frames[(t / c.frame_time).round() as usize]);
        let tp = positions(&rig, p);
        for (a, b) in bones {
            let ds = sp[index(&src, b)] - sp[index(&src, a)];
            let dt = tp[index(&rig, b)] - tp[index(&rig, a)];
            worst = worst.max(ds.angle(&dt).to_degrees());
        }
    }
    eprintln!("10_04 -> MakeHuman: upper-body bone directions within {worst:.2e} degrees");
    assert!(worst < 1e-3, "a bone is {worst} degrees off");
}

#[test]
fn both_clips_retarget_finite_at_scene_rate() {
    let rig = makehuman_rig();
    for name in ["10_04.bvh", "131_01.bvh"] {
        let c = clip(name);
        let r = retarget(&c, &rig, &RetargetOptions::default()).unwrap();
        let expect = (r.source_times.len() as Real, c.duration() * 30.0);
        assert!((expect.0 - expect.1).abs() <= 2.0, "{name}: {expect:?}");
        assert!(r.poses.iter().all(|p| {
            p.root_translation.iter().all(|x| x.is_finite())
                && p.local_rotations
                    .iter()
                    .all(|q| q.coords.iter().all(|x| x.is_finite()))
        }));
        let (errs, _) = ankle_errors(&c, &rig);
        let within = errs.iter().filter(|e| **e <= 0.01).count() as Real / errs.len() as Real;
        eprintln!(
            "{name} ({}): {} frames at 30 fps, ratio {:.3}, {:.1}% of 120-fps frames with ankles within 1 cm",
            r.source_scheme,
            r.poses.len(),
            r.ratio,
            within * 100.0
        );
    }
}

#[test]
fn hands_point_where_the_source_hands_point() {
    // CMU's fingers start where the hand does, so a hand's rest direction is its forearm's; the
    // MakeHuman hand's is toward its tail. Before this was handled the hand kept MakeHuman's rest
    // orientation under CMU's rotation and hung palm up, fingers across the hips (up to 94 degrees
    // off).
    let rig = makehuman_rig();
    let c = clip("10_04.bvh");
    let r = retarget(&c, &rig, &at_source_rate(&c)).unwrap();
    let src = Rig::from_clip(&c);
    let mut worst: Real = 0.0;
    for (p, t) in r.poses.iter().zip(&r.source_times) {
        let sp = &c.frames[(t / c.frame_time).round() as usize];
        let (sg, _) = joint_transforms(&src.skeleton, &src.rest, sp);
        let (tg, _) = joint_transforms(&rig.skeleton, &rig.rest, p);
        for (hand, forearm) in [("LeftHand", "LeftForeArm"), ("RightHand", "RightForeArm")] {
            let (sh, sf) = (index(&src, hand), index(&src, forearm));
            let th = index(&rig, hand);
            let ds = sg[sh] * (src.rest[sh] - src.rest[sf]);
            let dt = tg[th] * (rig.tips[th].unwrap() - rig.rest[th]);
            worst = worst.max(ds.angle(&dt).to_degrees());
        }
    }
    eprintln!("10_04 -> MakeHuman: hands within {worst:.2e} degrees");
    assert!(worst < 1e-3, "a hand is {worst} degrees off");
}

#[test]
fn no_joint_turns_faster_than_a_person_can() {
    // The scenes' bodies as built (retargeting, arm clearance, turn limit), both clips, MakeHuman
    // and the mannequin: a retargeting fault (an arm twisted into a knot) or a glitch in the data
    // shows as a joint turning far faster than any person's does between two frames. Without
    // the limit: 1,044 degrees per second on makehuman-dress-walk (a toe), 5,270 on
    // makehuman-casual-131 (131_01's glitch at 1.97 s).
    use mocap_retarget::turns::{DEFAULT_LIMIT_DEG_PER_S, fastest_turn};
    use tryon_pipeline::{Pipeline, Scene};
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes");
    let mannequin = |clip: &str| {
        format!(
            "[scene]\nname = \"m\"\nfps = 30\n[body]\nkind = \"mannequin\"\n[garment]\nkind = \"dress\"\n\
             [motion]\nkind = \"bvh\"\nfile = \"cmu-mocap-bvh/{clip}\"\n"
        )
    };
    let mut cases: Vec<(String, String)> = ["makehuman-dress-walk", "makehuman-casual-131"]
        .iter()
        .map(|s| {
            let path = scenes.join(format!("{s}.toml"));
            (s.to_string(), std::fs::read_to_string(path).unwrap())
        })
        .collect();
    for clip in ["10_04.bvh", "131_01.bvh"] {
        cases.push((format!("mannequin {clip}"), mannequin(clip)));
    }
    for (name, text) in cases {
        let scene = Scene::parse(&text, &scenes.join("t.toml")).unwrap();
        let p = Pipeline::new(scene).unwrap();
        let rig = p.body.rig().unwrap();
        let motion = p.motion.as_ref().unwrap();
        let dt = 1.0 / 30.0;
        let n = (motion.duration() / dt) as usize;
        let poses: Vec<Pose> = (0..=n)
            .map(|k| {
                let mut q = Pose::rest(rig.skeleton.names.len());
                motion.sample(k as Real * dt, &mut q);
                q
            })
            .collect();
        let t = fastest_turn(rig.skeleton, rig.joint_rest, &poses, dt).unwrap();
        eprintln!(
            "{name}: fastest turn {:.0} deg/s ({} at frame {})",
            t.deg_per_s, t.joint, t.frame
        );
        // The scenes' limit (max_turn), a little over for the interpolation between frames.
        assert!(
            t.deg_per_s <= DEFAULT_LIMIT_DEG_PER_S * 1.001,
            "{name}: {t:?}"
        );
    }
}

#[test]
fn a_fast_body_is_moved_in_sub_frames_near_the_cloth_only() {
    // The mannequin in its dress under 131_01 (lunges and arm swings): frames whose body moves
    // more than body_step near the cloth are split; body_step = 0 never splits; a body holding
    // still never does; the split run stays finite.
    use tryon_pipeline::timers::Timers;
    use tryon_pipeline::{Pipeline, Scene};
    let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes");
    let text = |motion: &str, step: &str| {
        format!(
            "[scene]\nname = \"m\"\nfps = 30\nsettle = 0\nbody_step = {step}\n[body]\nkind = \"mannequin\"\n\
             [garment]\nkind = \"dress\"\n[motion]\n{motion}\n"
        )
    };
    let parts = |t: String, frames: usize| {
        let mut p = Pipeline::new(Scene::parse(&t, &scenes.join("t.toml")).unwrap()).unwrap();
        let mut st = p.start();
        let mut timers = Timers::default();
        let parts: Vec<u32> = (1..=frames)
            .map(|k| {
                p.advance_coarse(&mut st, p.frame_time(k), &mut timers)
                    .body_parts
            })
            .collect();
        assert!(
            p.cloth
                .positions
                .iter()
                .all(|x| x.iter().all(|c| c.is_finite()))
        );
        parts
    };
    let clip = "kind = \"bvh\"\nfile = \"cmu-mocap-bvh/131_01.bvh\"\nease_in = 0";
    let split = parts(text(clip, "0.08"), 90);
    let most = *split.iter().max().unwrap();
    eprintln!(
        "131_01 on the mannequin: {} of 90 frames split, at most {most} parts",
        split.iter().filter(|&&n| n > 1).count()
    );
    assert!((2..=8).contains(&most), "{split:?}");
    assert!(split.iter().all(|&n| n >= 1));
    assert!(parts(text(clip, "0"), 30).iter().all(|&n| n == 1));
    assert!(
        parts(text("kind = \"still\"", "0.001"), 10)
            .iter()
            .all(|&n| n == 1)
    );
}
