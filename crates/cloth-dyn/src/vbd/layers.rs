//! VBD's self-contact (`crate::self_contact`): detection at each step's start, the contact energy
//! in each vertex's Newton step, and every move of the step kept within the vertices' bounds, so
//! the cloth does not pass through itself.

use super::VbdSim;
use tryon_core::math::{Real, Vec3};
use tryon_core::stages::Collider;

/// Passes of untangling at the start.
const UNTANGLE_PASSES: u32 = 30;

/// Farthest a step's detection looks (m), however fast the cloth moves: a vertex then moves at
/// most the bound's share of this in one step.
const MAX_REACH: Real = 0.02;

impl VbdSim {
    /// At a frame's start: before the first frame, the starting shape untangled
    /// (`layers_untangle`); after, the pairs that moves between frames (the body following's
    /// carry) closed or crossed since the last frame's end opened again
    /// (`SelfContacts::carry_apart`).
    pub(super) fn layers_frame_start(&mut self, x: &mut [Vec3], collider: &mut dyn Collider) {
        if self.layers.is_some() && self.untangled.is_none() {
            self.layers_untangle(x, collider);
        }
        let depth = match self.layers.as_ref() {
            Some(sc) if sc.last_end.len() == x.len() => body_depth(x, collider),
            _ => return,
        };
        let inv_mass = &self.model.inv_mass;
        if let Some(sc) = self.layers.as_mut() {
            let from = std::mem::take(&mut sc.last_end);
            sc.carry_apart(x, (&from, &depth), |i| inv_mass[i] == 0.0);
        }
    }

    /// Records the frame's end shape `x` (no pair crossing), from which the next frame's start
    /// (after the body following's carry) is judged.
    pub(super) fn layers_frame_end(&mut self, x: &[Vec3]) {
        if let Some(sc) = self.layers.as_mut() {
            sc.last_end.clear();
            sc.last_end.extend_from_slice(x);
        }
    }

    /// Before the first step: layers crossing or touching in the starting shape `x` pulled
    /// apart toward the thickness, the outer one outward along the body's normal, no vertex
    /// farther than two thicknesses (`SelfContacts::untangle`); that shape is then the one whose
    /// touching pairs are left out and whose near pairs keep their distance (`set_rest`). The
    /// elegant suit's 95 crossing pairs fall to 6; the casual suit's 30, between 2-3 mm
    /// triangles at the front of the waist, stay.
    fn layers_untangle(&mut self, x: &mut [Vec3], collider: &mut dyn Collider) {
        let Some(mut sc) = self.layers.take() else {
            return;
        };
        let mut probes = Vec::new();
        collider.probe(x, &self.all, &mut probes);
        let inv_mass = &self.model.inv_mass;
        let gap = sc.params.thickness;
        let report = sc.untangle(x, &probes, (gap, UNTANGLE_PASSES), |i| inv_mass[i] == 0.0);
        sc.set_rest(x);
        self.untangled = Some(report);
        self.layers = Some(sc);
    }

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

    /// Detection again from `x`, where a sweep held some vertex at its bound (Chen et al.'s
    /// offset geometric contact redoes detection as vertices reach their bounds): each vertex
    /// may then move its bound again. Layers in contact slide past each other, and an inner
    /// layer pushed by a limb pushes the outer one, as far as the iterations allow, not only a
    /// share of the gap in a step.
    pub(super) fn layers_redetect(&mut self, x: &[Vec3]) {
        let Some(mut sc) = self.layers.take() else {
            return;
        };
        let reach = std::mem::take(&mut sc.reach);
        sc.detect(x, &reach, |v| self.penalty(v));
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

impl VbdSim {
    /// After the body's fail-safe moved `x` from `before`: layers it pushed into the layer over
    /// them opened again (`SelfContacts::keep_apart`).
    pub(super) fn layers_keep(&self, x: &mut [Vec3], before: &[Vec3], collider: &mut dyn Collider) {
        if let Some(sc) = &self.layers {
            let depth = body_depth(x, collider);
            let inv_mass = &self.model.inv_mass;
            sc.keep_apart(x, (before, &depth), |i| inv_mass[i] == 0.0);
        }
    }
}

/// Every vertex's signed distance from the body at `x` (what tells the outer of two layers).
fn body_depth(x: &[Vec3], collider: &mut dyn Collider) -> Vec<Real> {
    let all: Vec<u32> = (0..x.len() as u32).collect();
    let mut probes = Vec::new();
    collider.probe(x, &all, &mut probes);
    probes.iter().map(|p| p.distance).collect()
}
