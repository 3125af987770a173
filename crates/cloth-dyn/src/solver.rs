//! The frame loop of the coarse cloth: substeps chosen for stability, handles, Provot's strain limit,
//! collision with Coulomb friction, and the guard that rejects a non-finite or exploding substep,
//! retries it at half the step, and as a last resort rolls offending particles back.

use crate::forces::{accelerations, jacobian_product, stiffness_bounds};
use crate::integrator::{Derivative, Integrator, IntegratorKind};
use crate::model::{ClothModel, Handle};
use crate::params::ClothParams;
use crate::strain::{ContactPlane, Tethers, limit_strain};
use tryon_core::frames::{CoarseFrame, Contact, StepReport};
use tryon_core::math::{Real, Vec3, is_finite};
use tryon_core::stages::{ClothInfo, ClothSolver, Collider};

/// How many times the stretch guard may halve a substep. The guard retries only substeps that
/// caused the over-stretch themselves.
pub const STRETCH_HALVINGS: u32 = 3;

/// Rejected substeps allowed per frame before offending particles are rolled back instead.
const MAX_RETRIES_PER_FRAME: u32 = 64;

/// A cloth simulation: the model, its parameters, an integrator and scratch memory. The state lives in
/// the caller's [`CoarseFrame`].
#[derive(serde::Serialize, serde::Deserialize)]
pub struct ClothSim {
    pub model: ClothModel,
    pub params: ClothParams,
    /// Left out of a checkpoint: the integrators keep nothing from one step to the next (their
    /// buffers are scratch), so the restored solver keeps the one it was built with.
    #[serde(skip, default = "placeholder_integrator")]
    integrator: Box<dyn Integrator>,
    /// Substep the stability bound allows (s).
    stable_substep: Real,
    force: Vec<Vec3>,
    elastic: Vec<Vec3>,
    backup_x: Vec<Vec3>,
    backup_v: Vec<Vec3>,
    pre_limit: Vec<Vec3>,
    contacts: Vec<Contact>,
    more_contacts: Vec<Contact>,
    planes: Vec<ContactPlane>,
    tethers: Tethers,
    tethers_stale: bool,
    stamp: Vec<bool>,
    /// Mass of each particle, 0 where pinned or handled (for implicit integrators).
    free_mass: Vec<Real>,
}

impl std::fmt::Debug for ClothSim {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClothSim")
            .field("particles", &self.model.particle_count())
            .field("springs", &self.model.springs.len())
            .field("integrator", &self.integrator.name())
            .field("stable_substep", &self.stable_substep)
            .finish()
    }
}

/// The force evaluation handed to the integrator.
struct Rhs<'a> {
    model: &'a ClothModel,
    params: &'a ClothParams,
    force: &'a mut Vec<Vec3>,
    elastic: &'a mut Vec<Vec3>,
    record: bool,
    free_mass: &'a [Real],
}

impl Derivative for Rhs<'_> {
    fn accelerations(&mut self, x: &[Vec3], v: &[Vec3], a: &mut [Vec3], first: bool) {
        let elastic = if first && self.record {
            Some(self.elastic.as_mut_slice())
        } else {
            None
        };
        accelerations(self.model, self.params, x, v, self.force, elastic, a);
    }

    fn jacobian_product(
        &mut self,
        x: &[Vec3],
        _v: &[Vec3],
        w: &[Vec3],
        cx: Real,
        cv: Real,
        out: &mut [Vec3],
    ) {
        jacobian_product(self.model, self.params, x, w, cx, cv, self.force, out);
    }

    fn masses(&self) -> Option<&[Real]> {
        Some(self.free_mass)
    }
}

impl ClothSim {
    /// A simulation of `model` with one of the built-in integrators.
    pub fn new(model: ClothModel, params: ClothParams, kind: IntegratorKind) -> Self {
        Self::with_integrator(model, params, kind.make())
    }

    /// A simulation of `model` with any integrator.
    pub fn with_integrator(
        model: ClothModel,
        params: ClothParams,
        integrator: Box<dyn Integrator>,
    ) -> Self {
        let n = model.particle_count();
        let (omega, damp) = stiffness_bounds(&model);
        let bound = 0.9 * integrator.stability_limit() / (omega + damp).max(1e-12);
        let stable_substep = if params.auto_substep {
            params.max_substep.min(bound)
        } else {
            params.max_substep
        };
        let z = vec![Vec3::zeros(); n];
        let free_mass = (0..n)
            .map(|i| {
                if model.inv_mass[i] > 0.0 {
                    model.mass[i]
                } else {
                    0.0
                }
            })
            .collect();
        ClothSim {
            model,
            params,
            integrator,
            stable_substep,
            force: z.clone(),
            elastic: z.clone(),
            backup_x: z.clone(),
            backup_v: z.clone(),
            pre_limit: z,
            contacts: Vec::new(),
            more_contacts: Vec::new(),
            planes: Vec::new(),
            tethers: Tethers::default(),
            tethers_stale: true,
            stamp: Vec::new(),
            free_mass,
        }
    }

    /// Hands particle `handle.particle` to a scripted path from now on (a user grabbing the cloth):
    /// it stops responding to forces, and tethers are recomputed.
    pub fn grab(&mut self, handle: Handle) {
        let p = handle.particle as usize;
        if self.model.take_handle(handle) {
            self.free_mass[p] = 0.0;
            self.tethers_stale = true;
        }
    }

    /// Lets go of a particle [`ClothSim::grab`] took: forces move it again from where it is.
    pub fn release(&mut self, particle: u32) {
        if self.model.release_handle(particle) {
            self.free_mass[particle as usize] = self.model.mass[particle as usize];
            self.tethers_stale = true;
        }
    }

    /// The substep used when nothing goes wrong (s).
    pub fn nominal_substep(&self) -> Real {
        self.stable_substep
    }

    /// Name of the integrator.
    pub fn integrator_name(&self) -> &'static str {
        self.integrator.name()
    }

    /// The rest state, with handles at their path start.
    pub fn initial_frame(&self) -> CoarseFrame {
        self.model.initial_frame()
    }

    /// One substep from absolute time `t`. Returns (non-finite particles, exploding particles).
    /// With `settle_first`, the strain limit first runs on the starting positions alone (their
    /// velocities untouched), so that only violations this substep makes become velocity.
    fn substep(
        &mut self,
        frame: &mut CoarseFrame,
        t: Real,
        h: Real,
        record: bool,
        settle_first: bool,
        collider: &mut dyn Collider,
    ) -> (u32, u32) {
        let (x, v) = (&mut frame.positions, &mut frame.velocities);
        for hd in &self.model.handles {
            x[hd.particle as usize] = hd.position(t);
            v[hd.particle as usize] = hd.velocity(t);
        }
        if settle_first && let Some(ratio) = self.params.max_strain {
            let p = &self.params;
            let tethers = (p.tethers && !self.model.handles.is_empty() && !self.tethers_stale)
                .then_some(&self.tethers);
            limit_strain(
                &self.model,
                ratio,
                p.strain_iterations,
                p.strain_relaxation,
                x,
                &[],
                tethers,
                p.min_bend_ratio,
            );
            self.more_contacts.clear();
            collider.resolve(x, &mut self.more_contacts);
        }
        let mut rhs = Rhs {
            model: &self.model,
            params: &self.params,
            force: &mut self.force,
            elastic: &mut self.elastic,
            record,
            free_mass: &self.free_mass,
        };
        self.integrator.step(&mut rhs, x, v, h);
        for hd in &self.model.handles {
            x[hd.particle as usize] = hd.position(t + h);
        }
        self.contacts.clear();
        collider.resolve(x, &mut self.contacts);
        if let Some(ratio) = self.params.max_strain {
            self.planes.clear();
            self.planes
                .extend(self.contacts.iter().map(|c| ContactPlane {
                    point: c.point,
                    normal: c.normal,
                    offset: c.normal.dot(&x[c.point as usize]),
                }));
            self.pre_limit.copy_from_slice(x);
            let p = &self.params;
            let tethers = if p.tethers && !self.model.handles.is_empty() {
                if self.tethers_stale {
                    self.tethers.compute(&self.model);
                    self.tethers_stale = false;
                }
                Some(&self.tethers)
            } else {
                None
            };
            limit_strain(
                &self.model,
                ratio,
                p.strain_iterations,
                p.strain_relaxation,
                x,
                &self.planes,
                tethers,
                p.min_bend_ratio,
            );
            // The limit's corrections become velocity (as in position-based dynamics), capped at a
            // quarter of the explosion speed so a teleport (a body jumping) is not turned into one.
            let inv_h = 1.0 / h;
            let cap = 0.25 * self.params.max_speed;
            for i in 0..x.len() {
                let dv = (x[i] - self.pre_limit[i]) * inv_h;
                let n = dv.norm();
                v[i] += if n > cap { dv * (cap / n) } else { dv };
            }
            // The limit may have pulled particles that were not in contact into the body.
            self.more_contacts.clear();
            collider.resolve(x, &mut self.more_contacts);
            merge_contacts(
                &mut self.contacts,
                &self.more_contacts,
                &mut self.stamp,
                x.len(),
            );
        }
        let mu = self.params.friction;
        for c in &self.contacts {
            let p = c.point as usize;
            if self.model.inv_mass[p] == 0.0 {
                continue;
            }
            v[p] = contact_velocity(v[p], c.normal, c.body_velocity, mu);
        }
        for hd in &self.model.handles {
            x[hd.particle as usize] = hd.position(t + h);
        }
        let max2 = self.params.max_speed * self.params.max_speed;
        let (mut nonfinite, mut fast) = (0, 0);
        for i in 0..x.len() {
            if !is_finite(&x[i]) || !is_finite(&v[i]) {
                nonfinite += 1;
            } else if v[i].norm_squared() > max2 {
                fast += 1;
            }
        }
        (nonfinite, fast)
    }

    /// Puts any non-finite particle of an incoming frame back at rest. Returns how many.
    fn sanitize(&self, frame: &mut CoarseFrame) -> u32 {
        self.model.sanitize(frame)
    }
}

/// Adds the contacts of `more` to `base`, keeping one contact (the later) per point. `stamp` is
/// scratch with one slot per point.
fn merge_contacts(base: &mut Vec<Contact>, more: &[Contact], stamp: &mut Vec<bool>, points: usize) {
    if more.is_empty() {
        return;
    }
    stamp.clear();
    stamp.resize(points, false);
    for c in more {
        stamp[c.point as usize] = true;
    }
    base.retain(|c| !stamp[c.point as usize]);
    base.extend_from_slice(more);
}

/// Velocity after a contact: the inward normal part (relative to the body) is removed and the
/// tangential part loses up to `mu` times that much (Coulomb friction).
pub fn contact_velocity(v: Vec3, normal: Vec3, body_velocity: Vec3, mu: Real) -> Vec3 {
    let vr = v - body_velocity;
    let vn = vr.dot(&normal);
    if vn >= 0.0 {
        return v;
    }
    let vt = vr - normal * vn;
    let vt_len = vt.norm();
    let scale = if vt_len > 0.0 {
        (1.0 - mu * (-vn) / vt_len).max(0.0)
    } else {
        0.0
    };
    body_velocity + vt * scale
}

/// What a decoded [`ClothSim`] holds until its built integrator is put back.
fn placeholder_integrator() -> Box<dyn Integrator> {
    IntegratorKind::SymplecticEuler.make()
}

impl ClothSolver for ClothSim {
    fn save_state(&self) -> Option<Vec<u8>> {
        Some(tryon_core::state::encode(self))
    }
    fn restore_state(&mut self, state: &[u8]) -> Result<(), tryon_core::state::StateError> {
        let mut restored: ClothSim = tryon_core::state::decode(state)?;
        std::mem::swap(&mut restored.integrator, &mut self.integrator);
        *self = restored;
        Ok(())
    }
    fn info(&self) -> ClothInfo {
        let springs = self.model.springs.len();
        self.model
            .info(self.integrator_name(), self.nominal_substep(), springs)
    }

    fn initial_frame(&self) -> CoarseFrame {
        ClothSim::initial_frame(self)
    }

    fn hold_handles(&mut self, first: usize, targets: &[Vec3]) {
        self.model.hold_handles(first, targets)
    }

    fn grab(&mut self, handle: Handle) {
        ClothSim::grab(self, handle)
    }

    fn release(&mut self, particle: u32) {
        ClothSim::release(self, particle)
    }

    fn step_frame(
        &mut self,
        frame: &mut CoarseFrame,
        dt: Real,
        collider: &mut dyn Collider,
    ) -> StepReport {
        let mut report = StepReport::default();
        let bad_input = self.sanitize(frame);
        report.rollbacks += bad_input;
        report.non_finite_events += bad_input;
        if !(dt.is_finite() && dt > 0.0) {
            return report;
        }
        let n_sub = (dt / self.stable_substep).ceil().max(1.0);
        let h_base = dt / n_sub;
        let (mut t, mut h, mut level, mut good) = (0.0, h_base, 0u32, 0u32);
        report.min_substep = h_base;
        let end = dt * (1.0 - 1e-12);
        while t < end {
            let h_try = h.min(dt - t);
            self.backup_x.copy_from_slice(&frame.positions);
            self.backup_v.copy_from_slice(&frame.velocities);
            let last = t + h_try >= end;
            // A retried substep is shorter, so the strain limit's correction of what the passes
            // left over from before it would become a larger velocity (corrections / step): at a
            // quarter step, a kick that made the drape bounce on its sphere. Settle those first.
            let settle = level > 0;
            let (nonfinite, fast) =
                self.substep(frame, frame.time + t, h_try, last, settle, collider);
            report.non_finite_events += nonfinite;
            let give_up =
                level >= self.params.max_halvings || report.retries >= MAX_RETRIES_PER_FRAME;
            // Only a substep that itself caused the over-stretch is retried: stretch that was there
            // before it (a body that jumped, a handle yanked) does not shrink with the step.
            let overstretched = nonfinite + fast == 0
                && level < STRETCH_HALVINGS
                && report.retries < MAX_RETRIES_PER_FRAME
                && self.params.stretch_guard.is_some_and(|r| {
                    self.overstretched(&frame.positions, r)
                        && !self.overstretched(&self.backup_x, r)
                });
            let ok = nonfinite + fast == 0;
            if overstretched || !(ok || give_up) {
                frame.positions.copy_from_slice(&self.backup_x);
                frame.velocities.copy_from_slice(&self.backup_v);
                report.retries += 1;
                h = h_try * 0.5;
                level += 1;
                good = 0;
            } else {
                if !ok {
                    // Even the smallest step failed: roll the offending particles back and carry on
                    // at the nominal step, so a persistent failure cannot stall the frame.
                    report.rollbacks += self.roll_back(frame);
                    (h, level, good) = (h_base, 0, 0);
                }
                t += h_try;
                report.substeps += 1;
                report.min_substep = report.min_substep.min(h_try);
                if level > 0 {
                    good += 1;
                    if good >= 4 {
                        h = (h * 2.0).min(h_base);
                        level -= 1;
                        good = 0;
                    }
                }
            }
        }
        frame.time += dt;
        frame.elastic_force.clone_from(&self.elastic);
        frame.contacts.clone_from(&self.contacts);
        report.contacts = frame.contacts.len() as u32;
        report
    }
}

impl ClothSim {
    /// True when some structural edge is longer than `ratio` times its rest length.
    fn overstretched(&self, x: &[Vec3], ratio: Real) -> bool {
        let s = &self.model.springs;
        self.model.structural.clone().any(|k| {
            let (i, j) = (s.i[k] as usize, s.j[k] as usize);
            (x[i] - x[j]).norm_squared() > (ratio * s.rest[k]).powi(2)
        })
    }

    /// Restores every non-finite or too-fast particle to its state before the substep, at rest.
    fn roll_back(&self, frame: &mut CoarseFrame) -> u32 {
        let max2 = self.params.max_speed * self.params.max_speed;
        let mut count = 0;
        for i in 0..frame.positions.len() {
            let (x, v) = (&frame.positions[i], &frame.velocities[i]);
            if !is_finite(x) || !is_finite(v) || v.norm_squared() > max2 {
                frame.positions[i] = self.backup_x[i];
                frame.velocities[i] = Vec3::zeros();
                count += 1;
            }
        }
        count
    }
}
