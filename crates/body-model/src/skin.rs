//! Linear blend skinning: up to four joint influences per vertex, and a skinned body that turns a
//! pose into a deformed body frame (positions, and velocities by finite difference).

use crate::press::{Press, Pressed};
use rayon::prelude::*;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Mat3, Real, Vec3};
use tryon_core::pose::{Pose, Skeleton};
use tryon_core::stages::{BodyCorrections, BodyModel, Rig};

/// Skinning weights: per vertex four (joint, weight) pairs; unused slots have weight 0; weights sum to 1.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SkinWeights {
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[Real; 4]>,
}

impl SkinWeights {
    /// Merges repeated joints, keeps the strongest four influences and normalises them to sum 1.
    /// A vertex with no positive influence is bound to joint 0.
    pub fn from_influences(infl: &[Vec<(usize, Real)>]) -> Self {
        let mut out = SkinWeights::default();
        for list in infl {
            let mut merged: Vec<(usize, Real)> = Vec::new();
            for &(j, w) in list {
                if !(w > 0.0) {
                    continue;
                }
                match merged.iter_mut().find(|e| e.0 == j) {
                    Some(e) => e.1 += w,
                    None => merged.push((j, w)),
                }
            }
            merged.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            merged.truncate(4);
            let sum: Real = merged.iter().map(|e| e.1).sum();
            let mut joints = [0u16; 4];
            let mut weights = [0.0; 4];
            if sum > 0.0 {
                for (k, &(j, w)) in merged.iter().enumerate() {
                    joints[k] = j as u16;
                    weights[k] = w / sum;
                }
            } else {
                weights[0] = 1.0;
            }
            out.joints.push(joints);
            out.weights.push(weights);
        }
        out
    }

    pub fn len(&self) -> usize {
        self.joints.len()
    }

    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }
}

/// Global rotation and position of every joint for `pose` (rotations relative to the rest pose,
/// which has identity orientations).
pub fn joint_transforms(
    skeleton: &Skeleton,
    joint_rest: &[Vec3],
    pose: &Pose,
) -> (Vec<Mat3>, Vec<Vec3>) {
    let n = skeleton.parents.len();
    let mut rot = Vec::with_capacity(n);
    let mut pos = Vec::with_capacity(n);
    for j in 0..n {
        let local = pose
            .local_rotations
            .get(j)
            .map_or(Mat3::identity(), |q| *q.to_rotation_matrix().matrix());
        match skeleton.parents[j] {
            Some(p) => {
                let r: Mat3 = rot[p] * local;
                let x: Vec3 = pos[p] + rot[p] * skeleton.rest_offsets[j];
                rot.push(r);
                pos.push(x);
            }
            None => {
                rot.push(local);
                pos.push(joint_rest[j] + pose.root_translation);
            }
        }
    }
    (rot, pos)
}

/// A body deformed by linear blend skinning.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SkinnedBody {
    pub rest_positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub skeleton: Skeleton,
    pub joint_rest: Vec<Vec3>,
    pub skin: SkinWeights,
    /// Parts pressed apart after skinning (none: plain linear blend skinning).
    pub press: Option<Press>,
    /// What pressing did, summed over the poses so far.
    pub pressed: Pressed,
    /// Poses the press ran on.
    pub pressed_poses: usize,
    last: Option<(Real, Vec<Vec3>)>,
    /// The shape `shape_next` made, with its pose and what the press did there: `pose` and
    /// `shape_next` reuse it for any pose with the same joints.
    next: Option<(Pose, Vec<Vec3>, Option<Pressed>)>,
}

impl SkinnedBody {
    /// A skinned body; `skin` must have one entry per rest position.
    pub fn new(
        rest_positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
        skeleton: Skeleton,
        joint_rest: Vec<Vec3>,
        skin: SkinWeights,
    ) -> Self {
        SkinnedBody {
            rest_positions,
            triangles,
            skeleton,
            joint_rest,
            skin,
            press: None,
            pressed: Pressed::default(),
            pressed_poses: 0,
            last: None,
            next: None,
        }
    }

    /// Skins the rest positions into `out` for `pose`.
    pub fn skin_into(&self, pose: &Pose, out: &mut Vec<Vec3>) {
        let (rot, pos) = joint_transforms(&self.skeleton, &self.joint_rest, pose);
        // Each joint's skinning transform x -> R (x - rest) + p, as R x + t.
        let t: Vec<Vec3> = (0..rot.len())
            .map(|j| pos[j] - rot[j] * self.joint_rest[j])
            .collect();
        out.clear();
        // Each vertex on its own, in parallel (collected in order: the same on any thread count).
        out.par_extend(self.rest_positions.par_iter().enumerate().map(|(i, x)| {
            let (js, ws) = (&self.skin.joints[i], &self.skin.weights[i]);
            let mut acc = Vec3::zeros();
            for k in 0..4 {
                if ws[k] != 0.0 {
                    let j = js[k] as usize;
                    acc += (rot[j] * x + t[j]) * ws[k];
                }
            }
            acc
        }));
    }
}

/// Whether two poses give the same shape (the same root and joint rotations; the time aside).
fn same_joints(a: &Pose, b: &Pose) -> bool {
    a.root_translation == b.root_translation && a.local_rotations == b.local_rotations
}

impl SkinnedBody {
    /// The body in `pose`, skinned and pressed, and what the press did.
    fn shape_pressed(&self, pose: &Pose, out: &mut Vec<Vec3>) -> Option<Pressed> {
        self.skin_into(pose, out);
        self.press.as_ref().map(|p| p.apply(out, &self.triangles))
    }
}

impl BodyModel for SkinnedBody {
    tryon_core::whole_state!();
    fn pose(&mut self, pose: &Pose, out: &mut BodyFrame) {
        out.time = pose.time;
        let pressed = match &self.next {
            Some((p, x, r)) if same_joints(p, pose) => {
                out.positions.clone_from(x);
                *r
            }
            _ => self.shape_pressed(pose, &mut out.positions),
        };
        if let Some(r) = pressed {
            self.pressed.moved += r.moved;
            self.pressed.deepest = self.pressed.deepest.max(r.deepest);
            self.pressed_poses += 1;
        }
        out.velocities.clear();
        if let Some((t0, x0)) = &self.last {
            let dt = pose.time - t0;
            if dt > 0.0 && x0.len() == out.positions.len() {
                out.velocities
                    .extend(out.positions.iter().zip(x0).map(|(a, b)| (a - b) / dt));
            }
        }
        match &mut self.last {
            Some((t, x)) => {
                *t = pose.time;
                x.clone_from(&out.positions);
            }
            None => self.last = Some((pose.time, out.positions.clone())),
        }
    }
    fn shape_at(&self, pose: &Pose, out: &mut Vec<Vec3>) {
        self.shape_pressed(pose, out);
    }
    fn shape_next(&mut self, pose: &Pose, out: &mut Vec<Vec3>) {
        // A body holding still (a settle, a still clip, a drape) is not skinned and pressed
        // again: the last shape is the shape.
        let r = match &self.next {
            Some((p, x, r)) if same_joints(p, pose) => {
                out.clone_from(x);
                *r
            }
            _ => self.shape_pressed(pose, out),
        };
        let mut kept = self.next.take().map(|(_, x, _)| x).unwrap_or_default();
        kept.clone_from(out);
        self.next = Some((pose.clone(), kept, r));
    }
    /// The press's moves in `pose`, carried back through each vertex's blended joint rotation to
    /// the rest mesh: skinning the rest mesh plus these offsets gives the pressed body exactly
    /// (linear blend skinning is linear in the rest position).
    fn skin_offsets_at(&self, pose: &Pose, out: &mut Vec<(u32, Vec3)>) {
        out.clear();
        let Some(press) = &self.press else { return };
        let mut x = Vec::new();
        self.skin_into(pose, &mut x);
        let plain = x.clone();
        press.apply(&mut x, &self.triangles);
        let (rot, _) = joint_transforms(&self.skeleton, &self.joint_rest, pose);
        for (i, (a, b)) in x.iter().zip(&plain).enumerate() {
            if a == b {
                continue;
            }
            let (js, ws) = (&self.skin.joints[i], &self.skin.weights[i]);
            let blend: Mat3 = (0..4)
                .filter(|&k| ws[k] != 0.0)
                .map(|k| rot[js[k] as usize] * ws[k])
                .sum();
            if let Some(inv) = blend.try_inverse() {
                let d = inv * (a - b);
                if d.iter().all(|c| c.is_finite()) {
                    out.push((i as u32, d));
                }
            }
        }
    }
    fn rig(&self) -> Option<Rig<'_>> {
        Some(Rig {
            rest_positions: &self.rest_positions,
            skeleton: &self.skeleton,
            joint_rest: &self.joint_rest,
            joints: &self.skin.joints,
            weights: &self.skin.weights,
        })
    }
    fn corrections(&self) -> Option<BodyCorrections> {
        self.press.as_ref().map(|_| BodyCorrections {
            poses: self.pressed_poses,
            moved: self.pressed.moved,
            deepest: self.pressed.deepest,
        })
    }
}
