//! Retargeting (P1.6): a source clip's motion on a target skeleton. Bones correspond through roles
//! (name maps per scheme); rest poses are aligned bone by bone (the swing that turns the target's rest
//! bone direction into the source's), so a T-pose, an arms-down pose and an A-pose all map. The root
//! moves as the source's, scaled by the ratio of leg lengths; each leg is solved by two-bone IK toward
//! the source's ankle (scaled, and shifted across the floor by the hip joint's offset from the
//! source's, since hip widths differ), its knee in the source knee's bend plane; feet, spine, neck, head
//! and arms copy the source's rotations relative to the aligned rest. The clip is resampled to the
//! scene's frame rate and eased in from the target's rest pose.

use crate::ik::{frame_rotation, solve_leg};
use crate::names::{CHAINS, REQUIRED, ROLES, Role, RoleMap};
use thiserror::Error;
use tryon_core::assets::MotionClip;
use tryon_core::math::{Real, UnitQuat, Vec3};
use tryon_core::pose::{Pose, Skeleton};
use tryon_core::stages::MotionSource;

/// A skeleton at rest: joint positions (world, m) and, for joints without children, a tip.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rig {
    pub skeleton: Skeleton,
    pub rest: Vec<Vec3>,
    pub tips: Vec<Option<Vec3>>,
}

impl Rig {
    /// A rig from rest joint positions (tips: bone tails where known).
    pub fn new(skeleton: Skeleton, rest: Vec<Vec3>, tips: Vec<Option<Vec3>>) -> Self {
        Rig {
            skeleton,
            rest,
            tips,
        }
    }

    /// A clip's skeleton with every rotation zero (the BVH offsets), end sites as tips.
    pub fn from_clip(clip: &MotionClip) -> Self {
        let s = &clip.skeleton;
        let mut rest: Vec<Vec3> = Vec::with_capacity(s.parents.len());
        for j in 0..s.parents.len() {
            let base = s.parents[j].map_or(Vec3::zeros(), |p| rest[p]);
            rest.push(base + s.rest_offsets[j]);
        }
        let mut tips = vec![None; rest.len()];
        for (j, o) in &clip.end_sites {
            if let Some(t) = tips.get_mut(*j) {
                t.get_or_insert(rest[*j] + o);
            }
        }
        Rig::new(s.clone(), rest, tips)
    }

    /// Rest direction of `role`'s bone: toward the next role of its chain that sits elsewhere, else
    /// the bone's tip where the rig knows it, else a child joint elsewhere, else the direction of
    /// the chain's bone before it. (A child before the tip would take a hand's direction from
    /// whichever finger is listed first: MakeHuman lists the thumb, 30 degrees off the hand.)
    fn direction(&self, map: &RoleMap, role: Role) -> Option<Vec3> {
        let j = map.get(role)?;
        let chain = CHAINS.iter().find(|c| c.contains(&role))?;
        let at = chain.iter().position(|r| *r == role)?;
        let far = |p: Vec3| (p - self.rest[j]).try_normalize(1e-6);
        for r in &chain[at + 1..] {
            if let Some(d) = map.get(*r).and_then(|k| far(self.rest[k])) {
                return Some(d);
            }
        }
        self.tips
            .get(j)
            .copied()
            .flatten()
            .and_then(far)
            .or_else(|| self.child_direction(j))
            // A bone with nothing beyond it (CMU's hands: their fingers start where they do)
            // continues the bone before it: without a direction its rest alignment would be lost
            // and the hand would keep the target's rest orientation under the source's rotation.
            .or_else(|| {
                let before = chain[..at].iter().rev().find(|r| map.get(**r).is_some())?;
                self.direction(map, *before)
            })
    }

    /// Rest direction from joint `j` to its first child elsewhere, else to its tip.
    fn child_direction(&self, j: usize) -> Option<Vec3> {
        let far = |p: Vec3| (p - self.rest[j]).try_normalize(1e-6);
        let children = (0..self.rest.len()).filter(|&k| self.skeleton.parents[k] == Some(j));
        for k in children {
            if let Some(d) = far(self.rest[k]) {
                return Some(d);
            }
        }
        self.tips.get(j).copied().flatten().and_then(far)
    }
}

/// Where the retargeted body stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Placement {
    /// Source coordinates scaled by the leg ratio (no offset).
    Source,
    /// Starts over the target's rest position, the source's planted-ankle height on the target's.
    StartAtTarget,
}

/// Settings of a retargeting.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RetargetOptions {
    /// Output frame rate.
    pub fps: Real,
    pub placement: Placement,
    /// Seconds of the source to skip (after any synthetic T-pose frames).
    pub start: Real,
    /// Seconds of the source to use (`None`: to its end).
    pub duration: Option<Real>,
    /// Seconds to blend in from the target's rest pose.
    pub ease_in: Real,
    /// Drop leading frames that jump to the next by more than 15 degrees (CMU's synthetic T-pose).
    pub skip_synthetic: bool,
}

impl Default for RetargetOptions {
    fn default() -> Self {
        RetargetOptions {
            fps: 30.0,
            placement: Placement::StartAtTarget,
            start: 0.0,
            duration: None,
            ease_in: 0.5,
            skip_synthetic: true,
        }
    }
}

/// Why a clip cannot be retargeted.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum RetargetError {
    #[error(
        "the {which} skeleton matches no known naming scheme (CMU, CMU hip/knee, MakeHuman, mannequin); its joints start {first:?}"
    )]
    UnknownSkeleton {
        which: &'static str,
        first: Vec<String>,
    },
    #[error("the clip has no frames left after skipping {skipped} and starting at {start} s")]
    NoFrames { skipped: usize, start: Real },
    #[error("option `{name}` = {value} is invalid: expected {expected}")]
    BadOption {
        name: &'static str,
        value: Real,
        expected: &'static str,
    },
}

/// A retargeted clip on the target skeleton, at the output frame rate (ease-in frames first).
#[derive(Clone, Debug)]
pub struct Retargeted {
    pub skeleton: Skeleton,
    pub frame_time: Real,
    pub poses: Vec<Pose>,
    /// Target leg length over source leg length.
    pub ratio: Real,
    /// Source point mapped onto `target_origin`: p_t = target_origin + (p_s - source_origin) * ratio.
    pub source_origin: Vec3,
    pub target_origin: Vec3,
    pub source_scheme: &'static str,
    pub target_scheme: &'static str,
    /// Leading source frames dropped as synthetic.
    pub skipped_frames: usize,
    /// Number of ease-in frames at the start of `poses`.
    pub ease_frames: usize,
    /// Source time (s) of each output frame after the ease-in.
    pub source_times: Vec<Real>,
    /// Output frames in which an ankle target was out of reach (the leg was straightened).
    pub unreachable_frames: usize,
    /// What [`crate::clearance::keep_arms_clear`] did, if it ran.
    pub clearance: crate::clearance::Clearance,
}

fn swing(from: Vec3, to: Vec3) -> UnitQuat {
    UnitQuat::rotation_between(&from, &to).unwrap_or_else(|| {
        let a = if from.x.abs() < 0.9 {
            Vec3::x()
        } else {
            Vec3::y()
        };
        UnitQuat::from_scaled_axis(from.cross(&a).normalize() * std::f64::consts::PI)
    })
}

/// Global rotations and positions of a clip's skeleton for `pose`.
fn forward(s: &Skeleton, pose: &Pose) -> (Vec<UnitQuat>, Vec<Vec3>) {
    let n = s.parents.len();
    let mut g: Vec<UnitQuat> = Vec::with_capacity(n);
    let mut p: Vec<Vec3> = Vec::with_capacity(n);
    for j in 0..n {
        let l = pose.local_rotations.get(j).copied().unwrap_or_default();
        match s.parents[j] {
            Some(q) => {
                p.push(p[q] + g[q] * s.rest_offsets[j]);
                g.push(g[q] * l);
            }
            None => {
                p.push(s.rest_offsets[j] + pose.root_translation);
                g.push(l);
            }
        }
    }
    (g, p)
}

/// The source pose at time `t` (s), interpolated between frames.
fn sample_clip(clip: &MotionClip, t: Real) -> Pose {
    let last = clip.frames.len() - 1;
    let f = (t / clip.frame_time).clamp(0.0, last as Real);
    let i = (f.floor() as usize).min(last);
    let k = (i + 1).min(last);
    let a = f - i as Real;
    let (p, q) = (&clip.frames[i], &clip.frames[k]);
    Pose {
        time: t,
        root_translation: p.root_translation.lerp(&q.root_translation, a),
        local_rotations: p
            .local_rotations
            .iter()
            .zip(&q.local_rotations)
            .map(|(x, y)| x.try_slerp(y, a, 1e-9).unwrap_or(*x))
            .collect(),
    }
}

/// Leading frames that jump to the next by more than `deg` degrees at some joint.
fn synthetic_frames(clip: &MotionClip, deg: Real) -> usize {
    let jump = |a: &Pose, b: &Pose| {
        a.local_rotations
            .iter()
            .zip(&b.local_rotations)
            .map(|(x, y)| x.angle_to(y))
            .fold(0.0, Real::max)
    };
    let mut k = 0;
    while k + 2 < clip.frames.len() && jump(&clip.frames[k], &clip.frames[k + 1]) > deg.to_radians()
    {
        k += 1;
    }
    k
}

/// How a target joint gets its rotation.
#[derive(Clone, Copy)]
enum Copy {
    /// The source joint's world rotation times the rest alignment.
    World(usize, UnitQuat),
    /// The source joint's local rotation.
    Local(usize),
    /// The parent's world rotation.
    Inherit,
}

struct Leg {
    src: [usize; 3],
    tgt: [usize; 3],
    l1: Real,
    l2: Real,
    d1: Vec3,
    d2: Vec3,
}

/// Retargets `clip` onto `target`.
pub fn retarget(
    clip: &MotionClip,
    target: &Rig,
    opt: &RetargetOptions,
) -> Result<Retargeted, RetargetError> {
    for (name, value, ok, expected) in [
        (
            "fps",
            opt.fps,
            opt.fps > 0.0 && opt.fps <= 1000.0,
            "0 < fps <= 1000",
        ),
        ("start", opt.start, opt.start >= 0.0, "start >= 0"),
        (
            "ease_in",
            opt.ease_in,
            (0.0..=10.0).contains(&opt.ease_in),
            "0..=10 s",
        ),
        (
            "duration",
            opt.duration.unwrap_or(1.0),
            opt.duration.is_none_or(|d| d > 0.0),
            "a positive duration",
        ),
    ] {
        if !(ok && value.is_finite()) {
            return Err(RetargetError::BadOption {
                name,
                value,
                expected,
            });
        }
    }
    let source = Rig::from_clip(clip);
    let unknown = |which, s: &Skeleton| RetargetError::UnknownSkeleton {
        which,
        first: s.names.iter().take(6).cloned().collect(),
    };
    let sm = RoleMap::detect(&source.skeleton).ok_or_else(|| unknown("source", &clip.skeleton))?;
    let tm =
        RoleMap::detect(&target.skeleton).ok_or_else(|| unknown("target", &target.skeleton))?;
    let skipped = if opt.skip_synthetic && !clip.frames.is_empty() {
        synthetic_frames(clip, 15.0)
    } else {
        0
    };
    let t0 = skipped as Real * clip.frame_time + opt.start;
    let t_end = opt
        .duration
        .map_or(clip.duration(), |d| (t0 + d).min(clip.duration()));
    if clip.frames.is_empty() || t_end <= t0 {
        return Err(RetargetError::NoFrames {
            skipped,
            start: opt.start,
        });
    }
    let dt = 1.0 / opt.fps;
    let count = ((t_end - t0) / dt + 1e-4).floor() as usize + 1;
    let source_times: Vec<Real> = (0..count).map(|k| t0 + k as Real * dt).collect();

    // Rest alignment: per role present in both, the swing from the target's rest bone direction to
    // the source's.
    let mut swings: [Option<UnitQuat>; ROLES] = [None; ROLES];
    for r in crate::names::ALL_ROLES {
        if let (Some(_), Some(_)) = (sm.get(r), tm.get(r)) {
            let ds = source.direction(&sm, r);
            let dtg = target.direction(&tm, r);
            swings[r as usize] = Some(match (ds, dtg) {
                (Some(a), Some(b)) => swing(b, a),
                _ => UnitQuat::identity(),
            });
        }
    }
    let req = |m: &RoleMap, r: Role| m.get(r).unwrap_or(0);
    let legs: Vec<Leg> = [
        [Role::LThigh, Role::LShin, Role::LFoot],
        [Role::RThigh, Role::RShin, Role::RFoot],
    ]
    .iter()
    .map(|roles| {
        let src = roles.map(|r| req(&sm, r));
        let tgt = roles.map(|r| req(&tm, r));
        let v1 = target.rest[tgt[1]] - target.rest[tgt[0]];
        let v2 = target.rest[tgt[2]] - target.rest[tgt[1]];
        Leg {
            src,
            tgt,
            l1: v1.norm(),
            l2: v2.norm(),
            d1: v1,
            d2: v2,
        }
    })
    .collect();
    debug_assert!(REQUIRED.iter().all(|r| sm.get(*r).is_some()));
    let src_leg: Real = legs
        .iter()
        .map(|l| {
            (source.rest[l.src[1]] - source.rest[l.src[0]]).norm()
                + (source.rest[l.src[2]] - source.rest[l.src[1]]).norm()
        })
        .sum::<Real>()
        / 2.0;
    let tgt_leg: Real = legs.iter().map(|l| l.l1 + l.l2).sum::<Real>() / 2.0;
    let ratio = if src_leg > 1e-9 {
        tgt_leg / src_leg
    } else {
        1.0
    };

    let src_poses: Vec<Pose> = source_times.iter().map(|t| sample_clip(clip, *t)).collect();
    let src_fk: Vec<(Vec<UnitQuat>, Vec<Vec3>)> = src_poses
        .iter()
        .map(|p| forward(&clip.skeleton, p))
        .collect();
    let hips_t = req(&tm, Role::Hips);
    // The root is placed through the midpoint of the hip joints, so that the legs reach as far on
    // the target as on the source whatever the pelvis joint's height.
    let mid_s = |p: &[Vec3]| (p[legs[0].src[0]] + p[legs[1].src[0]]) / 2.0;
    let mid_t_rest = (target.rest[legs[0].tgt[0]] + target.rest[legs[1].tgt[0]]) / 2.0;
    let (source_origin, target_origin) = match opt.placement {
        Placement::Source => (Vec3::zeros(), Vec3::zeros()),
        Placement::StartAtTarget => {
            let mut lows: Vec<Real> = src_fk
                .iter()
                .map(|(_, p)| p[legs[0].src[2]].y.min(p[legs[1].src[2]].y))
                .collect();
            lows.sort_by(Real::total_cmp);
            let floor_s = lows[lows.len() / 20];
            let first = mid_s(&src_fk[0].1);
            let ankle_t = (target.rest[legs[0].tgt[2]].y + target.rest[legs[1].tgt[2]].y) / 2.0;
            (
                Vec3::new(first.x, floor_s, first.z),
                Vec3::new(mid_t_rest.x, ankle_t, mid_t_rest.z),
            )
        }
    };
    let place = |p: Vec3| target_origin + (p - source_origin) * ratio;

    let n = target.skeleton.parents.len();
    // What each target joint copies: its role's source joint (world rotation after rest alignment),
    // else a source joint of the same name (fingers, hip and collar offsets: its local rotation, so
    // that fixed offsets inside the pelvis and chest keep the target's proportions); otherwise it
    // keeps its parent's orientation.
    let copy: Vec<Copy> = (0..n)
        .map(|j| {
            if let Some(r) = crate::names::ALL_ROLES
                .iter()
                .find(|r| tm.get(**r) == Some(j))
            {
                return match (sm.get(*r), swings[*r as usize]) {
                    (Some(js), Some(s)) => Copy::World(js, s),
                    _ => Copy::Inherit,
                };
            }
            let name = &target.skeleton.names[j];
            match clip.skeleton.names.iter().position(|x| x == name) {
                Some(js) => Copy::Local(js),
                None => Copy::Inherit,
            }
        })
        .collect();
    let mut unreachable = 0;
    let mut poses = Vec::with_capacity(count);
    for (k, ((gs, ps), src_pose)) in src_fk.iter().zip(&src_poses).enumerate() {
        let local_of = |js: usize| {
            src_pose
                .local_rotations
                .get(js)
                .copied()
                .unwrap_or_default()
        };
        let mut g: Vec<UnitQuat> = Vec::with_capacity(n);
        let mut p: Vec<Vec3> = Vec::with_capacity(n);
        let mut shins = [UnitQuat::identity(); 2];
        let mut short = false;
        for j in 0..n {
            let parent = target.skeleton.parents[j];
            let inherited = parent.map_or(UnitQuat::identity(), |q| g[q]);
            let mut gj = match copy[j] {
                Copy::World(js, s) => gs[js] * s,
                Copy::Local(js) => inherited * local_of(js),
                Copy::Inherit => inherited,
            };
            let pj = match parent {
                Some(q) => p[q] + g[q] * (target.rest[j] - target.rest[q]),
                None => place(mid_s(ps)) - gj * (mid_t_rest - target.rest[j]),
            };
            p.push(pj);
            for (side, leg) in legs.iter().enumerate() {
                if j == leg.tgt[0] {
                    let (hs, ks, a_s) = (ps[leg.src[0]], ps[leg.src[1]], ps[leg.src[2]]);
                    let line = (a_s - hs).try_normalize(1e-9).unwrap_or(-Vec3::y());
                    let bend = ks - hs;
                    let pole = (bend - line * bend.dot(&line))
                        .try_normalize(1e-6)
                        .unwrap_or_else(|| g[hips_t] * Vec3::z());
                    // The ankle goes where the source's goes (scaled), shifted across the floor by
                    // how far this hip joint sits from the source's (hip widths differ): feet keep
                    // their stance under their own hips, heights stay the source's.
                    let mut shift = pj - place(hs);
                    shift.y = 0.0;
                    let sol = solve_leg(pj, place(a_s) + shift, leg.l1, leg.l2, pole);
                    short |= !sol.reached;
                    let thigh = sol.knee - pj;
                    let shin = sol.ankle - sol.knee;
                    let normal = thigh.cross(&pole);
                    let thigh_rot = frame_rotation(leg.d1, leg.d1.cross(&Vec3::z()), thigh, normal);
                    let shin_rot = frame_rotation(leg.d2, leg.d2.cross(&Vec3::z()), shin, normal);
                    gj = UnitQuat::from_matrix(&thigh_rot);
                    shins[side] = UnitQuat::from_matrix(&shin_rot);
                } else if j == leg.tgt[1] {
                    gj = shins[side];
                }
            }
            g.push(gj);
        }
        if short {
            unreachable += 1;
        }
        let mut pose = Pose::rest(n);
        pose.time = k as Real * dt;
        pose.root_translation = p[hips_t] - target.rest[hips_t];
        for j in 0..n {
            pose.local_rotations[j] = match target.skeleton.parents[j] {
                Some(q) => g[q].inverse() * g[j],
                None => g[j],
            };
        }
        poses.push(pose);
    }
    let ease_frames = (opt.ease_in * opt.fps).round() as usize;
    let first = poses[0].clone();
    let mut out: Vec<Pose> = (0..ease_frames)
        .map(|k| {
            let s = smoothstep(k as Real / ease_frames as Real);
            Pose {
                time: 0.0,
                root_translation: first.root_translation * s,
                local_rotations: first
                    .local_rotations
                    .iter()
                    .map(|q| UnitQuat::identity().try_slerp(q, s, 1e-9).unwrap_or(*q))
                    .collect(),
            }
        })
        .collect();
    out.extend(poses);
    for (k, p) in out.iter_mut().enumerate() {
        p.time = k as Real * dt;
    }
    Ok(Retargeted {
        skeleton: target.skeleton.clone(),
        frame_time: dt,
        poses: out,
        ratio,
        source_origin,
        target_origin,
        source_scheme: sm.scheme,
        target_scheme: tm.scheme,
        skipped_frames: skipped,
        ease_frames,
        source_times,
        unreachable_frames: unreachable,
        clearance: Default::default(),
    })
}

fn smoothstep(t: Real) -> Real {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl MotionSource for Retargeted {
    fn duration(&self) -> Real {
        self.poses.len().saturating_sub(1) as Real * self.frame_time
    }

    fn sample(&self, t: Real, out: &mut Pose) {
        let Some(last) = self.poses.len().checked_sub(1) else {
            *out = Pose::rest(self.skeleton.names.len());
            return;
        };
        let f = (t / self.frame_time).clamp(0.0, last as Real);
        let i = (f.floor() as usize).min(last);
        let k = (i + 1).min(last);
        let a = f - i as Real;
        let (p, q) = (&self.poses[i], &self.poses[k]);
        out.time = t;
        out.root_translation = p.root_translation.lerp(&q.root_translation, a);
        out.local_rotations.clear();
        out.local_rotations.extend(
            p.local_rotations
                .iter()
                .zip(&q.local_rotations)
                .map(|(x, y)| x.try_slerp(y, a, 1e-9).unwrap_or(*x)),
        );
    }
}
