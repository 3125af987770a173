//! Arms kept clear of the body. Retargeting copies the source's bone directions, so an arm hangs at
//! the source's angle; on a body whose hips are wider than its shoulders (MakeHuman's female body
//! under CMU 10_04: shoulder joints 14.7 cm from the midline, hip surface about 18 cm) the hanging
//! hand then sits inside the hip, and a garment between them is pinched through. Here each frame's
//! arms are opened sideways about the shoulder, by the smallest angle that puts the elbow, wrist
//! and hand at least a margin outside the body's rest envelope (its cross-sections without the
//! arms), and the angles are smoothed over time so the correction never jerks. The head is kept
//! clear the same way: a clip whose actor touches their face puts a retargeted hand, on a body of
//! other proportions, into the head (CMU 131_01 on the MakeHuman body: the fingers in the face
//! and the sleeve's cuff 27 mm inside it), so the wrist and forearm are also kept [`HEAD_MARGIN`]
//! and the fingertip half of it outside the head at rest ([`Head`], carried by the head joint), a
//! raised hand swinging away from the head.

use crate::names::{Role, RoleMap};
use crate::retarget::Retargeted;
use tryon_core::math::{Real, UnitQuat, Vec3};
use tryon_core::pose::{Pose, Skeleton};

/// How far outside the body's rest shape the arm joints are kept unless a scene says otherwise
/// (m): a wrist's or hand's own half-thickness, two layers of cloth and the collision thickness.
/// On makehuman-dress-walk 0.04 left the jacket pinched 19 mm into the hips; 0.07 clears them
/// (openings of at most 10 degrees).
pub const DEFAULT_MARGIN: Real = 0.07;
/// How far outside the head the wrist and forearm are kept (m): a wrist's half-thickness and a
/// sleeve. The fingertip, with no sleeve, is kept half as far.
pub const HEAD_MARGIN: Real = 0.03;
/// Seconds either side over which openings are smoothed.
pub const SMOOTHING_S: Real = 0.15;

/// Angular sectors of a cross-section.
const SECTORS: usize = 32;
/// Height of a cross-section slab (m).
const SLAB: Real = 0.02;
/// Largest opening tried (degrees) and its step.
const MAX_OPEN_DEG: u32 = 45;

/// The body at rest, arms left out, as horizontal slabs: each a centre and the largest radius per
/// angular sector around it (a star-shaped cross-section).
#[derive(Clone, Debug, PartialEq)]
pub struct Envelope {
    pub y0: Real,
    pub slabs: Vec<Slab>,
    /// The head, when the body has one.
    pub head: Option<Head>,
    /// Per hand joint, its farthest skin vertex at rest (the middle fingertip): a rig's hand bone
    /// can end at the knuckles, 15 cm short of the fingers that reach a face.
    pub fingertips: Vec<(usize, Vec3)>,
}

/// The head at rest, carried by the head joint `joint`: star-shaped about `centre` (the middle of
/// its box), its largest radius per direction bin (latitude x longitude), so a forehead or a nose
/// counts where an ellipsoid would miss it.
#[derive(Clone, Debug, PartialEq)]
pub struct Head {
    pub joint: usize,
    pub centre: Vec3,
    /// `HEAD_BINS.0 * HEAD_BINS.1` radii (m), latitude-major.
    pub radius: Vec<Real>,
}

/// Direction bins of a [`Head`]: latitude, longitude.
const HEAD_BINS: (usize, usize) = (12, 24);

fn head_bin(d: &Vec3) -> (usize, usize) {
    let r = d.norm();
    let lat = if r > 0.0 {
        (d.y / r).clamp(-1.0, 1.0).acos()
    } else {
        0.0
    };
    let lon = d.z.atan2(d.x) + std::f64::consts::PI;
    let i = ((lat / std::f64::consts::PI * HEAD_BINS.0 as Real) as usize).min(HEAD_BINS.0 - 1);
    let k = ((lon / std::f64::consts::TAU * HEAD_BINS.1 as Real) as usize).min(HEAD_BINS.1 - 1);
    (i, k)
}

impl Head {
    /// The head around `points` (its vertices at rest); `None` for none.
    pub fn new(joint: usize, points: &[Vec3]) -> Option<Head> {
        let first = *points.first()?;
        // The box's middle: a face has many more vertices than the back of the head, which would
        // pull a mean forward.
        let lo = points.iter().fold(first, |a, p| a.inf(p));
        let hi = points.iter().fold(first, |a, p| a.sup(p));
        let centre = (lo + hi) / 2.0;
        if !centre.iter().all(|c| c.is_finite()) {
            return None;
        }
        let mut radius = vec![0.0; HEAD_BINS.0 * HEAD_BINS.1];
        for p in points {
            let (i, k) = head_bin(&(p - centre));
            let r = &mut radius[i * HEAD_BINS.1 + k];
            *r = Real::max(*r, (p - centre).norm());
        }
        Some(Head {
            joint,
            centre,
            radius,
        })
    }

    /// Whether `p` (in the head's rest frame) is within `margin` of the head: nearer the centre
    /// than the largest radius of its direction's bin and the bins around it, plus `margin`.
    pub fn contains(&self, p: &Vec3, margin: Real) -> bool {
        let d = p - self.centre;
        let (i, k) = head_bin(&d);
        let (nl, nk) = HEAD_BINS;
        let mut reach: Real = 0.0;
        for ii in i.saturating_sub(1)..=(i + 1).min(nl - 1) {
            for dk in [nk - 1, 0, 1] {
                reach = reach.max(self.radius[ii * nk + (k + dk) % nk]);
            }
        }
        reach > 0.0 && d.norm() < reach + margin
    }
}

/// One slab of an [`Envelope`].
#[derive(Clone, Debug, PartialEq)]
pub struct Slab {
    pub centre: [Real; 2],
    pub radius: [Real; SECTORS],
}

fn sector(dx: Real, dz: Real) -> usize {
    let a = dz.atan2(dx) + std::f64::consts::PI;
    ((a / std::f64::consts::TAU * SECTORS as Real) as usize).min(SECTORS - 1)
}

impl Envelope {
    /// The envelope of `points` (the body's rest vertices not on the arms) below `top`.
    pub fn new(points: &[Vec3], top: Real) -> Option<Envelope> {
        let below: Vec<&Vec3> = points.iter().filter(|p| p.y < top).collect();
        let y0 = below.iter().map(|p| p.y).fold(Real::INFINITY, Real::min);
        if !y0.is_finite() {
            return None;
        }
        let n = ((top - y0) / SLAB).ceil().max(1.0) as usize;
        let mut sums = vec![(0.0, 0.0, 0usize); n];
        let slab_of = |y: Real| (((y - y0) / SLAB) as usize).min(n - 1);
        for p in &below {
            let s = &mut sums[slab_of(p.y)];
            s.0 += p.x;
            s.1 += p.z;
            s.2 += 1;
        }
        let mut slabs: Vec<Slab> = sums
            .iter()
            .map(|&(x, z, c)| Slab {
                centre: if c > 0 {
                    [x / c as Real, z / c as Real]
                } else {
                    [0.0; 2]
                },
                radius: [0.0; SECTORS],
            })
            .collect();
        for p in &below {
            let s = &mut slabs[slab_of(p.y)];
            let (dx, dz) = (p.x - s.centre[0], p.z - s.centre[1]);
            let r = &mut s.radius[sector(dx, dz)];
            *r = r.max((dx * dx + dz * dz).sqrt());
        }
        Some(Envelope {
            y0,
            slabs,
            head: None,
            fingertips: Vec::new(),
        })
    }

    /// The envelope of a skinned body at rest: its vertices whose strongest joint is not an upper
    /// arm or below one, up to the lower shoulder joint. `None` without arms or vertices.
    pub fn from_skin(
        points: &[Vec3],
        joints: &[[u16; 4]],
        weights: &[[Real; 4]],
        skeleton: &Skeleton,
        rest: &[Vec3],
    ) -> Option<Envelope> {
        let map = RoleMap::detect(skeleton)?;
        let uppers = [map.get(Role::LUpperArm)?, map.get(Role::RUpperArm)?];
        let on_arm = |mut j: usize| loop {
            if uppers.contains(&j) {
                return true;
            }
            match skeleton.parents.get(j).copied().flatten() {
                Some(p) => j = p,
                None => return false,
            }
        };
        let strongest = |(j, w): (&[u16; 4], &[Real; 4])| {
            let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
            j[k] as usize
        };
        let body: Vec<Vec3> = points
            .iter()
            .zip(joints.iter().zip(weights))
            .filter(|(_, jw)| !on_arm(strongest(*jw)))
            .map(|(p, _)| *p)
            .collect();
        let mut e = Envelope::new(&body, rest[uppers[0]].y.min(rest[uppers[1]].y))?;
        // The skin moved by joint `top` or a joint under it.
        let skin_under = |top: usize| -> Vec<Vec3> {
            let under = |mut j: usize| loop {
                if j == top {
                    return true;
                }
                match skeleton.parents.get(j).copied().flatten() {
                    Some(p) => j = p,
                    None => return false,
                }
            };
            points
                .iter()
                .zip(joints.iter().zip(weights))
                .filter(|(_, jw)| under(strongest(*jw)))
                .map(|(p, _)| *p)
                .collect()
        };
        e.head = map
            .get(Role::Head)
            .and_then(|head| Head::new(head, &skin_under(head)));
        for hand in [map.get(Role::LHand), map.get(Role::RHand)]
            .into_iter()
            .flatten()
        {
            let Some(&wrist) = rest.get(hand) else {
                continue;
            };
            let far = skin_under(hand)
                .into_iter()
                .max_by(|a, b| (a - wrist).norm().total_cmp(&(b - wrist).norm()));
            e.fingertips.extend(far.map(|f| (hand, f)));
        }
        Some(e)
    }

    /// How far `p` is inside the envelope grown by `margin` (positive inside, 0 outside).
    pub fn depth(&self, p: &Vec3, margin: Real) -> Real {
        let k = (p.y - self.y0) / SLAB;
        if !(k >= 0.0 && k < self.slabs.len() as Real) {
            return 0.0;
        }
        let s = &self.slabs[k as usize];
        let (dx, dz) = (p.x - s.centre[0], p.z - s.centre[1]);
        let r = (dx * dx + dz * dz).sqrt();
        // The sector the point is in and its neighbours (the section is sampled coarsely).
        let at = sector(dx, dz);
        let reach = (0..3)
            .map(|d| s.radius[(at + SECTORS + d - 1) % SECTORS])
            .fold(0.0, Real::max);
        if reach == 0.0 {
            return 0.0;
        }
        (reach + margin - r).max(0.0)
    }
}

/// What the clearance did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Clearance {
    /// Frames in which an arm was opened.
    pub frames_opened: usize,
    /// Largest opening (degrees).
    pub max_open_deg: Real,
}

/// World rotations and positions of `skeleton` in `pose` (the root at its rest position plus the
/// pose's translation).
pub fn forward(skeleton: &Skeleton, rest: &[Vec3], pose: &Pose) -> (Vec<UnitQuat>, Vec<Vec3>) {
    let n = skeleton.parents.len();
    let mut g: Vec<UnitQuat> = Vec::with_capacity(n);
    let mut p: Vec<Vec3> = Vec::with_capacity(n);
    for j in 0..n {
        let local = pose.local_rotations.get(j).copied().unwrap_or_default();
        match skeleton.parents[j] {
            Some(q) => {
                g.push(g[q] * local);
                p.push(p[q] + g[q] * (rest[j] - rest[q]));
            }
            None => {
                g.push(local);
                p.push(rest[j] + pose.root_translation);
            }
        }
    }
    (g, p)
}

/// One arm: upper arm, forearm and hand joints, and the hand's tip at rest.
struct Arm {
    upper: usize,
    forearm: usize,
    hand: usize,
    tip: Vec3,
}

fn arms(skeleton: &Skeleton, rest: &[Vec3], tips: &[Option<Vec3>]) -> Vec<Arm> {
    let Some(map) = RoleMap::detect(skeleton) else {
        return Vec::new();
    };
    [
        [Role::LUpperArm, Role::LForearm, Role::LHand],
        [Role::RUpperArm, Role::RForearm, Role::RHand],
    ]
    .iter()
    .filter_map(|r| {
        let [u, f, h] = r.map(|r| map.get(r));
        let (upper, forearm, hand) = (u?, f?, h?);
        // The tip: the rig's, else the wrist continued by 40% of the forearm.
        let tip = tips
            .get(hand)
            .copied()
            .flatten()
            .unwrap_or(rest[hand] + (rest[hand] - rest[forearm]) * 0.4);
        Some(Arm {
            upper,
            forearm,
            hand,
            tip,
        })
    })
    .collect()
}

/// Opens each arm of every pose of `motion` just enough to clear `envelope` by `margin` (m), with
/// the openings smoothed over `window` frames either side. `rest` and `tips` are the target rig's.
pub fn keep_arms_clear(
    motion: &mut Retargeted,
    rest: &[Vec3],
    tips: &[Option<Vec3>],
    envelope: &Envelope,
    margin: Real,
    window: usize,
) -> Clearance {
    let skeleton = motion.skeleton.clone();
    let arms = arms(&skeleton, rest, tips);
    let hips = skeleton
        .parents
        .iter()
        .position(|p| p.is_none())
        .unwrap_or(0);
    let mut report = Clearance::default();
    for arm in &arms {
        let side = if rest[arm.upper].x >= rest[hips].x {
            1.0
        } else {
            -1.0
        };
        let (need, axes): (Vec<Real>, Vec<Vec3>) = motion
            .poses
            .iter()
            .map(|pose| opening(&skeleton, rest, pose, arm, hips, side, envelope, margin))
            .unzip();
        let smooth = smooth_max(&need, window);
        for ((pose, &phi), &axis) in motion.poses.iter_mut().zip(&smooth).zip(&axes) {
            if phi > 0.0 {
                open(&skeleton, rest, pose, arm.upper, axis, phi);
                report.frames_opened += 1;
                report.max_open_deg = report.max_open_deg.max(phi.to_degrees());
            }
        }
    }
    motion.clearance = report;
    report
}

/// The smallest opening (radians, in whole degrees) that clears the arm in `pose`, and the world
/// axis (through the shoulder) it turns the upper arm about. A hand below its shoulder opens
/// sideways, about the root's forward axis, away from the midline; a hand above it (at the face)
/// swings away from the head, in the plane through the shoulder, the wrist and the head's centre.
#[allow(clippy::too_many_arguments)]
fn opening(
    skeleton: &Skeleton,
    rest: &[Vec3],
    pose: &Pose,
    arm: &Arm,
    hips: usize,
    side: Real,
    envelope: &Envelope,
    margin: Real,
) -> (Real, Vec3) {
    let (g, p) = forward(skeleton, rest, pose);
    // Into the root's rest frame, where the envelope was taken, and the head's.
    let to_rest = |x: Vec3| g[hips].inverse() * (x - p[hips]) + rest[hips];
    let head = envelope.head.as_ref().filter(|h| h.joint < g.len());
    let to_head = |h: &Head, x: Vec3| g[h.joint].inverse() * (x - p[h.joint]) + rest[h.joint];
    let tip = p[arm.hand] + g[arm.hand] * (arm.tip - rest[arm.hand]);
    let pivot = p[arm.upper];
    let local = [
        p[arm.forearm],
        p[arm.hand],
        tip,
        (p[arm.forearm] + p[arm.hand]) / 2.0,
    ]
    .map(|x| x - pivot);
    let forward_axis = g[hips] * Vec3::z();
    let sideways = forward_axis * side;
    let raised = to_rest(p[arm.hand]).y > to_rest(pivot).y;
    let axis = match head {
        Some(h) if raised => {
            let centre = p[h.joint] + g[h.joint] * (h.centre - rest[h.joint]);
            // Turning the wrist about (centre - shoulder) x (wrist - shoulder) moves it away
            // from the centre.
            let a = (centre - pivot).cross(&local[1]);
            if a.norm() > 1e-9 {
                a.normalize()
            } else {
                -sideways
            }
        }
        _ if raised => -sideways,
        _ => sideways,
    };
    let clear = |x: Vec3| {
        envelope.depth(&to_rest(x), margin) == 0.0
            && head.is_none_or(|h| !h.contains(&to_head(h, x), HEAD_MARGIN))
    };
    // The fingertip, kept off the head only (the hips' margin counts from the hand's joints).
    let finger = envelope
        .fingertips
        .iter()
        .find(|(j, _)| *j == arm.hand)
        .map(|(_, f)| p[arm.hand] + g[arm.hand] * (f - rest[arm.hand]) - pivot);
    let finger_clear =
        |x: Vec3| head.is_none_or(|h| !h.contains(&to_head(h, x), HEAD_MARGIN / 2.0));
    for deg in 0..=MAX_OPEN_DEG {
        let phi = (deg as Real).to_radians();
        let r = UnitQuat::from_scaled_axis(axis * phi);
        if local.iter().all(|&v| clear(pivot + r * v))
            && finger.is_none_or(|v| finger_clear(pivot + r * v))
        {
            return (phi, axis);
        }
    }
    ((MAX_OPEN_DEG as Real).to_radians(), axis)
}

/// Rotates the upper arm `upper` of `pose` by `angle` about the world axis `axis` (unit).
fn open(
    skeleton: &Skeleton,
    rest: &[Vec3],
    pose: &mut Pose,
    upper: usize,
    axis: Vec3,
    angle: Real,
) {
    let (g, _) = forward(skeleton, rest, pose);
    let r = UnitQuat::from_scaled_axis(axis * angle);
    let parent = skeleton.parents[upper].map_or(UnitQuat::identity(), |q| g[q]);
    pose.local_rotations[upper] = parent.inverse() * r * g[upper];
}

/// The largest value within `window` frames either side, then averaged over the same window: never
/// below the need, and without jumps.
pub fn smooth_max(need: &[Real], window: usize) -> Vec<Real> {
    let n = need.len();
    let span = |k: usize| k.saturating_sub(window)..(k + window + 1).min(n);
    let hold: Vec<Real> = (0..n)
        .map(|k| need[span(k)].iter().copied().fold(0.0, Real::max))
        .collect();
    (0..n)
        .map(|k| {
            let s = &hold[span(k)];
            let mean = s.iter().sum::<Real>() / s.len() as Real;
            // The mean can dip below this frame's need at the edge of a plateau.
            mean.max(need[k])
        })
        .collect()
}

#[cfg(test)]
mod tests;
