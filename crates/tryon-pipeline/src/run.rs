//! A whole run: the frame loop over the scene's frames, each judged by the exact referee, with
//! every stage timed; the result holds every frame's garment and pose for the exporters, and the
//! statistics written to stats.json.

use crate::metrics::{Baseline, penetration, stretch};
use crate::pipeline::{LoopState, Pipeline, run_surface};
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;
use tryon_core::frames::{BodyFrame, CoarseFrame, StepReport};
use tryon_core::math::{Real, Vec3};
use tryon_core::pose::Pose;
use tryon_core::stages::SurfaceInput;

pub use crate::timers::{StageTime, Timers};

/// One output frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameRecord {
    pub time: Real,
    pub garment: Vec<Vec3>,
    /// The body's pose (a skinned body only).
    pub pose: Option<Pose>,
    /// What the body adds after skinning in that pose (its press), as offsets of rest-mesh
    /// vertices (`BodyModel::skin_offsets_at`); only when the sink asks for them.
    pub skin_offsets: Vec<(u32, Vec3)>,
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
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Metrics {
    /// Deepest garment vertex inside the body over all frames (m).
    pub max_penetration_m: Real,
    /// The worst frame's 99th-percentile depth (m).
    pub p99_penetration_m: Real,
    /// Mean over frames of the share of garment vertices deeper than 1 mm.
    pub share_over_1mm: Real,
    /// Largest structural edge length / rest length over all frames.
    pub max_stretch: Real,
    /// Smallest structural edge length / rest length over all frames.
    pub min_stretch: Real,
    /// Largest share, over frames, of garment vertices detached from the body (torn, slid or
    /// fallen off; `crate::hold`): 0 while the garment stays on.
    pub detached_share: Real,
    /// Mean over frames of the mean structural stretch.
    pub mean_stretch: Real,
    pub non_finite_events: u32,
    pub substep_retries: u32,
    pub rollbacks: u32,
    /// Most sub-frames a frame's body motion was split into (`[scene] body_step`).
    pub max_body_parts: u32,
    /// Mean over frames of the length restoration error over compressed coarse edges,
    /// |fine path length - rest| / rest (when the scene refines).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub length_error: Option<Real>,
    /// With `[effects] body_press`: body vertices pressed out of another part per pose (mean), and
    /// the deepest overlap of two parts found before pressing (m). The GLB's body does not carry
    /// the press (its joints alone animate it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body_pressed_per_pose: Option<Real>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body_press_deepest_m: Option<Real>,
    /// Garment vertices moved out of the body when placing it on the rest pose.
    pub placement_moved: usize,
    /// Frames the referee judged (`[output] referee_every`); the figures above are over these.
    pub judged_frames: usize,
    /// Most pairs of output garment triangles (sharing no vertex) that cross each other in one
    /// frame (`crossings.rs`).
    pub cloth_intersections: usize,
    /// Smallest gap between layers of cloth over all frames: a vertex's distance to a triangle
    /// not around it, along that triangle's normal (m; 0.01 when no layers came nearer).
    pub cloth_min_gap_m: Real,
    /// Garments worn (`[[garment]]`).
    pub garments: usize,
    /// Garment vertices moved out over the layers beneath when dressing, and the farthest move (m).
    pub layer_placement_moved: usize,
    pub layer_placement_farthest_m: Real,
    /// Vertices of real garments' separate pieces (a jacket over its skirt, a patch on shorts)
    /// moved out over the pieces beneath when dressing, and the farthest move (m).
    pub piece_placement_moved: usize,
    pub piece_placement_farthest_m: Real,
    /// With contact between layers of cloth: what pulling apart the layers that crossed or
    /// touched in the starting shape did before the first step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub untangle: Option<UntangleStats>,
    /// Per `[[fold]]`, its height over the surrounding cloth at the last frame over its drawn
    /// height (P3's open problem: how far simulation drifts from the drawn shape); null where
    /// a fold could not be measured. Absent without folds.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fold_retention: Vec<Option<Real>>,
    /// The same before the simulation, as shaped (smoothing alone lowers a fold).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fold_retention_shaped: Vec<Option<Real>>,
}

/// What untangling the starting shape did (`tryon_core::stages::Untangled`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct UntangleStats {
    /// Crossing triangle pairs before and after.
    pub crossings_before: usize,
    pub crossings_after: usize,
    /// Pairs still nearer than nine tenths of the thickness after (left out as never apart).
    pub near_after: usize,
    /// Vertices moved, and the farthest move (m).
    pub moved: usize,
    pub farthest_m: Real,
}

/// What retargeting a captured clip onto the body changed (`mocap_retarget::clearance`): arms
/// opened away from the body's hips and hands swung off its head.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct RetargetStats {
    /// Clip frames, counted per arm, in which an arm was moved.
    pub arm_frames_moved: usize,
    /// The largest turn of an upper arm (degrees).
    pub max_arm_turn_deg: Real,
}

impl From<mocap_retarget::clearance::Clearance> for RetargetStats {
    fn from(c: mocap_retarget::clearance::Clearance) -> Self {
        RetargetStats {
            arm_frames_moved: c.frames_opened,
            max_arm_turn_deg: c.max_open_deg,
        }
    }
}

/// Per-frame figures (for plots and regressions).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameStats {
    pub frame: usize,
    pub max_penetration_m: Real,
    pub p99_penetration_m: Real,
    pub max_stretch: Real,
    /// Share of garment vertices detached from the body (`crate::hold`).
    pub detached_share: Real,
    /// Crossing pairs of garment triangles.
    pub cloth_intersections: usize,
    pub contacts: u32,
    pub retries: u32,
    /// Sub-frames the body moved in.
    pub body_parts: u32,
    /// Each fold's height over its drawn height (NaN where not measurable; absent without folds).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub fold_retention: Vec<Real>,
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
    /// What retargeting the clip changed (absent for motions that are not captured clips).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub retarget: Option<RetargetStats>,
    /// Only the stages that ran.
    pub stages: BTreeMap<String, StageTime>,
    pub metrics: Metrics,
    /// Wall time of the whole frame loop, s.
    pub loop_s: Real,
    /// What was mended in the input while assembling (absent when nothing was).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    pub per_frame: Vec<FrameStats>,
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
type Pending = (CoarseFrame, BodyFrame, Option<Pose>, StepReport);

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
        mut progress: impl FnMut(usize, usize),
        sink: &mut dyn FrameSink,
    ) -> RunSummary {
        let frames = frames.unwrap_or(self.frames);
        let info = self.solver.info();
        let moving = self.motion.is_some();
        let mut st = self.start();
        if moving {
            tryon_core::stages::Collider::update(&mut self.referee, &st.body_frame);
        }
        let every = self.scene.output.referee_every;
        let garment_triangles = self.output_triangles();
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
        stats.warnings.clone_from(&self.warnings);
        stats.metrics.garments = self.wear.len().max(1);
        stats.metrics.layer_placement_moved = self.layered.iter().map(|l| l.moved).sum();
        stats.metrics.layer_placement_farthest_m =
            self.layered.iter().map(|l| l.farthest).fold(0.0, Real::max);
        stats.metrics.piece_placement_moved = self.pieces.iter().map(|l| l.moved).sum();
        stats.metrics.piece_placement_farthest_m =
            self.pieces.iter().map(|l| l.farthest).fold(0.0, Real::max);
        let mut timers = Timers::default();
        sink.begin(&RunHeader {
            name: &self.scene.scene.name,
            garment_triangles: &garment_triangles,
            garment_names: &garment_names,
            triangle_garment: &triangle_garment,
            body_positions: &self.body_mesh.positions,
            body_triangles: &body_triangles,
            rig: self.body.rig().filter(|_| moving),
        });
        let pose0 = moving.then(|| st.pose.clone());
        sink.frame(&FrameRecord {
            time: 0.0,
            garment: self.output_garment().to_vec(),
            skin_offsets: self.skin_offsets(&*sink, pose0.as_ref()),
            pose: pose0,
        });
        let mut total = StepReport::default();
        let (mut stretch_sum, mut share_sum) = (0.0, 0.0);
        let (mut length_sum, mut length_frames) = (0.0, 0usize);
        let loop_start = Instant::now();
        // Pipelined: frame k's coarse step runs beside frame k-1's surface stages, so the loop
        // below records frame k-1 while frame k waits in `pending`.
        let pipelined = self.scene.scene.pipelined && refines;
        let mut pending: Option<Pending> = None;
        let last = if pipelined { frames + 1 } else { frames };
        for step in 1..=last {
            let t = self.frame_time(step);
            let (report, coarse_x, body_frame, pose, k) = if pipelined {
                let previous = pending.take();
                pending =
                    self.pipelined_step(&mut st, step, frames, previous.as_ref(), &mut timers);
                let Some((cf, bf, pose, r)) = previous else {
                    continue;
                };
                (r, cf.positions, bf, pose, step - 1)
            } else {
                // On a worker of rayon's pool, as the cloth step is (`advance_coarse`).
                let r = rayon::scope(|_| self.advance(&mut st, t, &mut timers));
                (
                    r,
                    self.cloth.positions.clone(),
                    st.body_frame.clone(),
                    moving.then(|| st.pose.clone()),
                    step,
                )
            };
            let t = self.frame_time(k);
            total.accumulate(&report);
            let output = if refines {
                &self.surface.positions
            } else {
                &coarse_x
            };
            if every > 0 && k % every == 0 {
                stats.metrics.judged_frames += 1;
                if let Some((e, n)) = timers.time("referee", || {
                    self.surface_stages
                        .iter()
                        .find_map(|s| s.length_error(&self.surface))
                }) && n > 0
                {
                    length_sum += e;
                    length_frames += 1;
                }
                let referee = &mut self.referee;
                let (pen, (smin, smax, smean), cloth) = timers.time("referee", || {
                    if moving {
                        tryon_core::stages::Collider::update(referee, &body_frame);
                    }
                    (
                        penetration(referee, output, &start_distances),
                        stretch(&info.edges, &info.rest, &coarse_x),
                        crate::crossings::judge(output, &garment_triangles),
                    )
                });
                let m = &mut stats.metrics;
                m.max_penetration_m = m.max_penetration_m.max(pen.max);
                m.p99_penetration_m = m.p99_penetration_m.max(pen.p99);
                m.max_stretch = m.max_stretch.max(smax);
                m.min_stretch = if m.judged_frames == 1 {
                    smin
                } else {
                    m.min_stretch.min(smin)
                };
                m.detached_share = m.detached_share.max(pen.detached_share);
                m.cloth_intersections = m.cloth_intersections.max(cloth.crossings);
                m.cloth_min_gap_m = if m.judged_frames == 1 {
                    cloth.min_gap
                } else {
                    m.cloth_min_gap_m.min(cloth.min_gap)
                };
                stretch_sum += smean;
                share_sum += pen.share_over_1mm;
                stats.per_frame.push(FrameStats {
                    frame: k,
                    max_penetration_m: pen.max,
                    p99_penetration_m: pen.p99,
                    max_stretch: smax,
                    detached_share: pen.detached_share,
                    cloth_intersections: cloth.crossings,
                    contacts: report.contacts,
                    retries: report.retries,
                    body_parts: report.body_parts,
                    fold_retention: (self.folds).retention(&self.cloth.positions, &fold_triangles),
                });
            }
            sink.frame(&FrameRecord {
                time: t,
                garment: output.clone(),
                skin_offsets: self.skin_offsets(&*sink, pose.as_ref()),
                pose,
            });
            timers.end_frame();
            progress(k, frames);
        }
        stats.loop_s = loop_start.elapsed().as_secs_f64();
        let judged = stats.metrics.judged_frames.max(1) as Real;
        stats.metrics.mean_stretch = stretch_sum / judged;
        stats.metrics.share_over_1mm = share_sum / judged;
        stats.metrics.non_finite_events = total.non_finite_events;
        stats.metrics.substep_retries = total.retries;
        stats.metrics.rollbacks = total.rollbacks;
        stats.metrics.max_body_parts = total.body_parts;
        if let Some(c) = self.body.corrections() {
            stats.metrics.body_pressed_per_pose = Some(c.moved as Real / c.poses.max(1) as Real);
            stats.metrics.body_press_deepest_m = Some(c.deepest);
        }
        if refines {
            stats.metrics.length_error = Some(length_sum / length_frames.max(1) as Real);
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
            garment_triangles,
            body_triangles,
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
    /// The body's skin offsets in `pose`, when the sink asks for them.
    fn skin_offsets(&self, sink: &dyn FrameSink, pose: Option<&Pose>) -> Vec<(u32, Vec3)> {
        let mut out = Vec::new();
        if let Some(p) = pose.filter(|_| sink.wants_skin_offsets()) {
            self.body.skin_offsets_at(p, &mut out);
        }
        out
    }
}
