//! A whole run: the frame loop over the scene's frames, each judged by the exact referee, with
//! every stage timed; the result holds every frame's garment and pose for the exporters, and the
//! statistics written to stats.json.

use crate::metrics::{Baseline, StretchCounts};
use crate::pipeline::{LoopState, Pipeline, run_surface};
use serde::{Deserialize, Serialize};
use std::time::Instant;
use tryon_core::frames::{BodyFrame, CoarseFrame, StepReport};
use tryon_core::math::{Real, Vec3};
use tryon_core::pose::Pose;
use tryon_core::stages::SurfaceInput;

pub use crate::stats::{Counts, FrameStats, Metrics, RetargetStats, Stats, UntangleStats};
pub use crate::timers::{StageTime, Timers};

/// One output frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    pub time: Real,
    pub garment: Vec<Vec3>,
    /// The body's pose (a skinned body only).
    pub pose: Option<Pose>,
    /// What the body adds after skinning in that pose (its press), as offsets of rest-mesh
    /// vertices (`BodyModel::skin_offsets_at`); only when the sink asks for them.
    pub skin_offsets: Vec<(u32, Vec3)>,
    /// The body's positions in that frame, only when the sink asks for them (`wants_body`).
    pub body: Vec<Vec3>,
    /// The coarse cloth's positions when the output is a refined surface and the sink asks for
    /// them (`wants_coarse`); empty otherwise.
    #[serde(default)]
    pub coarse: Vec<Vec3>,
    /// Each garment vertex's depth in the body at the last judged frame
    /// ([`tryon_io::depth_code`]), when the sink asks for them (`wants_depth`) and the referee
    /// judges; empty otherwise.
    #[serde(default)]
    pub depth: Vec<u8>,
}

/// What a run's sinks learn before the first frame: what stays the same over the run.
#[derive(Clone, Copy, Debug)]
pub struct RunHeader<'a> {
    pub name: &'a str,
    pub garment_triangles: &'a [[u32; 3]],
    /// The garments' names, and the garment of each triangle of `garment_triangles`.
    pub garment_names: &'a [String],
    pub triangle_garment: &'a [u16],
    /// The body's rest positions and triangles.
    pub body_positions: &'a [Vec3],
    pub body_triangles: &'a [[u32; 3]],
    /// The body's rig when it moves (every frame then carries its pose).
    pub rig: Option<tryon_core::stages::Rig<'a>>,
    /// Output frames a second.
    pub fps: Real,
    /// The coarse cloth's triangles when the output is a refined surface (empty when the output
    /// is the coarse cloth itself).
    pub coarse_triangles: &'a [[u32; 3]],
}

/// Where a run's frames go as they are made (an exporter streaming them to files, or memory).
/// Writing may fail; a sink keeps its first error for whoever finishes it, and the run goes on.
pub trait FrameSink {
    /// Called once, before the first frame.
    fn begin(&mut self, _header: &RunHeader<'_>) {}
    /// Frame 0 is the garment as placed; then one record per simulated frame.
    fn frame(&mut self, record: &FrameRecord);
    /// Whether records should carry the body's skin offsets (they cost a second skinning).
    fn wants_skin_offsets(&self) -> bool {
        false
    }
    /// Whether records should carry the body's positions (a picture of every frame needs them).
    fn wants_body(&self) -> bool {
        false
    }
    /// Whether records should carry the coarse cloth under a refined output surface.
    fn wants_coarse(&self) -> bool {
        false
    }
    /// Whether records should carry the garment's depths in the body.
    fn wants_depth(&self) -> bool {
        false
    }
    /// The referee's figures of a judged frame, after its record.
    fn frame_stats(&mut self, _stats: &FrameStats) {}
    /// What the sink has taken so far, written out and described for a checkpoint; `None` when
    /// it cannot go on from a checkpoint.
    fn save_state(&mut self) -> Option<Vec<u8>> {
        None
    }
}

/// Keeps every frame in memory.
impl FrameSink for Vec<FrameRecord> {
    fn frame(&mut self, record: &FrameRecord) {
        self.push(record.clone());
    }
}

/// What a run produced, beside the frames its sink took.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunSummary {
    pub garment_triangles: Vec<[u32; 3]>,
    pub body_triangles: Vec<[u32; 3]>,
    pub stats: Stats,
}

/// What a run produced, every frame kept in memory.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOutput {
    /// Frame 0 is the garment as placed; then one record per simulated frame.
    pub frames: Vec<FrameRecord>,
    pub garment_triangles: Vec<[u32; 3]>,
    pub body_triangles: Vec<[u32; 3]>,
    pub stats: Stats,
}

/// One frame's coarse result waiting for its surface stages (the pipelined loop).
pub type Pending = (CoarseFrame, BodyFrame, Option<Pose>, StepReport);

/// The frame loop's state between output frames: what a checkpoint keeps beside the stages'.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RunState {
    pub loop_state: LoopState,
    /// The loop's next step (1 at the start).
    pub next: usize,
    pub total: StepReport,
    /// Sums over judged frames of the mean stretch and the share over 1 mm.
    pub sums: [Real; 2],
    /// Sums of the length restoration figures.
    pub length: crate::stats::LengthSums,
    /// Every judged frame's edge stretches, counted (`p99_stretch`).
    pub stretches: StretchCounts,
    /// Kept in a self-describing form: stats.json leaves out empty fields, which a compact
    /// binary form cannot.
    #[serde(with = "crate::stats::self_described")]
    pub stats: Stats,
    /// Stage times so far (filled when the state is saved).
    pub timers: crate::timers::SavedTimers,
    /// With the pipelined loop: the coarse frame made ahead of the last one recorded.
    pub pending: Option<Pending>,
    /// Wall time of the loop before this session (s).
    pub loop_s: Real,
    /// The output's depths in the body at the last judged frame ([`FrameRecord::depth`]); not
    /// kept by a checkpoint (the next judged frame makes them again).
    #[serde(skip)]
    pub depth: Vec<u8>,
}

/// What the loop needs that stays the same over a run (made again when a run resumes).
#[derive(Debug)]
pub struct RunContext {
    pub frames: usize,
    pub(crate) info: tryon_core::stages::ClothInfo,
    pub(crate) moving: bool,
    /// The referee judges every this many frames (`referee_every` times the stride that holds it
    /// to `referee_share`; 0: never) ...
    every: usize,
    /// ... and the last frame too, when the stride skips frames (so a short run is judged).
    last_judged: bool,
    pub garment_triangles: Vec<[u32; 3]>,
    pub garment_names: Vec<String>,
    pub triangle_garment: Vec<u16>,
    pub body_triangles: Vec<[u32; 3]>,
    /// The coarse cloth's triangles under a refined output (empty without refinement).
    pub coarse_triangles: Vec<[u32; 3]>,
    pub(crate) fold_triangles: Vec<[u32; 3]>,
    pub(crate) start_distances: Baseline,
    pub(crate) refines: bool,
    pipelined: bool,
}

/// Called after each output frame is handed to the sink, with the frame's number: where a run
/// writes its checkpoints.
pub type AfterFrame<'a> = &'a mut dyn FnMut(&Pipeline, &RunState, &mut dyn FrameSink, usize);

impl Pipeline {
    /// Runs `frames` output frames (the scene's count when `None`), calling `progress(done, total)`
    /// after each, and keeps every frame in memory.
    pub fn run(&mut self, frames: Option<usize>, progress: impl FnMut(usize, usize)) -> RunOutput {
        let mut kept: Vec<FrameRecord> = Vec::new();
        let s = self.run_into(frames, progress, &mut kept);
        RunOutput {
            frames: kept,
            garment_triangles: s.garment_triangles,
            body_triangles: s.body_triangles,
            stats: s.stats,
        }
    }

    /// Runs `frames` output frames (the scene's count when `None`), handing each to `sink` as it
    /// is made and calling `progress(done, total)` after each.
    pub fn run_into(
        &mut self,
        frames: Option<usize>,
        progress: impl FnMut(usize, usize),
        sink: &mut dyn FrameSink,
    ) -> RunSummary {
        let (ctx, state) = self.prepare(frames);
        self.begin_sink(&ctx, &state, sink);
        self.run_from(ctx, state, progress, sink, &mut |_, _, _, _| {})
    }

    /// The loop's context and its state before the first frame: the pipeline started (as
    /// [`Pipeline::start`]), the exact referee on the body, the starting distances measured.
    pub fn prepare(&mut self, frames: Option<usize>) -> (RunContext, RunState) {
        let frames = frames.unwrap_or(self.frames);
        let info = self.solver.info();
        let moving = self.motion.is_some();
        let st = self.start();
        if moving {
            tryon_core::stages::Collider::update(&mut self.referee, &st.body_frame);
        }
        let every = self.scene.output.referee_every;
        let garment_triangles = self.output_triangles();
        let stride = crate::budget::referee_stride(
            &self.estimate,
            match self.surface_stages.is_empty() {
                true => self.cloth.positions.len(),
                false => self.surface.positions.len(),
            },
            (self.body_mesh.positions.len(), self.body_mesh.faces.len()),
            self.scene.output.referee_share,
        );
        // The folds are measured on the coarse cloth.
        let fold_triangles = match self.folds.folds.is_empty() {
            true => Vec::new(),
            false => self.garment.triangulate().0,
        };
        let start_distances = if every > 0 {
            let garment = if self.surface_stages.is_empty() {
                &self.cloth.positions
            } else {
                &self.surface.positions
            };
            let d = crate::metrics::distances(&mut self.referee, garment);
            Baseline::new(d, &garment_triangles, garment)
        } else {
            Baseline::default()
        };
        let (garment_names, triangle_garment) = self.output_garments(&garment_triangles);
        let (body_triangles, _) = self.body_mesh.triangulate();
        let refines = !self.surface_stages.is_empty();
        let mut stats = Stats {
            scene: self.scene.scene.name.clone(),
            frames,
            fps: self.fps,
            integrator: info.method.to_string(),
            substep_s: info.nominal_substep,
            collider: self
                .collider
                .as_ref()
                .map_or("none", |c| c.name())
                .to_string(),
            retarget: self.retarget,
            counts: Counts {
                coarse_vertices: self.garment.positions.len(),
                coarse_faces: self.garment.faces.len(),
                springs: info.springs,
                body_vertices: self.body_mesh.positions.len(),
                body_triangles: body_triangles.len(),
                fine_vertices: refines.then_some(self.surface.positions.len()),
            },
            ..Stats::default()
        };
        stats.metrics.placement_moved = self.placed_moved;
        stats.metrics.judged_every = every * stride;
        stats.warnings.clone_from(&self.warnings);
        stats.metrics.garments = self.wear.len().max(1);
        stats.metrics.layer_placement_moved = self.layered.iter().map(|l| l.moved).sum();
        stats.metrics.layer_placement_farthest_m =
            self.layered.iter().map(|l| l.farthest).fold(0.0, Real::max);
        stats.metrics.piece_placement_moved = self.pieces.iter().map(|l| l.moved).sum();
        stats.metrics.piece_placement_farthest_m =
            self.pieces.iter().map(|l| l.farthest).fold(0.0, Real::max);
        let ctx = RunContext {
            frames,
            info,
            moving,
            every: every * stride,
            last_judged: stride > 1,
            garment_triangles,
            garment_names,
            triangle_garment,
            body_triangles,
            coarse_triangles: match refines {
                true => self.garment.triangulate().0,
                false => Vec::new(),
            },
            fold_triangles,
            start_distances,
            refines,
            pipelined: self.scene.scene.pipelined && refines,
        };
        let state = RunState {
            loop_state: st,
            next: 1,
            total: StepReport::default(),
            sums: [0.0; 2],
            length: Default::default(),
            stretches: StretchCounts::default(),
            stats,
            timers: Vec::new(),
            pending: None,
            loop_s: 0.0,
            depth: Vec::new(),
        };
        (ctx, state)
    }

    /// The sink's header of the run `ctx` describes.
    pub fn header<'a>(&'a self, ctx: &'a RunContext) -> RunHeader<'a> {
        RunHeader {
            name: &self.scene.scene.name,
            garment_triangles: &ctx.garment_triangles,
            garment_names: &ctx.garment_names,
            triangle_garment: &ctx.triangle_garment,
            body_positions: &self.body_mesh.positions,
            body_triangles: &ctx.body_triangles,
            rig: self.body.rig().filter(|_| ctx.moving),
            fps: self.fps,
            coarse_triangles: &ctx.coarse_triangles,
        }
    }

    /// Starts `sink` on the run: its header, then frame 0 (the garment as placed).
    pub fn begin_sink(&self, ctx: &RunContext, state: &RunState, sink: &mut dyn FrameSink) {
        sink.begin(&self.header(ctx));
        let pose0 = ctx.moving.then(|| state.loop_state.pose.clone());
        sink.frame(&FrameRecord {
            time: 0.0,
            garment: self.output_garment().to_vec(),
            skin_offsets: self.skin_offsets(&*sink, pose0.as_ref()),
            body: self.body_for(&*sink, pose0.as_ref()),
            coarse: self.coarse_for(&*sink, ctx, &self.cloth.positions),
            // Not judged yet (placing the garment cleared the body).
            depth: Vec::new(),
            pose: pose0,
        });
    }

    /// Runs the loop from `state` to the run's last frame, handing each frame to `sink` and
    /// then to `after`, and gathers the run's statistics.
    pub fn run_from(
        &mut self,
        ctx: RunContext,
        mut state: RunState,
        mut progress: impl FnMut(usize, usize),
        sink: &mut dyn FrameSink,
        after: AfterFrame<'_>,
    ) -> RunSummary {
        let frames = ctx.frames;
        let mut timers = Timers::restored(&state.timers, &self.stages());
        let loop_start = Instant::now();
        // Pipelined: frame k's coarse step runs beside frame k-1's surface stages, so the loop
        // below records frame k-1 while frame k waits in `pending`.
        let last = if ctx.pipelined { frames + 1 } else { frames };
        while state.next <= last {
            let step = state.next;
            state.next += 1;
            let t = self.frame_time(step);
            let (report, coarse_x, body_frame, pose, k) = if ctx.pipelined {
                let previous = state.pending.take();
                let st = &mut state.loop_state;
                state.pending =
                    self.pipelined_step(st, step, frames, previous.as_ref(), &mut timers);
                let Some((cf, bf, pose, r)) = previous else {
                    continue;
                };
                (r, cf.positions, bf, pose, step - 1)
            } else {
                // On a worker of rayon's pool, as the cloth step is (`advance_coarse`).
                let st = &mut state.loop_state;
                let r = rayon::scope(|_| self.advance(st, t, &mut timers));
                (
                    r,
                    self.cloth.positions.clone(),
                    st.body_frame.clone(),
                    ctx.moving.then(|| st.pose.clone()),
                    step,
                )
            };
            state.total.accumulate(&report);
            let due = k % ctx.every.max(1) == 0 || (ctx.last_judged && k == frames);
            if ctx.every > 0 && due {
                self.judge(
                    &ctx,
                    &mut state,
                    (k, &report, &coarse_x, &body_frame),
                    &mut timers,
                );
            }
            let output = if ctx.refines {
                &self.surface.positions
            } else {
                &coarse_x
            };
            sink.frame(&FrameRecord {
                time: self.frame_time(k),
                garment: output.clone(),
                skin_offsets: self.skin_offsets(&*sink, pose.as_ref()),
                body: self.body_for(&*sink, pose.as_ref()),
                coarse: self.coarse_for(&*sink, &ctx, &coarse_x),
                depth: match sink.wants_depth() {
                    true => state.depth.clone(),
                    false => Vec::new(),
                },
                pose,
            });
            if let Some(f) = state.stats.per_frame.last().filter(|f| f.frame == k) {
                sink.frame_stats(f);
            }
            timers.end_frame();
            if k < frames {
                state.timers = timers.saved();
                let elapsed = state.loop_s;
                state.loop_s += loop_start.elapsed().as_secs_f64();
                after(self, &state, sink, k);
                state.loop_s = elapsed;
            }
            progress(k, frames);
        }
        state.loop_s += loop_start.elapsed().as_secs_f64();
        self.conclude(&ctx, state, timers)
    }

    /// The run's statistics once the last frame is made.
    fn conclude(&mut self, ctx: &RunContext, state: RunState, timers: Timers) -> RunSummary {
        let mut stats = state.stats;
        stats.loop_s = state.loop_s;
        let judged = stats.metrics.judged_frames.max(1) as Real;
        stats.metrics.mean_stretch = state.sums[0] / judged;
        stats.metrics.p99_stretch = state.stretches.quantile(0.99);
        stats.metrics.share_over_1mm = state.sums[1] / judged;
        let total = state.total;
        stats.metrics.non_finite_events = total.non_finite_events;
        stats.metrics.substep_retries = total.retries;
        stats.metrics.rollbacks = total.rollbacks;
        stats.metrics.max_body_parts = total.body_parts;
        if let Some(c) = self.body.corrections() {
            stats.metrics.body_pressed_per_pose = Some(c.moved as Real / c.poses.max(1) as Real);
            stats.metrics.body_press_deepest_m = Some(c.deepest);
        }
        if ctx.refines {
            state.length.fill(&mut stats.metrics);
        }
        stats.metrics.untangle = self.solver.untangled().map(|u| UntangleStats {
            crossings_before: u.crossings_before,
            crossings_after: u.crossings_after,
            near_after: u.near_after,
            moved: u.moved,
            farthest_m: u.farthest,
        });
        if !self.folds.folds.is_empty() {
            let (tris, _) = self.garment.triangulate();
            let finite = |r: Real| r.is_finite().then_some(r);
            let m = &mut stats.metrics;
            m.fold_retention = (self
                .folds
                .retention(&self.cloth.positions, &tris)
                .into_iter())
            .map(finite)
            .collect();
            m.fold_retention_shaped = (self.folds.shaped.iter().zip(&self.folds.folds))
                .map(|(h, f)| h.map(|h| fold::fold_retention(h, f.drawn)))
                .collect();
        }
        stats.stages = timers.finish();
        RunSummary {
            garment_triangles: ctx.garment_triangles.clone(),
            body_triangles: ctx.body_triangles.clone(),
            stats,
        }
    }

    /// One step of the pipelined loop: frame `step`'s coarse part (while `step <= frames`) on this
    /// thread, beside the surface stages of the `previous` frame on another. Returns frame `step`'s
    /// coarse result.
    fn pipelined_step(
        &mut self,
        st: &mut LoopState,
        step: usize,
        frames: usize,
        previous: Option<&Pending>,
        timers: &mut Timers,
    ) -> Option<Pending> {
        let t = self.frame_time(step);
        let moving = self.motion.is_some();
        let mut stages = std::mem::take(&mut self.surface_stages);
        let mut surface = std::mem::take(&mut self.surface);
        let mut fine_timers = Timers::default();
        let (fresh, _) = rayon::join(
            || {
                (step <= frames).then(|| {
                    let r = self.advance_coarse(st, t, timers);
                    (
                        self.cloth.clone(),
                        st.body_frame.clone(),
                        moving.then(|| st.pose.clone()),
                        r,
                    )
                })
            },
            || {
                if let Some((cf, bf, _, _)) = previous {
                    let input = SurfaceInput {
                        coarse: cf,
                        body: moving.then_some(bf),
                    };
                    run_surface(&mut stages, &input, &mut surface, &mut fine_timers);
                }
            },
        );
        self.surface_stages = stages;
        self.surface = surface;
        timers.absorb(&mut fine_timers);
        fresh
    }
}

impl Pipeline {
    /// The body's positions in `pose` (or at rest), when the sink asks for them.
    fn body_for(&self, sink: &dyn FrameSink, pose: Option<&Pose>) -> Vec<Vec3> {
        match sink.wants_body() {
            true => self.body_at(pose),
            false => Vec::new(),
        }
    }

    /// The coarse cloth's positions `x`, when the output is refined and the sink asks for them.
    fn coarse_for(&self, sink: &dyn FrameSink, ctx: &RunContext, x: &[Vec3]) -> Vec<Vec3> {
        match sink.wants_coarse() && ctx.refines {
            true => x.to_vec(),
            false => Vec::new(),
        }
    }

    /// The body's skin offsets in `pose`, when the sink asks for them.
    fn skin_offsets(&self, sink: &dyn FrameSink, pose: Option<&Pose>) -> Vec<(u32, Vec3)> {
        let mut out = Vec::new();
        if let Some(p) = pose.filter(|_| sink.wants_skin_offsets()) {
            self.body.skin_offsets_at(p, &mut out);
        }
        out
    }
}
