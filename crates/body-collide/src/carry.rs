//! The body follower as the frame loop drives it ([`Follower`]): the whole cloth rides with the
//! root joint (the cloth is simulated in the root's moving frame, so its velocities and the body's
//! are taken relative to it), then P1.3.4 carries the particles near the body with their faces.

use crate::follow::BodyFollower;
use tryon_core::frames::{BodyFrame, CoarseFrame};
use tryon_core::math::{Mat3, Real, Vec3};
use tryon_core::pose::Pose;
use tryon_core::stages::Follower;

/// The root joint's rotation and position in a pose.
pub fn root_transform(root: usize, rest: &Vec3, pose: &Pose) -> (Mat3, Vec3) {
    let r = pose
        .local_rotations
        .get(root)
        .map_or(Mat3::identity(), |q| *q.to_rotation_matrix().matrix());
    (r, rest + pose.root_translation)
}

/// The rigid motion of the root from one frame to the next: x -> rot (x - from) + to.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RootDelta {
    pub rot: Mat3,
    pub from: Vec3,
    pub to: Vec3,
}

impl RootDelta {
    pub fn new(prev: (Mat3, Vec3), now: (Mat3, Vec3)) -> Self {
        RootDelta {
            rot: now.0 * prev.0.transpose(),
            from: prev.1,
            to: now.1,
        }
    }

    pub fn apply(&self, x: &Vec3) -> Vec3 {
        self.rot * (x - self.from) + self.to
    }
}

/// The root carry's state between frames.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RootCarry {
    pub root: usize,
    pub root_rest: Vec3,
    prev_root: (Mat3, Vec3),
    prev_body: Vec<Vec3>,
}

impl RootCarry {
    /// A carry with joint `root` whose rest position is `root_rest` (see `Rig::root`).
    pub fn new(root: usize, root_rest: Vec3) -> Self {
        RootCarry {
            root,
            root_rest,
            prev_root: (Mat3::identity(), Vec3::zeros()),
            prev_body: Vec::new(),
        }
    }
}

impl Default for RootCarry {
    fn default() -> Self {
        RootCarry::new(0, Vec3::zeros())
    }
}

impl Follower for BodyFollower {
    tryon_core::whole_state!();
    fn start(&mut self, pose: &Pose, body: &BodyFrame, cloth: &[Vec3]) {
        let c = &mut self.carry;
        c.prev_root = root_transform(c.root, &c.root_rest, pose);
        c.prev_body.clone_from(&body.positions);
        self.record(cloth);
    }

    fn carry(&mut self, pose: &Pose, body: &mut BodyFrame, cloth: &mut CoarseFrame, dt: Real) {
        let c = &mut self.carry;
        let now = root_transform(c.root, &c.root_rest, pose);
        let delta = RootDelta::new(c.prev_root, now);
        for (x, v) in cloth.positions.iter_mut().zip(cloth.velocities.iter_mut()) {
            *x = delta.apply(x);
            *v = delta.rot * *v;
        }
        body.velocities.clear();
        body.velocities.extend(
            body.positions
                .iter()
                .zip(c.prev_body.iter())
                .map(|(x, x0)| (x - delta.apply(x0)) * (1.0 / dt)),
        );
        c.prev_root = now;
        c.prev_body.clone_from(&body.positions);
        // A frame of the wrong size is ignored here (and counted by the collider).
        let _ = self.apply(body, &mut cloth.positions);
    }

    fn record(&mut self, cloth: &[Vec3]) {
        BodyFollower::record(self, cloth)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::body::BodyMesh;
    use crate::follow::FollowParams;
    use tryon_core::math::UnitQuat;
    use tryon_core::shapes::icosphere;

    /// A sphere body and a follower carrying with joint 0 at the origin.
    fn follower() -> (BodyFollower, BodyFrame) {
        let mesh = icosphere(0.3, 2, Vec3::zeros());
        let frame = BodyFrame {
            time: 0.0,
            positions: mesh.positions.clone(),
            velocities: Vec::new(),
        };
        let f = BodyFollower::new(BodyMesh::new(&mesh).unwrap(), FollowParams::default())
            .with_root(0, Vec3::zeros());
        (f, frame)
    }

    #[test]
    fn a_rigidly_moved_body_carries_the_cloth_rigidly_and_its_velocity_is_relative_to_the_root() {
        let (mut f, mut body) = follower();
        let mut pose = Pose::rest(1);
        // One point on the body, one far away (followed by the root alone).
        let mut cloth =
            CoarseFrame::at_rest(vec![Vec3::new(0.3, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0)]);
        cloth.velocities[1] = Vec3::new(0.0, 1.0, 0.0);
        f.start(&pose, &body, &cloth.positions);
        let q = UnitQuat::from_axis_angle(&Vec3::y_axis(), 0.5);
        pose.local_rotations[0] = q;
        pose.root_translation = Vec3::new(0.0, 0.1, 0.0);
        for p in &mut body.positions {
            *p = q * *p + pose.root_translation;
        }
        f.carry(&pose, &mut body, &mut cloth, 0.1);
        let moved = |p: Vec3| q * p + Vec3::new(0.0, 0.1, 0.0);
        for (got, was) in cloth
            .positions
            .iter()
            .zip([Vec3::new(0.3, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0)])
        {
            assert!((got - moved(was)).norm() < 1e-12, "{got} vs {}", moved(was));
        }
        assert!((cloth.velocities[1] - q * Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
        // The body moved with the root: no velocity relative to it.
        assert_eq!(body.velocities.len(), body.positions.len());
        assert!(body.velocities.iter().all(|v| v.norm() < 1e-9));
    }

    #[test]
    fn a_body_moving_against_the_root_has_that_velocity() {
        let (mut f, mut body) = follower();
        let pose = Pose::rest(1);
        let mut cloth = CoarseFrame::at_rest(vec![Vec3::new(5.0, 0.0, 0.0)]);
        f.start(&pose, &body, &cloth.positions);
        for p in &mut body.positions {
            p.x += 0.02;
        }
        f.carry(&pose, &mut body, &mut cloth, 0.01);
        assert!(
            body.velocities
                .iter()
                .all(|v| (v - Vec3::new(2.0, 0.0, 0.0)).norm() < 1e-9)
        );
        // Far from the body and the root still: the cloth stays.
        assert_eq!(cloth.positions[0], Vec3::new(5.0, 0.0, 0.0));
    }
}
