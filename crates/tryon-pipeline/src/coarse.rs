//! The coarse loop: per output frame, move the body, carry the cloth with it (P1 3.4), give the
//! collider the new shape, step the cloth, and record the cloth relative to the body again.

use body_collide::BodyFollower;
use cloth_dyn::ClothSim;
use tryon_core::frames::{BodyFrame, CoarseFrame, StepReport};
use tryon_core::math::Real;
use tryon_core::stages::{ClothSolver, Collider};

/// Coarse cloth dynamics against a (possibly moving) body.
pub struct CoarseLoop {
    pub sim: ClothSim,
    pub collider: Box<dyn Collider>,
    /// Body following; `None` when the scene turns it off.
    pub follower: Option<BodyFollower>,
    pub frame: CoarseFrame,
}

impl std::fmt::Debug for CoarseLoop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CoarseLoop")
            .field("sim", &self.sim)
            .field("collider", &self.collider.name())
            .field("follow", &self.follower.is_some())
            .finish()
    }
}

impl CoarseLoop {
    /// A loop starting from the simulation's rest frame; the cloth is recorded against the body.
    pub fn new(sim: ClothSim, collider: Box<dyn Collider>, follower: Option<BodyFollower>) -> Self {
        let frame = sim.initial_frame();
        let mut l = CoarseLoop {
            sim,
            collider,
            follower,
            frame,
        };
        if let Some(f) = &mut l.follower {
            f.record(&l.frame.positions);
        }
        l
    }

    /// One output frame of length `dt`; `body` is the body's new shape, if it moved.
    pub fn advance(&mut self, body: Option<&BodyFrame>, dt: Real) -> StepReport {
        if let Some(b) = body {
            if let Some(f) = &mut self.follower {
                // A frame of the wrong size is ignored here and counted by the collider.
                let _ = f.apply(b, &mut self.frame.positions);
            }
            self.collider.update(b);
        }
        let report = self
            .sim
            .step_frame(&mut self.frame, dt, self.collider.as_mut());
        if let Some(f) = &mut self.follower {
            f.record(&self.frame.positions);
        }
        report
    }
}
