//! A contact-aware garment solver: extended position-based dynamics with many small substeps and
//! one constraint pass each (Macklin, Storey, Lu, Terdiman, Chentanez, Jeschke and Müller 2019,
//! "Small steps in physics simulation"). Per substep: forces move every free particle, then the
//! distance constraints of every edge and the dihedral constraints of every interior edge are
//! solved colour by colour, then the body pushes particles out and friction (static, then kinetic)
//! acts on the contact's tangential motion relative to the body, and velocities are the substep's
//! displacement. Constraints are solved in position space with a compliance, so any stiffness is
//! stable at any step, and a sliver only gets a stiff constraint, never a smaller step. Bending
//! pulls toward the rest shape's angles, so a modelled garment keeps its shape.

pub mod constraints;
pub mod lanes;
pub mod springs;

use crate::model::{ClothModel, Handle};
use crate::params::ClothParams;
use crate::retry::frame_with_retries;
use crate::strain::Tethers;
pub use constraints::hinge_move;
use constraints::{Edge, Hinge, colour, dihedral};
use lanes::{
    EdgeBatch, HingeBatch, edge_batches, hinge_batches, solve_edge_batch, solve_hinge_batch,
};
use std::collections::HashMap;
use std::ops::Range;
use tryon_core::frames::{CoarseFrame, Contact, StepReport};
use tryon_core::math::{Real, Vec3, is_finite};
use tryon_core::stages::{ClothInfo, ClothSolver, Collider};

/// The `xpbd` solver's settings, as a scene's `[cloth.xpbd]` table gives them (absent keys take
/// these defaults).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct XpbdParams {
    /// Longest substep (s); a frame takes as many as it needs to keep under it.
    #[schemars(range(min = 1e-5, max = 0.1))]
    pub substep: Real,
    /// Constraint passes per substep (Macklin et al.: many substeps of one pass converge better
    /// than few of many).
    #[schemars(range(min = 1, max = 100))]
    pub iterations: u32,
    /// Compliance of the distance constraints, per unit of rest length (m/N): 0 is inextensible.
    #[schemars(range(min = 0.0, max = 1.0))]
    pub stretch_compliance: Real,
    /// Compliance of the dihedral constraints (1/(N m)): larger bends more easily.
    #[schemars(range(min = 0.0, max = 1e9))]
    pub bend_compliance: Real,
    /// Static friction at body contacts: a contact sticks while its tangential slip is under
    /// this times its normal correction (kinetic friction is `effects.friction`).
    #[schemars(range(min = 0.0, max = 5.0))]
    pub static_friction: Real,
    /// What bends the cloth: `dihedral` (angles toward the rest shape's, at `bend_compliance`)
    /// or `springs` (the model's bend springs, P3's, each at its own stiffness `cloth.k_bend`,
    /// changed where folds are drawn).
    pub bending: XpbdBending,
}

/// How the XPBD solver bends the cloth.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum XpbdBending {
    /// A dihedral-angle constraint on every interior edge (compliance `bend_compliance`).
    #[default]
    Dihedral,
    /// The model's bend springs (P3's and Provot's), each at its own stiffness ([`springs`]).
    Springs,
}

impl Default for XpbdParams {
    fn default() -> Self {
        XpbdParams {
            substep: 1.0 / 600.0,
            iterations: 1,
            stretch_compliance: 0.0,
            bend_compliance: 1.0,
            static_friction: 0.6,
            bending: XpbdBending::Dihedral,
        }
    }
}

/// The XPBD garment solver over a [`ClothModel`] (masses, handles and topology are shared with
/// P1's solver).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct XpbdSim {
    pub model: ClothModel,
    pub params: ClothParams,
    pub xpbd: XpbdParams,
    edges: Vec<Edge>,
    edge_colours: Vec<Range<usize>>,
    hinges: Vec<Hinge>,
    hinge_colours: Vec<Range<usize>>,
    /// The same constraints eight at a time, colour by colour ([`lanes`]).
    edge_lanes: Vec<EdgeBatch>,
    hinge_lanes: Vec<HingeBatch>,
    bend_springs: Vec<springs::BendSpring>,
    prev: Vec<Vec3>,
    backup: (Vec<Vec3>, Vec<Vec3>),
    elastic: Vec<Vec3>,
    contacts: Vec<Contact>,
    tethers: Tethers,
    tethers_stale: bool,
}

/// The unique edges of `triangles` and the interior edges' hinges (the two triangles' opposite
/// vertices, in the first triangle's winding).
fn edges_and_hinges(triangles: &[[u32; 3]]) -> (Vec<[u32; 2]>, Vec<[u32; 4]>) {
    let mut first: HashMap<(u32, u32), (u32, u32, u32)> = HashMap::new();
    let mut edges = Vec::new();
    let mut hinges = Vec::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let key = (a.min(b), a.max(b));
            match first.get(&key) {
                None => {
                    first.insert(key, (a, b, c));
                    edges.push([key.0, key.1]);
                }
                Some(&(a0, b0, c0)) => hinges.push([a0, b0, c0, c]),
            }
        }
    }
    (edges, hinges)
}

impl XpbdSim {
    /// A solver of `model` with `params` (environment, friction, rest scale) and `xpbd`.
    pub fn new(model: ClothModel, params: ClothParams, xpbd: XpbdParams) -> Self {
        let x = &model.rest_positions;
        let (edge_list, all_hinges) = edges_and_hinges(&model.triangles);
        let (hinge_list, bend_springs) = match xpbd.bending {
            XpbdBending::Dihedral => (
                springs::scaled_hinges(&model, &all_hinges, false),
                Vec::new(),
            ),
            XpbdBending::Springs => (
                springs::scaled_hinges(&model, &all_hinges, true),
                springs::bend_springs(&model).0,
            ),
        };
        let refs: Vec<&[u32]> = edge_list.iter().map(|e| &e[..]).collect();
        let (order, edge_colours) = colour(&refs, x.len());
        let edges: Vec<Edge> = order
            .iter()
            .map(|&k| {
                let [i, j] = edge_list[k as usize];
                let rest = (x[i as usize] - x[j as usize]).norm() * params.rest_scale;
                Edge { i, j, rest }
            })
            .collect();
        let refs: Vec<&[u32]> = hinge_list.iter().map(|h| &h.0[..]).collect();
        let (order, hinge_colours) = colour(&refs, x.len());
        let hinges: Vec<Hinge> = order
            .iter()
            .map(|&k| {
                let (v, compliance_scale) = hinge_list[k as usize];
                let p = v.map(|i| x[i as usize]);
                let rest_angle = dihedral(p).map_or(0.0, |d| d.0);
                Hinge {
                    v,
                    rest_angle,
                    compliance_scale,
                }
            })
            .collect();
        let (edge_lanes, _) = edge_batches(&edges, &edge_colours);
        let (hinge_lanes, _) = hinge_batches(&hinges, &hinge_colours);
        let n = x.len();
        let z = vec![Vec3::zeros(); n];
        XpbdSim {
            model,
            params,
            xpbd,
            edges,
            edge_colours,
            hinges,
            hinge_colours,
            edge_lanes,
            hinge_lanes,
            bend_springs,
            prev: z.clone(),
            backup: (z.clone(), z.clone()),
            elastic: z,
            contacts: Vec::new(),
            tethers: Tethers::default(),
            tethers_stale: true,
        }
    }

    /// Number of colours of the distance and dihedral constraints.
    pub fn colours(&self) -> (usize, usize) {
        (self.edge_colours.len(), self.hinge_colours.len())
    }

    /// Forces, then the predicted positions, of one substep of length `h` ending at time `t1`.
    fn predict(&mut self, frame: &mut CoarseFrame, t1: Real, h: Real) {
        let p = &self.params;
        let m = &self.model;
        let damp = (-p.velocity_damping * h).exp();
        for i in 0..frame.positions.len() {
            self.prev[i] = frame.positions[i];
            if m.inv_mass[i] == 0.0 {
                continue;
            }
            let v = &mut frame.velocities[i];
            let mut a = p.gravity;
            if p.air_drag != 0.0 {
                a -= (*v - p.wind) * (p.air_drag * m.area[i] * m.inv_mass[i]);
            }
            *v = (*v + a * h) * damp;
            frame.positions[i] += *v * h;
        }
        for hd in &m.handles {
            frame.positions[hd.particle as usize] = hd.position(t1);
        }
    }

    /// One pass over the distance constraints, colour by colour, eight at a time; with `record`,
    /// their forces go into `elastic`.
    fn solve_edges(&mut self, x: &mut [Vec3], h: Real, record: bool) {
        let w = &self.model.inv_mass;
        let alpha = (self.xpbd.stretch_compliance / (h * h)) as f32;
        for eb in &self.edge_lanes {
            let elastic = record.then_some((&mut self.elastic[..], h));
            solve_edge_batch(x, w, eb, alpha, elastic);
        }
    }

    /// One pass over the dihedral constraints, colour by colour, eight at a time.
    fn solve_hinges(&mut self, x: &mut [Vec3], h: Real) {
        let w = &self.model.inv_mass;
        let alpha = (self.xpbd.bend_compliance / (h * h)) as f32;
        for hb in &self.hinge_lanes {
            solve_hinge_batch(x, w, hb, alpha);
        }
    }

    /// Friction on this substep's contacts: the tangential slip relative to the body is undone
    /// while under `static_friction` times the normal correction, else cut by `friction` times it.
    fn friction(&self, x: &mut [Vec3], h: Real) {
        let (mu_s, mu_k) = (self.xpbd.static_friction, self.params.friction);
        if mu_s == 0.0 && mu_k == 0.0 {
            return;
        }
        for c in &self.contacts {
            let i = c.point as usize;
            if self.model.inv_mass[i] == 0.0 {
                continue;
            }
            let rel = x[i] - self.prev[i] - c.body_velocity * h;
            let slip = rel - c.normal * rel.dot(&c.normal);
            let s = slip.norm();
            if s <= mu_s * c.depth {
                x[i] -= slip;
            } else if s > 0.0 {
                x[i] -= slip * (mu_k * c.depth / s).min(1.0);
            }
        }
    }

    /// One substep from `t0`; returns how many particles ended non-finite or too fast.
    fn substep(
        &mut self,
        frame: &mut CoarseFrame,
        t0: Real,
        h: Real,
        last: bool,
        collider: &mut dyn Collider,
    ) -> u32 {
        self.predict(frame, t0 + h, h);
        if last {
            self.elastic.iter_mut().for_each(|f| *f = Vec3::zeros());
        }
        let mut x = std::mem::take(&mut frame.positions);
        let passes = self.xpbd.iterations.max(1);
        let tethers = self.params.tethers && !self.model.handles.is_empty();
        if tethers && self.tethers_stale {
            self.tethers.compute(&self.model);
            self.tethers_stale = false;
        }
        for pass in 0..passes {
            if tethers {
                self.tethers.project(1.0, &mut x);
            }
            self.solve_edges(&mut x, h, last && pass + 1 == passes);
            self.solve_hinges(&mut x, h);
            springs::solve(&self.bend_springs, &self.model.inv_mass, &mut x, h);
        }
        self.contacts.clear();
        collider.resolve(&mut x, &mut self.contacts);
        self.friction(&mut x, h);
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

impl ClothSolver for XpbdSim {
    tryon_core::whole_state!();
    fn info(&self) -> ClothInfo {
        let elements = self.edges.len() + self.hinges.len() + self.bend_springs.len();
        self.model.info("xpbd", self.xpbd.substep, elements)
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
        let (longest, max_speed) = (self.xpbd.substep, self.params.max_speed);
        let end = frame.time + dt;
        let mut backup = std::mem::take(&mut self.backup);
        let step = |f: &mut CoarseFrame, t: Real, h: Real| {
            // The frame's last substep records the elastic forces.
            let last = t + 1.5 * h > end;
            self.substep(f, t, h, last, collider)
        };
        let mut report =
            frame_with_retries(frame, dt, longest, max_speed, bad_input, &mut backup, step);
        self.backup = backup;
        frame.elastic_force.clone_from(&self.elastic);
        frame.contacts.clone_from(&self.contacts);
        report.contacts = frame.contacts.len() as u32;
        report
    }

    fn hold_handles(&mut self, first: usize, targets: &[Vec3]) {
        self.model.hold_handles(first, targets)
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

    fn boxed_clone(&self) -> Option<Box<dyn ClothSolver>> {
        Some(Box::new(self.clone()))
    }
}

#[cfg(test)]
mod tests;
