//! A second contact-aware garment solver: Vertex Block Descent (Chen, Macklin, Yang, Yuksel and
//! Liang 2024). Each step minimises the implicit-Euler variational energy, inertia plus springs plus
//! body contact, by block coordinate descent: vertex by vertex (colour by colour, so a colour's
//! vertices are independent), one Newton step on that vertex's 3x3 block with every other vertex
//! held. Springs are the model's structural and shear springs (stiff) and its flexion springs
//! (soft, from the modelled shape, so a garment keeps its form). Body contact is an energy inside
//! the solve: each vertex near the body at the start of the step gets the body's tangent plane
//! there (and, where another part faces that one across a pinch, that part's plane too:
//! `contact.rs`), and a quadratic penalty holds it a thickness outside; friction is IPC's lagged smoothed
//! Coulomb term on the tangential motion relative to the body (static below a slip of `eps_v h`,
//! kinetic above), bounded by the penalty's normal force. The collider's projection runs after the
//! solve as a fail-safe only.

mod bending;
pub mod colour;
mod contact;
mod forces;
mod layers;
mod linalg;
mod pairs;
mod sweep;

/// Fewest vertices a thread takes at once in a colour's sweep: below this the hand-over costs more
/// than the Newton steps it shares out.
const PAR_CHUNK: usize = 32;

/// Self-contact is detected again after an iteration that held more than one in this many
/// vertices at their bounds (`layers_redetect`).
const REDETECT: usize = 25;

use crate::model::{ClothModel, Handle};
use crate::params::ClothParams;
use crate::retry::frame_with_retries;
use crate::self_contact::{SelfContacts, SelfParams};
use crate::strain::{ContactPlane, Tethers, limit_strain};
use linalg::{add_outer, solve_spd3};
use tryon_core::frames::{CoarseFrame, Contact, StepReport};
use tryon_core::math::{Mat3, Real, Vec3, is_finite};
use tryon_core::stages::{ClothInfo, ClothSolver, Collider, Probe};

/// The `vbd` solver's settings, a scene's `[cloth.vbd]` (self-contact: `with_self_contact`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct VbdParams {
    /// Longest step (s); a frame takes as many as it needs to keep under it.
    #[schemars(range(min = 1e-5, max = 0.1))]
    pub substep: Real,
    /// Descent sweeps over all vertices per step.
    #[schemars(range(min = 1, max = 1000))]
    pub iterations: u32,
    /// Stretch and shear stiffness per spring (N/m times rest length: k = this / rest).
    #[schemars(range(min = 1.0, max = 1e9))]
    pub stretch: Real,
    /// Flexion springs (P1's bending), stiffness in N/m times rest length; 0 leaves them out.
    #[serde(rename = "flexion")]
    #[schemars(range(min = 0.0, max = 1e6))]
    pub bend: Real,
    /// Bending rigidity (N m) toward the rest dihedral angles, so a modelled garment keeps its
    /// curves and a fold its side; 0 leaves it out (docs/decisions, *vbd bending*).
    #[schemars(range(min = 0.0, max = 1.0))]
    pub dihedral: Real,
    /// Body contact stiffness (N/m); it must dominate the springs a particle hangs from.
    #[schemars(range(min = 1.0, max = 1e9))]
    pub contact: Real,
    /// Slip speed below which friction sticks (m/s): IPC's eps_v.
    #[schemars(range(min = 1e-6, max = 1.0))]
    pub stick_speed: Real,
    /// Particles nearer the body than the thickness plus this get a contact plane for a step (m).
    #[schemars(range(min = 0.0, max = 0.2))]
    pub reach: Real,
    /// Swept body collision: a particle whose path crosses the body's surface inward is stopped.
    pub swept: bool,
    /// Provot's strain limit after the sweeps, 0 (off) or a ratio of rest length in [1, 2], for
    /// free-hanging sheets (docs/decisions, *vbd strain limit*).
    pub limit: Real,
    /// Passes of that limit per step.
    #[schemars(range(min = 1, max = 100))]
    pub limit_passes: u32,
}

impl Default for VbdParams {
    fn default() -> Self {
        VbdParams {
            substep: 1.0 / 120.0,
            iterations: 10,
            stretch: 5e3,
            bend: 5.0,
            dihedral: 0.0,
            contact: 1e6,
            stick_speed: 0.01,
            reach: 0.03,
            swept: true,
            limit: 0.0,
            limit_passes: 8,
        }
    }
}

/// One spring seen from one of its ends.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Arm {
    other: u32,
    rest: Real,
    k: Real,
}

/// A body contact held during one step: stay `thickness` outside the plane through `point`
/// with unit normal `normal`, which moves with `velocity`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Plane {
    point: Vec3,
    normal: Vec3,
}

/// The VBD garment solver over a [`ClothModel`].
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct VbdSim {
    pub model: ClothModel,
    pub params: ClothParams,
    pub vbd: VbdParams,
    /// Hinges toward the rest dihedral angles.
    hinges: bending::Hinges,
    /// Springs per vertex (CSR).
    offsets: Vec<u32>,
    arms: Vec<Arm>,
    /// The blocks each Newton step moves: a vertex alone, or a sliver's pair (`pairs`).
    blocks: Vec<[u32; 2]>,
    /// Per block, a pair's ring (empty for a vertex alone) and its target offset for this step.
    rings: Vec<pairs::Ring>,
    /// Soft holds: per particle, a point it is drawn to and the spring's stiffness (N/m).
    anchors: Vec<Option<(Vec3, Real)>>,
    targets: Vec<Vec3>,
    /// Blocks in colour order and each colour's range.
    order: Vec<u32>,
    colours: Vec<std::ops::Range<usize>>,
    thickness: Real,
    prev: Vec<Vec3>,
    inertial: Vec<Vec3>,
    planes: Vec<Option<Plane>>,
    /// Per particle with a contact plane, the plane of the body part facing that one across a
    /// pinch ([`Collider::probe_opposite`]): held off both, it is squeezed between them.
    opposite: Vec<Option<Plane>>,
    probes: Vec<Probe>,
    /// Per particle, its signed distance from the body at the step's start (infinite when the
    /// collider knows none): a path shorter than that cannot cross the still body.
    clear: Vec<Real>,
    /// The swept test's share of the particles: where they started, where they ended, who.
    #[serde(skip)]
    swept_sub: (Vec<Vec3>, Vec<Vec3>, Vec<u32>),
    /// The particles with a contact plane this step, and their probes.
    near: Vec<u32>,
    near_probes: Vec<Probe>,
    all: Vec<u32>,
    contacts: Vec<Contact>,
    backup: (Vec<Vec3>, Vec<Vec3>),
    tethers: Tethers,
    tethers_stale: bool,
    /// Each colour's steps (per block) before they are applied.
    dx: Vec<[Vec3; 2]>,
    /// Positions after the solve, before the fail-safe projection.
    solved: Vec<Vec3>,
    /// Per vertex, the summed stiffness of its springs (N/m).
    spring_sum: Vec<Real>,
    /// Particles the swept test stopped in this step.
    stopped: Vec<bool>,
    /// Per particle, the plane of the body surface the swept test last stopped it on: a second
    /// contact plane for the next step, so the solve holds it there with its neighbours instead
    /// of pulling it back through (`None` when it was not stopped).
    held: Vec<Option<Plane>>,
    /// The contact planes the strain limit keeps particles outside of.
    limit_planes: Vec<ContactPlane>,
    /// The cloth's contacts with itself (`with_self_contact`), and what untangling the starting
    /// shape did (`None` until the first step).
    layers: Option<SelfContacts>,
    untangled: Option<crate::self_contact::Untangled>,
}

impl VbdSim {
    /// A solver of `model` keeping `thickness` from the body.
    pub fn new(model: ClothModel, params: ClothParams, vbd: VbdParams, thickness: Real) -> Self {
        let n = model.particle_count();
        let s = &model.springs;
        let mut lists: Vec<Vec<Arm>> = vec![Vec::new(); n];
        for k in 0..s.len() {
            let (i, j, rest) = (s.i[k], s.j[k], s.rest[k] * params.rest_scale);
            let per_rest = model.spring_scale.get(k).copied().unwrap_or(1.0)
                * if model.bend.contains(&k) {
                    vbd.bend
                } else {
                    vbd.stretch
                };
            if per_rest == 0.0 {
                continue;
            }
            let k_s = per_rest / rest.max(1e-6);
            lists[i as usize].push(Arm {
                other: j,
                rest,
                k: k_s,
            });
            lists[j as usize].push(Arm {
                other: i,
                rest,
                k: k_s,
            });
        }
        let mut offsets = vec![0u32];
        let mut arms = Vec::new();
        for l in &lists {
            arms.extend_from_slice(l);
            offsets.push(arms.len() as u32);
        }
        let blocks = pairs::blocks(&offsets, &arms, &model.inv_mass);
        let rest = &model.rest_positions;
        let rings: Vec<pairs::Ring> = blocks
            .iter()
            .map(|&b| match b[1] {
                pairs::ALONE => pairs::Ring::default(),
                _ => pairs::Ring::new(&offsets, &arms, b, rest, params.rest_scale),
            })
            .collect();
        let hinges = bending::Hinges::new(rest, &model.triangles, vbd.dihedral);
        let mut neighbours = pairs::neighbours(&offsets, &arms, &blocks);
        hinges.add_neighbours(&blocks, &mut neighbours);
        // A triangle's corners are coloured apart. The retired coarse pokes coupled them (an
        // energy on a triangle's three corners); the colouring stays, as another one changes
        // every VBD result (docs/decisions, *fine pokes*).
        let stencils: Vec<[u32; 4]> = model
            .triangles
            .iter()
            .map(|t| [t[0], t[1], t[2], t[2]])
            .collect();
        bending::add_stencil_neighbours(&stencils, &blocks, &mut neighbours);
        let (order, colours) = colour::vertices(&neighbours);
        let spring_sum = lists.iter().map(|l| l.iter().map(|a| a.k).sum()).collect();
        let z = vec![Vec3::zeros(); n];
        VbdSim {
            model,
            params,
            vbd,
            hinges,
            offsets,
            arms,
            targets: vec![Vec3::zeros(); blocks.len()],
            blocks,
            rings,
            anchors: Vec::new(),
            order,
            colours,
            thickness,
            prev: z.clone(),
            inertial: z.clone(),
            planes: vec![None; n],
            opposite: vec![None; n],
            probes: Vec::new(),
            clear: vec![Real::INFINITY; n],
            swept_sub: Default::default(),
            near: Vec::new(),
            near_probes: Vec::new(),
            all: (0..n as u32).collect(),
            contacts: Vec::new(),
            backup: (z.clone(), z),
            tethers: Tethers::default(),
            tethers_stale: true,
            dx: Vec::new(),
            solved: vec![Vec3::zeros(); n],
            stopped: Vec::new(),
            spring_sum,
            held: vec![None; n],
            limit_planes: Vec::new(),
            layers: None,
            untangled: None,
        }
    }

    /// The solver with the cloth's contact with itself and between its garments (`None`: none).
    pub fn with_self_contact(mut self, contact: Option<SelfParams>) -> Self {
        let m = &self.model;
        self.layers = contact.map(|p| {
            SelfContacts::new(&m.triangles, &m.rest_positions, p)
                .with_garments(&m.garment, &m.layer)
        });
        self
    }

    /// Number of vertex colours.
    pub fn colour_count(&self) -> usize {
        self.colours.len()
    }

    /// The inertial targets and, for vertices near the body, their contact planes, for a step of
    /// `h` ending at `t1`.
    fn begin(&mut self, frame: &mut CoarseFrame, t1: Real, h: Real, collider: &mut dyn Collider) {
        let p = &self.params;
        let m = &self.model;
        let damp = (-p.velocity_damping * h).exp();
        let reach = self.thickness + self.vbd.reach;
        collider.probe_near(&frame.positions, &self.all, reach, &mut self.probes);
        for i in 0..frame.positions.len() {
            let x = frame.positions[i];
            self.prev[i] = x;
            self.clear[i] = self.probes.get(i).map_or(Real::INFINITY, |q| q.distance);
            self.planes[i] = self
                .probes
                .get(i)
                .filter(|q| q.distance < reach && q.normal != Vec3::zeros())
                .map(|q| Plane {
                    point: x - q.normal * q.distance,
                    normal: q.normal,
                });
            if m.inv_mass[i] == 0.0 {
                self.inertial[i] = x;
                continue;
            }
            let v = frame.velocities[i];
            let mut a = p.gravity;
            if p.air_drag != 0.0 {
                a -= (v - p.wind) * (p.air_drag * m.area[i] * m.inv_mass[i]);
            }
            let v = (v + a * h) * damp;
            frame.velocities[i] = v;
            self.inertial[i] = x + v * h;
            // Start from the inertial guess (the paper's simplest initialisation).
            frame.positions[i] = self.inertial[i];
        }
        for hd in &m.handles {
            let k = hd.particle as usize;
            frame.positions[k] = hd.position(t1);
            self.inertial[k] = frame.positions[k];
        }
        for (b, ring) in self.rings.iter().enumerate() {
            if !ring.ids.is_empty() {
                self.targets[b] = ring.target_or_spring(&self.prev, self.blocks[b]);
            }
        }
        let prev = std::mem::take(&mut self.prev);
        self.pinches(&prev, collider);
        self.hinges.begin(&prev);
        self.prev = prev;
    }

    /// Vertex `i`'s force and Hessian at `x`: inertia, its springs except those to `partner`,
    /// and its contact planes.
    fn gather(&self, x: &[Vec3], i: usize, partner: u32, h: Real) -> (Vec3, Mat3) {
        let w = self.model.mass[i] / (h * h);
        let xi = x[i];
        let mut f = (self.inertial[i] - xi) * w;
        // Each spring's Hessian, made positive semi-definite, is k (n n^T + t (I - n n^T)) with
        // t = max(1 - rest / l, 0): summed as an isotropic part k t and a symmetric outer part
        // k (1 - t) / l^2 d d^T (six entries), with no per-spring matrix.
        let mut iso = w;
        let mut o = [0.0; 6];
        for a in pairs::arms_of(&self.offsets, &self.arms, i) {
            if a.other == partner {
                continue;
            }
            let d = xi - x[a.other as usize];
            let l2 = d.norm_squared();
            if l2 < 1e-24 {
                continue;
            }
            let l = l2.sqrt();
            f -= d * (a.k * (l - a.rest) / l);
            let t = (1.0 - a.rest / l).max(0.0);
            iso += a.k * t;
            let s = a.k * (1.0 - t) / l2;
            add_outer(&mut o, s, &d);
        }
        self.hinges.add(i, &mut f, &mut o);
        self.add_anchor(i, xi, &mut f, &mut iso);
        let mut hess = Mat3::new(
            o[0] + iso,
            o[1],
            o[2],
            o[1],
            o[3] + iso,
            o[4],
            o[2],
            o[4],
            o[5] + iso,
        );
        // By reference: copying the three planes cost a memmove call a vertex.
        for pl in [&self.planes[i], &self.opposite[i], &self.held[i]]
            .into_iter()
            .flatten()
        {
            self.contact(pl, i, xi, h, &mut f, &mut hess);
        }
        if let Some(sc) = &self.layers {
            let kc = (self.penalty(i), self.vbd.stick_speed * h);
            sc.add(i, x, kc, &mut f, &mut hess);
        }
        (f, hess)
    }

    /// One Newton step on block `b` (a vertex, or a sliver's pair on their 6 x 6 block); returns
    /// the members' displacements (zero for a kinematic member).
    fn descend(&self, x: &[Vec3], b: usize, h: Real) -> [Vec3; 2] {
        let [i, j] = self.blocks[b];
        let free = |v: u32| v != pairs::ALONE && self.model.inv_mass[v as usize] != 0.0;
        let single = |v: u32| {
            if !free(v) {
                return Vec3::zeros();
            }
            let (f, hess) = self.gather(x, v as usize, pairs::ALONE, h);
            solve_spd3(&hess, &f)
        };
        if !(free(i) && free(j)) {
            // Alone, or a member was grabbed since the pairing: each free one by itself.
            return [single(i), single(j)];
        }
        let (iu, ju) = (i as usize, j as usize);
        let (fi, hi) = self.gather(x, iu, j, h);
        let (fj, hj) = self.gather(x, ju, i, h);
        let ring = &self.rings[b];
        let target = self.targets[b];
        pairs::pair_step(
            (x[iu], fi, hi),
            (x[ju], fj, hj),
            (target, ring.k * pairs::PAIR_STIFFEN),
        )
        .map_or([Vec3::zeros(); 2], |(a, b)| [a, b])
    }

    /// Provot's limit after the sweeps (`VbdParams::limit`), each contact particle kept on the
    /// outer side of its planes: ten sweeps leave a free-hanging sheet stretched (the drape at
    /// N = 64 1.31, at N = 128 2.87), a few passes carry the tension at once.
    fn limit(&mut self, x: &mut [Vec3]) {
        if self.vbd.limit <= 0.0 {
            return;
        }
        self.limit_planes.clear();
        for i in 0..x.len() {
            let planes = [self.planes[i], self.opposite[i], self.held[i]];
            for pl in planes.into_iter().flatten() {
                self.limit_planes.push(ContactPlane {
                    point: i as u32,
                    normal: pl.normal,
                    offset: pl.normal.dot(&pl.point) + self.thickness,
                });
            }
        }
        let (ratio, passes) = (self.vbd.limit, self.vbd.limit_passes);
        limit_strain(
            &self.model,
            ratio,
            passes,
            1.0,
            x,
            &self.limit_planes,
            None,
            None,
        );
    }

    /// The descent sweeps of one step.
    fn solve(&mut self, x: &mut [Vec3], h: Real) {
        let tethers = self.params.tethers && !self.model.handles.is_empty();
        if tethers && self.tethers_stale {
            self.tethers.compute(&self.model);
            self.tethers_stale = false;
        }
        if !self.hinges.is_empty() {
            // The sweeps start from the inertial guess, not from the step's start.
            self.hinges.refresh(x, &self.prev);
        }
        let mut dx = std::mem::take(&mut self.dx);
        for _ in 0..self.vbd.iterations.max(1) {
            let mut clamped = 0;
            for r in self.colours.clone() {
                self.sweep_colour(x, &self.order[r.clone()], h, &mut dx);
                clamped += self.apply(x, r, &dx);
            }
            if clamped > x.len() / REDETECT {
                self.layers_redetect(x);
            }
            if tethers {
                self.tethers.project(1.0, x);
                self.layers_clamp(x);
                if !self.hinges.is_empty() {
                    self.hinges.refresh(x, &self.prev);
                }
            }
        }
        self.dx = dx;
    }

    /// One step of `h` from `t0`, during which the body covers the fraction `span` of its last
    /// move; returns the particles that ended non-finite or too fast.
    fn step(
        &mut self,
        frame: &mut CoarseFrame,
        (t0, h): (Real, Real),
        span: [Real; 2],
        collider: &mut dyn Collider,
    ) -> u32 {
        self.begin(frame, t0 + h, h, collider);
        let mut x = std::mem::take(&mut frame.positions);
        self.layers_begin(&mut x);
        self.solve(&mut x, h);
        self.limit(&mut x);
        self.layers_clamp(&mut x);
        let before = self.layers.as_ref().map(|_| x.clone());
        self.fail_safe(&mut x, span, collider);
        if let Some(b) = before {
            self.layers_keep(&mut x, &b, collider);
        }
        frame.positions = x;
        let max2 = self.params.max_speed * self.params.max_speed;
        let mut bad = 0;
        for i in 0..frame.positions.len() {
            let v = (frame.positions[i] - self.prev[i]) / h;
            frame.velocities[i] = v;
            if !is_finite(&frame.positions[i]) || !(v.norm_squared() <= max2) {
                bad += 1;
            }
        }
        bad
    }
}

impl ClothSolver for VbdSim {
    tryon_core::whole_state!();
    fn untangled(&self) -> Option<crate::self_contact::Untangled> {
        self.untangled
    }
    fn boxed_clone(&self) -> Option<Box<dyn ClothSolver>> {
        Some(Box::new(self.clone()))
    }
    fn info(&self) -> ClothInfo {
        self.model
            .info("vbd", self.vbd.substep, self.arms.len() / 2)
    }

    fn initial_frame(&self) -> CoarseFrame {
        self.model.initial_frame()
    }

    fn step_frame(
        &mut self,
        frame: &mut CoarseFrame,
        dt: Real,
        collider: &mut dyn Collider,
    ) -> StepReport {
        let bad_input = self.model.sanitize(frame);
        self.layers_frame_start(&mut frame.positions, collider);
        let (longest, max_speed) = (self.vbd.substep, self.params.max_speed);
        let mut backup = std::mem::take(&mut self.backup);
        // The body is at its new shape for the whole frame (it moved at the collider's update).
        let step =
            |f: &mut CoarseFrame, t: Real, h: Real| self.step(f, (t, h), [1.0, 1.0], collider);
        let mut report =
            frame_with_retries(frame, dt, longest, max_speed, bad_input, &mut backup, step);
        self.backup = backup;
        self.layers_frame_end(&frame.positions);
        frame.contacts.clone_from(&self.contacts);
        self.elastic_forces(&frame.positions, &mut frame.elastic_force);
        report.contacts = frame.contacts.len() as u32;
        report
    }

    fn hold_handles(&mut self, first: usize, targets: &[Vec3]) {
        self.model.hold_handles(first, targets)
    }

    fn anchor(&mut self, particles: &[u32], targets: &[Vec3], stiffness: Real) {
        self.set_anchors(particles, targets, stiffness)
    }

    fn grab(&mut self, handle: Handle) {
        if self.model.take_handle(handle) {
            self.tethers_stale = true;
        }
    }

    fn release(&mut self, particle: u32) {
        if self.model.release_handle(particle) {
            self.tethers_stale = true;
        }
    }
}

#[cfg(test)]
mod layer_tests;
#[cfg(test)]
mod swept_tests;
#[cfg(test)]
mod tests;
