//! The frame loop: pose the body, carry the cloth with it, update the collider, step the cloth, and
//! judge the result with the exact referee. Each stage is timed; the result holds every frame's
//! garment and pose for the exporters, and the statistics written to stats.json.

use crate::assemble::{BodyDriver, Pipeline};
use crate::metrics::{penetration, stretch};
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;
use tryon_core::frames::{BodyFrame, CoarseFrame, StepReport};
use tryon_core::math::{Mat3, Real, Vec3};
use tryon_core::pose::Pose;
use tryon_core::stages::{BodyModel, ClothSolver, Collider};

/// One output frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameRecord {
    pub time: Real,
    pub garment: Vec<Vec3>,
    /// The body's pose (a skinned body only).
    pub pose: Option<Pose>,
}

/// Time spent in one stage per frame (ms).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct StageTime {
    pub ms_mean: Real,
    pub ms_max: Real,
    #[serde(skip)]
    sum: Real,
    #[serde(skip)]
    count: usize,
}

/// Counts of the scene's meshes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Counts {
    pub coarse_vertices: usize,
    pub coarse_faces: usize,
    pub springs: usize,
    pub body_vertices: usize,
    pub body_triangles: usize,
    /// Vertices of the refined surface (when the scene refines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fine_vertices: Option<usize>,
}

/// Accuracy and robustness over the run, judged by the exact referee.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Metrics {
    /// Deepest garment vertex inside the body over all frames (m).
    pub max_penetration_m: Real,
    /// The worst frame's 99th-percentile depth (m).
    pub p99_penetration_m: Real,
    /// Mean over frames of the share of garment vertices deeper than 1 mm.
    pub share_over_1mm: Real,
    /// Largest structural edge length / rest length over all frames.
    pub max_stretch: Real,
    /// Mean over frames of the mean structural stretch.
    pub mean_stretch: Real,
    pub non_finite_events: u32,
    pub substep_retries: u32,
    pub rollbacks: u32,
    /// Mean over frames of the length restoration error over compressed coarse edges,
    /// |fine path length - rest| / rest (when the scene refines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length_error: Option<Real>,
    /// Garment vertices moved out of the body when placing it on the rest pose.
    pub placement_moved: usize,
}

/// Per-frame figures (for plots and regressions).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FrameStats {
    pub frame: usize,
    pub max_penetration_m: Real,
    pub p99_penetration_m: Real,
    pub max_stretch: Real,
    pub contacts: u32,
    pub retries: u32,
}

/// Everything stats.json holds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Stats {
    pub scene: String,
    pub frames: usize,
    pub fps: Real,
    pub integrator: String,
    pub substep_s: Real,
    pub collider: String,
    pub counts: Counts,
    /// Only the stages that ran.
    pub stages: BTreeMap<String, StageTime>,
    pub metrics: Metrics,
    /// Wall time of the whole frame loop, s.
    pub loop_s: Real,
    pub per_frame: Vec<FrameStats>,
}

/// What a run produced.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOutput {
    /// Frame 0 is the garment as placed; then one record per simulated frame.
    pub frames: Vec<FrameRecord>,
    pub garment_triangles: Vec<[u32; 3]>,
    pub body_triangles: Vec<[u32; 3]>,
    pub stats: Stats,
}

/// The root joint's rotation and position in a pose.
fn root_transform(root: usize, rest: &Vec3, pose: &Pose) -> (Mat3, Vec3) {
    let r = pose
        .local_rotations
        .get(root)
        .map_or(Mat3::identity(), |q| *q.to_rotation_matrix().matrix());
    (r, rest + pose.root_translation)
}

/// The rigid motion of the root from one frame to the next: x -> rot (x - from) + to.
struct RootDelta {
    rot: Mat3,
    from: Vec3,
    to: Vec3,
}

impl RootDelta {
    fn new(prev: (Mat3, Vec3), now: (Mat3, Vec3)) -> Self {
        RootDelta {
            rot: now.0 * prev.0.transpose(),
            from: prev.1,
            to: now.1,
        }
    }

    fn apply(&self, x: &Vec3) -> Vec3 {
        self.rot * (x - self.from) + self.to
    }
}

/// The frame loop's state between frames.
#[derive(Clone, Debug)]
pub struct LoopState {
    pub body_frame: BodyFrame,
    pub pose: Pose,
    prev_body: Vec<Vec3>,
    root: usize,
    root_rest: Vec3,
    prev_root: (Mat3, Vec3),
}

/// Wall time per stage. A stage timed in several parts within one frame (following: carry
/// before the step, record after it) counts as one: parts add up until `end_frame`.
#[derive(Debug, Default)]
pub struct Timers {
    totals: BTreeMap<&'static str, StageTime>,
    frame: BTreeMap<&'static str, Real>,
}

impl Timers {
    pub(crate) fn time<T>(&mut self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let t0 = Instant::now();
        let r = f();
        *self.frame.entry(name).or_default() += t0.elapsed().as_secs_f64() * 1e3;
        r
    }

    /// Adds another set of timers' open frame into this one (for work done on another thread).
    pub fn absorb(&mut self, other: &mut Timers) {
        for (name, ms) in std::mem::take(&mut other.frame) {
            *self.frame.entry(name).or_default() += ms;
        }
    }

    /// Closes the frame: each stage's time this frame goes into its mean and max.
    pub fn end_frame(&mut self) {
        for (name, ms) in std::mem::take(&mut self.frame) {
            let e = self.totals.entry(name).or_default();
            e.sum += ms;
            e.count += 1;
            e.ms_max = e.ms_max.max(ms);
        }
    }
}

impl Pipeline {
    /// Body vertex positions for a recorded frame (the rest mesh for a fixed body).
    pub fn body_at(&self, record: &FrameRecord) -> Vec<Vec3> {
        match (&self.driver, &record.pose) {
            (BodyDriver::Skinned { body, .. }, Some(p)) => {
                let mut out = Vec::new();
                body.skin_into(p, &mut out);
                out
            }
            _ => self.body_mesh.positions.clone(),
        }
    }

    /// The loop's state at time 0: the body posed at the motion's start.
    pub fn start(&mut self) -> LoopState {
        let mut st = LoopState {
            body_frame: BodyFrame {
                time: 0.0,
                positions: self.body_mesh.positions.clone(),
                velocities: Vec::new(),
            },
            pose: Pose::default(),
            prev_body: Vec::new(),
            root: 0,
            root_rest: Vec3::zeros(),
            prev_root: (Mat3::identity(), Vec3::zeros()),
        };
        if let BodyDriver::Skinned { body: m, .. } = &self.driver {
            st.root = m
                .skeleton
                .parents
                .iter()
                .position(|p| p.is_none())
                .unwrap_or(0);
            st.root_rest = m.joint_rest.get(st.root).copied().unwrap_or_default();
        }
        if let BodyDriver::Skinned { body, motion } = &mut self.driver {
            motion.sample(0.0, &mut st.pose);
            body.pose(&st.pose, &mut st.body_frame);
        }
        st.prev_root = root_transform(st.root, &st.root_rest, &st.pose);
        if let Some(fine) = &mut self.fine {
            let skinned = matches!(self.driver, BodyDriver::Skinned { .. });
            let mut scratch = Timers::default();
            fine.run(
                &self.coarse.frame,
                skinned.then_some(&st.body_frame),
                &mut scratch,
            );
            fine.length_error_sum = 0.0;
            fine.length_frames = 0;
        }
        st
    }

    /// The coarse part of the output frame ending at time `t`: motion, skinning, following,
    /// collider update and the cloth step (each timed into `timers`). The referee is not run here.
    pub fn advance_coarse(
        &mut self,
        st: &mut LoopState,
        t: Real,
        timers: &mut Timers,
    ) -> StepReport {
        let dt = 1.0 / self.fps;
        let settle = self.scene.scene.settle;
        let skinned = matches!(self.driver, BodyDriver::Skinned { .. });
        let LoopState {
            body_frame,
            pose,
            prev_body,
            root,
            root_rest,
            prev_root,
        } = st;
        if let BodyDriver::Skinned { body, motion } = &mut self.driver {
            prev_body.clone_from(&body_frame.positions);
            timers.time("motion", || {
                motion.sample((t - settle).max(0.0), pose);
                pose.time = t;
            });
            timers.time("skinning", || body.pose(pose, body_frame));
        }
        let c = &mut self.coarse;
        if skinned {
            if let Some(f) = &mut c.follower {
                timers.time("follow_body", || {
                    // The whole cloth rides with the root (pelvis): the cloth is simulated in the
                    // root's moving frame, so its velocities and the body's are relative to it;
                    // then P1.3.4 carries the particles near the body with their faces.
                    let now = root_transform(*root, root_rest, pose);
                    let delta = RootDelta::new(*prev_root, now);
                    for (x, v) in c
                        .frame
                        .positions
                        .iter_mut()
                        .zip(c.frame.velocities.iter_mut())
                    {
                        *x = delta.apply(x);
                        *v = delta.rot * *v;
                    }
                    body_frame.velocities.clear();
                    body_frame.velocities.extend(
                        body_frame
                            .positions
                            .iter()
                            .zip(prev_body.iter())
                            .map(|(x, x0)| (x - delta.apply(x0)) * (1.0 / dt)),
                    );
                    *prev_root = now;
                    // A frame of the wrong size cannot happen here (the body is ours).
                    let _ = f.apply(body_frame, &mut c.frame.positions);
                });
            }
            if self.stages.contains(&"collider_update") {
                timers.time("collider_update", || c.collider.update(body_frame));
            }
        }
        if skinned && let Some(b) = &mut self.bands {
            timers.time("bands", || b.update(body_frame, &mut c.sim.model.handles));
        }
        // The grab takes the particle nearest its first point once the frame reaches its time.
        if let Some(path) = &self.grab
            && let Some(&(t0, start)) = path.first()
            && t0 <= t
            && !c.frame.positions.is_empty()
        {
            let x = &c.frame.positions;
            let particle = (0..x.len())
                .min_by(|&a, &b| {
                    (x[a] - start)
                        .norm_squared()
                        .total_cmp(&(x[b] - start).norm_squared())
                })
                .unwrap_or(0);
            let at = x[particle];
            c.sim.grab(cloth_dyn::Handle {
                particle: particle as u32,
                path: path.iter().map(|(k, p)| (*k, at + (p - start))).collect(),
            });
            self.grab = None;
        }
        let report = timers.time("cloth", || {
            c.sim.step_frame(&mut c.frame, dt, c.collider.as_mut())
        });
        if !self.attachments.is_empty() {
            timers.time("attach_pieces", || {
                garment_fit::apply_attachments(
                    &self.attachments,
                    &mut c.frame.positions,
                    &mut c.frame.velocities,
                )
            });
        }
        if let Some(f) = &mut c.follower {
            timers.time("follow_body", || f.record(&c.frame.positions));
        }
        report
    }

    /// One output frame ending at time `t`: [`Pipeline::advance_coarse`], then the surface stages
    /// on its result.
    pub fn advance(&mut self, st: &mut LoopState, t: Real, timers: &mut Timers) -> StepReport {
        let report = self.advance_coarse(st, t, timers);
        let skinned = matches!(self.driver, BodyDriver::Skinned { .. });
        if let Some(fine) = &mut self.fine {
            fine.run(
                &self.coarse.frame,
                skinned.then_some(&st.body_frame),
                timers,
            );
        }
        report
    }

    /// The garment as output: the fine surface when the scene refines, else the coarse cloth.
    pub fn output_garment(&self) -> &[Vec3] {
        match &self.fine {
            Some(f) => &f.surface.positions,
            None => &self.coarse.frame.positions,
        }
    }

    /// Runs `frames` output frames (the scene's count when `None`), calling `progress(done, total)`
    /// after each.
    pub fn run(
        &mut self,
        frames: Option<usize>,
        mut progress: impl FnMut(usize, usize),
    ) -> RunOutput {
        let frames = frames.unwrap_or(self.frames);
        let dt = 1.0 / self.fps;
        let model = &self.coarse.sim.model;
        let s = &model.springs;
        let edges: Vec<[u32; 2]> = model.structural.clone().map(|k| [s.i[k], s.j[k]]).collect();
        let rest: Vec<Real> = model.structural.clone().map(|k| s.rest[k]).collect();
        let garment_triangles = match &self.fine {
            Some(f) => f.refiner.triangles.clone(),
            None => self.garment.triangulate().0,
        };
        let (body_triangles, _) = self.body_mesh.triangulate();
        let mut stats = Stats {
            scene: self.scene.scene.name.clone(),
            frames,
            fps: self.fps,
            integrator: self.coarse.sim.integrator_name().to_string(),
            substep_s: self.coarse.sim.nominal_substep(),
            collider: self.coarse.collider.name().to_string(),
            counts: Counts {
                coarse_vertices: self.garment.positions.len(),
                coarse_faces: self.garment.faces.len(),
                springs: s.len(),
                body_vertices: self.body_mesh.positions.len(),
                body_triangles: body_triangles.len(),
                fine_vertices: self.fine.as_ref().map(|f| f.refiner.fine_vertices()),
            },
            ..Stats::default()
        };
        stats.metrics.placement_moved = self.placed_moved;
        let mut timers = Timers::default();
        let mut out_frames = Vec::with_capacity(frames + 1);
        let skinned = matches!(self.driver, BodyDriver::Skinned { .. });
        let mut st = self.start();
        out_frames.push(FrameRecord {
            time: 0.0,
            garment: self.output_garment().to_vec(),
            pose: skinned.then(|| st.pose.clone()),
        });
        let mut total = StepReport::default();
        let mut stretch_sum = 0.0;
        let mut share_sum = 0.0;
        let loop_start = Instant::now();
        // Pipelined: frame k's coarse step runs beside frame k-1's surface stages, so the loop
        // below records frame k-1 while frame k waits in `pending`.
        let pipelined = self.scene.scene.pipelined && self.fine.is_some();
        let mut pending: Option<(CoarseFrame, BodyFrame, Option<Pose>, StepReport)> = None;
        let mut fine_timers = Timers::default();
        let last = if pipelined { frames + 1 } else { frames };
        for step in 1..=last {
            let t = step as Real * dt;
            let (report, coarse_x, body_frame, pose, k) = if pipelined {
                let mut fine = self.fine.take();
                let previous = pending.take();
                let (fresh, _) = rayon::join(
                    || {
                        (step <= frames).then(|| {
                            let r = self.advance_coarse(&mut st, t, &mut timers);
                            (
                                self.coarse.frame.clone(),
                                st.body_frame.clone(),
                                skinned.then(|| st.pose.clone()),
                                r,
                            )
                        })
                    },
                    || {
                        if let (Some(f), Some((cf, bf, _, _))) = (&mut fine, &previous) {
                            f.run(cf, skinned.then_some(bf), &mut fine_timers);
                        }
                    },
                );
                self.fine = fine;
                timers.absorb(&mut fine_timers);
                pending = fresh;
                let Some((cf, bf, pose, r)) = previous else {
                    continue;
                };
                (r, cf.positions, bf, pose, step - 1)
            } else {
                let r = self.advance(&mut st, t, &mut timers);
                (
                    r,
                    self.coarse.frame.positions.clone(),
                    st.body_frame.clone(),
                    skinned.then(|| st.pose.clone()),
                    step,
                )
            };
            let t = k as Real * dt;
            let body_frame = &body_frame;
            total.accumulate(&report);
            if let Some(f) = &mut self.fine {
                timers.time("referee", || f.record_length_error());
            }
            let output = match &self.fine {
                Some(f) => &f.surface.positions,
                None => &coarse_x,
            };
            let referee = &mut self.referee;
            let (pen, (smax, smean)) = timers.time("referee", || {
                if skinned {
                    referee.update(body_frame);
                }
                (
                    penetration(referee, output),
                    stretch(&edges, &rest, &coarse_x),
                )
            });
            let m = &mut stats.metrics;
            m.max_penetration_m = m.max_penetration_m.max(pen.max);
            m.p99_penetration_m = m.p99_penetration_m.max(pen.p99);
            m.max_stretch = m.max_stretch.max(smax);
            stretch_sum += smean;
            share_sum += pen.share_over_1mm;
            stats.per_frame.push(FrameStats {
                frame: k,
                max_penetration_m: pen.max,
                p99_penetration_m: pen.p99,
                max_stretch: smax,
                contacts: report.contacts,
                retries: report.retries,
            });
            out_frames.push(FrameRecord {
                time: t,
                garment: output.clone(),
                pose,
            });
            timers.end_frame();
            progress(k, frames);
        }
        stats.loop_s = loop_start.elapsed().as_secs_f64();
        stats.metrics.mean_stretch = stretch_sum / frames.max(1) as Real;
        stats.metrics.share_over_1mm = share_sum / frames.max(1) as Real;
        stats.metrics.non_finite_events = total.non_finite_events;
        stats.metrics.substep_retries = total.retries;
        stats.metrics.rollbacks = total.rollbacks;
        if let Some(f) = &self.fine {
            stats.metrics.length_error = Some(f.length_error_sum / f.length_frames.max(1) as Real);
        }
        timers.end_frame();
        for (name, mut t) in timers.totals {
            t.ms_mean = t.sum / t.count.max(1) as Real;
            stats.stages.insert(name.to_string(), t);
        }
        RunOutput {
            frames: out_frames,
            garment_triangles,
            body_triangles,
            stats,
        }
    }
}
