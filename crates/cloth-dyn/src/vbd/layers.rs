//! VBD's self-contact (`crate::self_contact`): detection at each step's start, the contact energy
//! in each vertex's Newton step, and every move of the step kept within the vertices' bounds, so
//! the cloth does not pass through itself.

use super::VbdSim;
use tryon_core::math::{Real, Vec3};

/// Farthest a step's detection looks (m), however fast the cloth moves: a vertex then moves at
/// most the bound's share of this in one step.
const MAX_REACH: Real = 0.02;

impl VbdSim {
    /// Finds the step's self-contacts at its start (`prev`) and brings the first guess `x` within
    /// the bounds. Each vertex looks far enough for its guessed move to stay unclamped where
    /// nothing is near (between the settings' reach and [`MAX_REACH`]): settled cloth looks a few
    /// millimetres, falling cloth centimetres.
    pub(super) fn layers_begin(&mut self, x: &mut [Vec3]) {
        let Some(mut sc) = self.layers.take() else {
            return;
        };
        let p = sc.params;
        let top = MAX_REACH.max(p.reach);
        let reach: Vec<Real> = x
            .iter()
            .zip(&self.prev)
            .map(|(a, b)| (1.05 * (a - b).norm() / p.share).clamp(p.reach, top))
            .collect();
        sc.detect(&self.prev, &reach, |v| self.penalty(v));
        let inv_mass = &self.model.inv_mass;
        sc.clamp_all(x, |i| inv_mass[i] == 0.0);
        self.layers = Some(sc);
    }

    /// Every free vertex of `x` brought back within its bound (after a pass that moves many at
    /// once: the tethers, the strain limit).
    pub(super) fn layers_clamp(&self, x: &mut [Vec3]) {
        if let Some(sc) = &self.layers {
            let inv_mass = &self.model.inv_mass;
            sc.clamp_all(x, |i| inv_mass[i] == 0.0);
        }
    }
}
