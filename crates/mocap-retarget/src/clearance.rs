//! Arms kept clear of the body. Retargeting copies the source's bone directions, so an arm hangs at
//! the source's angle; on a body whose hips are wider than its shoulders (MakeHuman's female body
//! under CMU 10_04: shoulder joints 14.7 cm from the midline, hip surface about 18 cm) the hanging
//! hand then sits inside the hip, and a garment between them is pinched through. Here each frame's
//! arms are opened sideways about the shoulder, by the smallest angle that puts the elbow, wrist
//! and hand at least a margin outside the body's rest envelope (its cross-sections without the
//! arms), and the angles are smoothed over time so the correction never jerks.

use crate::names::{Role, RoleMap};
use crate::retarget::Retargeted;
use tryon_core::math::{Real, UnitQuat, Vec3};
use tryon_core::pose::{Pose, Skeleton};

/// How far outside the body's rest shape the arm joints are kept unless a scene says otherwise
/// (m): a wrist's or hand's own half-thickness, two layers of cloth and the collision thickness.
/// On makehuman-dress-walk 0.04 left the jacket pinched 19 mm into the hips; 0.07 clears them
/// (openings of at most 10 degrees).
pub const DEFAULT_MARGIN: Real = 0.07;
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
        Some(Envelope { y0, slabs })
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
        let body: Vec<Vec3> = points
            .iter()
            .zip(joints.iter().zip(weights))
            .filter(|(_, (j, w))| {
                let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
                !on_arm(j[k] as usize)
            })
            .map(|(p, _)| *p)
            .collect();
        Envelope::new(&body, rest[uppers[0]].y.min(rest[uppers[1]].y))
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
        let need: Vec<Real> = motion
            .poses
            .iter()
            .map(|pose| opening(&skeleton, rest, pose, arm, hips, side, envelope, margin))
            .collect();
        let smooth = smooth_max(&need, window);
        for (pose, &phi) in motion.poses.iter_mut().zip(&smooth) {
            if phi > 0.0 {
                open(&skeleton, rest, pose, arm.upper, hips, side * phi);
                report.frames_opened += 1;
                report.max_open_deg = report.max_open_deg.max(phi.to_degrees());
            }
        }
    }
    motion.clearance = report;
    report
}

/// The smallest opening (radians, in whole degrees) that clears the arm in `pose`.
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
) -> Real {
    let (g, p) = forward(skeleton, rest, pose);
    // Into the root's rest frame, where the envelope was taken.
    let to_rest = |x: Vec3| g[hips].inverse() * (x - p[hips]) + rest[hips];
    let tip = p[arm.hand] + g[arm.hand] * (arm.tip - rest[arm.hand]);
    let pts = [
        p[arm.forearm],
        p[arm.hand],
        tip,
        (p[arm.forearm] + p[arm.hand]) / 2.0,
    ];
    let pivot = to_rest(p[arm.upper]);
    let local: Vec<Vec3> = pts.iter().map(|&x| to_rest(x) - pivot).collect();
    for deg in 0..=MAX_OPEN_DEG {
        let phi = (deg as Real).to_radians();
        let r = UnitQuat::from_axis_angle(&Vec3::z_axis(), side * phi);
        if local
            .iter()
            .all(|&v| envelope.depth(&(pivot + r * v), margin) == 0.0)
        {
            return phi;
        }
    }
    (MAX_OPEN_DEG as Real).to_radians()
}

/// Rotates the upper arm `upper` of `pose` by `angle` about the root's forward axis.
fn open(
    skeleton: &Skeleton,
    rest: &[Vec3],
    pose: &mut Pose,
    upper: usize,
    hips: usize,
    angle: Real,
) {
    let (g, _) = forward(skeleton, rest, pose);
    let axis = g[hips] * Vec3::z_axis();
    let r = UnitQuat::from_axis_angle(&axis, angle);
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
