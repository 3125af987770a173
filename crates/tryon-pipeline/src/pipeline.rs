//! The assembled pipeline and the one frame loop every caller drives (the CLI, the drape fixture,
//! the tradeoff sweeps, the benches and the tests): pose the body, carry the cloth with it, update
//! the collider, hold the bands, step the cloth, place the attached pieces, then run the surface
//! stages. Each stage is an object behind a tryon-core trait; a stage that is off is not there.

use crate::scene::Scene;
use crate::timers::Timers;
use body_collide::{Bands, ExactCollider};
use garment_fit::Attachment;
use tryon_core::frames::{BodyFrame, CoarseFrame, FineSurface, StepReport};
use tryon_core::interact::Grab;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::pose::Pose;
use tryon_core::stages::{
    BodyModel, Clock, ClothSolver, Collider, Follower, MotionSource, NoCollider, SurfaceInput,
    SurfaceStage, Untimed,
};

pub use tryon_scene::BODY_STEP;
/// Most sub-frames a frame is split into for a fast body.
pub const MAX_BODY_PARTS: usize = 8;

/// Where a long preparation reports how far it is: one line of text at a time.
pub type Progress<'a> = &'a (dyn Fn(&str) + Sync);

/// How a pipeline is built beyond its scene.
#[derive(Clone, Copy)]
pub struct Options<'a> {
    /// Told how far a long preparation is (putting a kimono on takes tens of seconds).
    pub progress: Progress<'a>,
    /// What the run may take, checked before the costly stages are built.
    pub limits: crate::budget::Limits,
    /// Frames the run will make when not the scene's own (the command line's `--frames`).
    pub frames: Option<usize>,
}

impl std::fmt::Debug for Options<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Options")
            .field("limits", &self.limits)
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

impl Default for Options<'_> {
    fn default() -> Self {
        Options {
            progress: &|_| {},
            limits: crate::budget::Limits::default(),
            frames: None,
        }
    }
}

/// A scene ready to run: the stage objects and the state they share between frames.
pub struct Pipeline {
    pub scene: Scene,
    /// The body in its rest pose.
    pub body_mesh: PolyMesh,
    /// The body model (a skinned body, or a fixed mesh).
    pub body: Box<dyn BodyModel>,
    /// The motion posing the body; `None` when the body holds still (it is then never re-posed).
    pub motion: Option<Box<dyn MotionSource>>,
    /// What retargeting a captured clip changed (`None` for other motions).
    pub retarget: Option<crate::run::RetargetStats>,
    /// Body following (P1.3.4, with the root carry); only with a moving body.
    pub follower: Option<Box<dyn Follower>>,
    /// The cloth's body collider; `None` when the scene turns body collision off.
    pub collider: Option<Box<dyn Collider>>,
    /// Elastic bands bound to the body (waistbands, collars, cuffs), driving the solver's handles.
    pub bands: Option<Bands>,
    /// Vertices of small separate pieces (pockets, patches) placed on the piece beneath.
    pub attachments: Vec<Attachment>,
    pub solver: Box<dyn ClothSolver>,
    /// The coarse cloth's state.
    pub cloth: CoarseFrame,
    /// The surface stages (P1 section 4) in order; empty when the scene does not refine.
    pub surface_stages: Vec<Box<dyn SurfaceStage>>,
    /// The detailed surface the stages write.
    pub surface: FineSurface,
    /// The exact referee judging penetration (always the body's true surface, no skin).
    pub referee: ExactCollider,
    /// The garment as placed on the rest pose (after clearing the body).
    pub garment: PolyMesh,
    /// Garment vertices moved out of the body when placing it.
    pub placed_moved: usize,
    /// What was mended in the input while assembling (a welded OBJ), for the user to read.
    pub warnings: Vec<String>,
    /// What the run was estimated to take before it was built.
    pub estimate: crate::budget::Estimate,
    /// Each garment's vertices in `garment`, layer and material (one entry per garment).
    pub wear: Vec<cloth_dyn::wear::GarmentWear>,
    /// What wearing each garment over the lower layers moved (one per garment).
    pub layered: Vec<garment_fit::LayerPlacement>,
    /// What wearing each garment's separate pieces over each other moved (one per garment).
    pub pieces: Vec<garment_fit::LayerPlacement>,
    pub frames: usize,
    pub fps: Real,
    /// A grab still to happen (`[garment] grab`).
    pub grab: Option<Grab>,
    /// Scratch: the body's shape at the end of the frame being stepped.
    pub end_shape: Vec<Vec3>,
    /// The folds drawn on the garment (`[[fold]]`), to measure after the run.
    pub folds: crate::folding::Folds,
}

impl std::fmt::Debug for Pipeline {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pipeline")
            .field("scene", &self.scene.scene.name)
            .field("stages", &self.stages())
            .field("frames", &self.frames)
            .finish()
    }
}

/// The frame loop's state between frames.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct LoopState {
    pub body_frame: BodyFrame,
    pub pose: Pose,
}

/// Runs the surface stages in order on `surface`.
pub fn run_surface(
    stages: &mut [Box<dyn SurfaceStage>],
    input: &SurfaceInput<'_>,
    surface: &mut FineSurface,
    clock: &mut dyn Clock,
) {
    for s in stages {
        s.run(input, surface, clock);
    }
}

impl Pipeline {
    /// The per-frame stages that will run, in order, as the stage objects name them.
    pub fn stages(&self) -> Vec<&'static str> {
        let moving = self.motion.is_some();
        let mut names = Vec::new();
        if moving {
            names.extend(["motion", "skinning"]);
        }
        if self.grab.is_some() {
            names.push("grab");
        }
        if moving && self.follower.is_some() {
            names.push("follow_body");
        }
        if moving && self.collider.is_some() {
            names.push("collider_update");
        }
        if moving && self.bands.is_some() {
            names.push("bands");
        }
        names.push("cloth");
        if !self.attachments.is_empty() {
            names.push("attach_pieces");
        }
        for part in self.surface_stages.iter().flat_map(|s| s.parts()) {
            if !names.contains(&part) {
                names.push(part);
            }
        }
        names.push("referee");
        names
    }

    /// The time at which output frame `k` ends (s): the one clock every caller of the loop uses.
    pub fn frame_time(&self, k: usize) -> Real {
        k as Real * (1.0 / self.fps)
    }

    /// Replaces the cloth solver (its initial frame becomes the cloth's state): for sweeps and
    /// fixtures that set the solver's parameters themselves. Call before [`Pipeline::start`].
    pub fn set_solver(&mut self, solver: Box<dyn ClothSolver>) {
        self.cloth = solver.initial_frame();
        self.solver = solver;
    }

    /// Body vertex positions in a recorded pose (the rest mesh for a body that holds still).
    pub fn body_at(&self, pose: Option<&Pose>) -> Vec<Vec3> {
        match pose {
            Some(p) if self.motion.is_some() => {
                let mut out = Vec::new();
                self.body.shape_at(p, &mut out);
                out
            }
            _ => self.body_mesh.positions.clone(),
        }
    }

    /// The loop's state at time 0: the body posed at the motion's start, the follower started on
    /// the cloth, and the surface evaluated once on the starting cloth.
    pub fn start(&mut self) -> LoopState {
        let mut st = LoopState {
            body_frame: BodyFrame {
                time: 0.0,
                positions: self.body_mesh.positions.clone(),
                velocities: Vec::new(),
            },
            pose: Pose::default(),
        };
        if let Some(motion) = &mut self.motion {
            motion.sample(0.0, &mut st.pose);
            self.body.pose(&st.pose, &mut st.body_frame);
        }
        if let Some(f) = &mut self.follower {
            f.start(&st.pose, &st.body_frame, &self.cloth.positions);
        }
        let input = SurfaceInput {
            coarse: &self.cloth,
            body: self.motion.is_some().then_some(&st.body_frame),
        };
        run_surface(
            &mut self.surface_stages,
            &input,
            &mut self.surface,
            &mut Untimed,
        );
        st
    }

    /// The coarse part of the output frame ending at time `t`: motion, skinning, following,
    /// collider update, bands, grab, the cloth step and attached pieces (each timed into
    /// `timers`). The referee is not run here. A body that moves far within the frame is moved
    /// in sub-frames (its pose sampled between the frames), each followed by a cloth step, so
    /// that no body vertex moves more than [`BODY_STEP`] between two collider updates.
    pub fn advance_coarse(
        &mut self,
        st: &mut LoopState,
        t: Real,
        timers: &mut Timers,
    ) -> StepReport {
        let dt = 1.0 / self.fps;
        let parts = self.body_parts(st, t, timers);
        let mut report = StepReport::default();
        for i in 1..=parts {
            // The last part ends exactly at `t` (the pose `body_parts` shaped the body in).
            let ti = match i == parts {
                true => t,
                false => t - dt + dt * i as Real / parts as Real,
            };
            report.accumulate(&self.advance_part(st, ti, dt / parts as Real, timers));
        }
        report.body_parts = parts as u32;
        if !self.attachments.is_empty() {
            timers.time("attach_pieces", || {
                let riding = match self.scene.effects.self_collision {
                    true => garment_fit::Riding::Whole,
                    false => garment_fit::Riding::PerVertex,
                };
                garment_fit::apply_attachments(
                    &self.attachments,
                    riding,
                    &mut self.cloth.positions,
                    &mut self.cloth.velocities,
                )
            });
        }
        report
    }

    /// How many sub-frames the body needs to reach its pose at `t` moving no vertex near the
    /// cloth more than `[scene] body_step` in one (1 for a body that holds still; at most
    /// [`MAX_BODY_PARTS`]).
    fn body_parts(&mut self, st: &LoopState, t: Real, timers: &mut Timers) -> usize {
        let step = self.scene.scene.body_step;
        let Some(motion) = self.motion.as_ref().filter(|_| step > 0.0) else {
            return 1;
        };
        let settle = self.scene.scene.settle;
        let (body, end) = (&mut self.body, &mut self.end_shape);
        timers.time("skinning", || {
            let mut pose = st.pose.clone();
            motion.sample((t - settle).max(0.0), &mut pose);
            // Kept by the body: the last sub-frame's `pose` takes it instead of skinning again.
            body.shape_next(&pose, end);
        });
        // Only the body near the cloth counts (a dress does not care how fast the feet move): its
        // vertices inside the cloth's bounding box grown by a tenth of a metre.
        let (mut lo, mut hi) = (Vec3::repeat(Real::INFINITY), Vec3::repeat(-Real::INFINITY));
        for p in &self.cloth.positions {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        let (lo, hi) = (lo.add_scalar(-0.1), hi.add_scalar(0.1));
        let near = |p: &Vec3| (0..3).all(|k| p[k] >= lo[k] && p[k] <= hi[k]);
        let far = end
            .iter()
            .zip(&st.body_frame.positions)
            .filter(|(_, b)| near(b))
            .map(|(a, b)| (a - b).norm_squared())
            .fold(0.0, Real::max)
            .sqrt();
        if !far.is_finite() {
            return 1;
        }
        ((far / step).ceil() as usize).clamp(1, MAX_BODY_PARTS)
    }

    /// One sub-frame ending at `t`, `dt` long: the body posed at `t`, then the cloth stepped.
    fn advance_part(
        &mut self,
        st: &mut LoopState,
        t: Real,
        dt: Real,
        timers: &mut Timers,
    ) -> StepReport {
        let settle = self.scene.scene.settle;
        let LoopState { body_frame, pose } = st;
        if let Some(motion) = &mut self.motion {
            timers.time("motion", || {
                motion.sample((t - settle).max(0.0), pose);
                pose.time = t;
            });
            timers.time("skinning", || self.body.pose(pose, body_frame));
            if let Some(f) = &mut self.follower {
                let cloth = &mut self.cloth;
                timers.time("follow_body", || f.carry(pose, body_frame, cloth, dt));
            }
            if let Some(c) = &mut self.collider {
                let cloth = &self.cloth.positions;
                timers.time("collider_update", || {
                    if let Some((lo, hi)) = finite_bounds(cloth) {
                        c.focus(&lo, &hi);
                    }
                    c.update(body_frame)
                });
            }
            if let Some(b) = &mut self.bands {
                let solver = &mut self.solver;
                let first = b.first_handle;
                timers.time("bands", || {
                    if let Some(targets) = b.targets(body_frame) {
                        solver.hold_handles(first, targets);
                    }
                });
            }
        }
        if let Some(handle) = self
            .grab
            .as_ref()
            .and_then(|g| g.handle_at(t, &self.cloth.positions))
        {
            self.solver.grab(handle);
            self.grab = None;
        }
        let mut none = NoCollider;
        let collider: &mut dyn Collider = match &mut self.collider {
            Some(c) => c.as_mut(),
            None => &mut none,
        };
        let (solver, cloth) = (&mut self.solver, &mut self.cloth);
        // Stepped on a worker of rayon's pool: the solver's parallel sweeps (dozens a step) then
        // start there, instead of each being handed from this thread to the pool and waited
        // for (a futex wake and sleep per sweep, 10-15% of a walk's single-thread time).
        let report = timers.time("cloth", || {
            rayon::scope(|_| solver.step_frame(cloth, dt, collider))
        });
        if let Some(f) = &mut self.follower {
            timers.time("follow_body", || f.record(&cloth.positions));
        }
        report
    }

    /// One output frame ending at time `t`: [`Pipeline::advance_coarse`], then the surface stages
    /// on its result.
    pub fn advance(&mut self, st: &mut LoopState, t: Real, timers: &mut Timers) -> StepReport {
        let report = self.advance_coarse(st, t, timers);
        let input = SurfaceInput {
            coarse: &self.cloth,
            body: self.motion.is_some().then_some(&st.body_frame),
        };
        run_surface(&mut self.surface_stages, &input, &mut self.surface, timers);
        report
    }

    /// The garment as output: the fine surface when the scene refines, else the coarse cloth.
    pub fn output_garment(&self) -> &[Vec3] {
        if self.surface_stages.is_empty() {
            &self.cloth.positions
        } else {
            &self.surface.positions
        }
    }

    /// Each garment's name (a real garment's file, else its kind) and, for every output triangle
    /// (as [`Pipeline::output_triangles`] lists them), the garment it belongs to.
    pub fn output_garments(&self, triangles: &[[u32; 3]]) -> (Vec<String>, Vec<u16>) {
        use crate::scene::GarmentSection as G;
        let names = self
            .scene
            .garments()
            .iter()
            .map(|w| match w.garment {
                G::Mhclo(g) => std::path::Path::new(&g.file)
                    .file_stem()
                    .map_or("garment".into(), |s| s.to_string_lossy().into_owned()),
                G::Dress(_) => "dress".into(),
                G::Skirt(_) => "skirt".into(),
                G::Shirt(_) => "shirt".into(),
                G::Square(_) => "sheet".into(),
                G::Kimono(_) => "kimono".into(),
            })
            .collect();
        let of_coarse = |v: u32| {
            self.wear
                .iter()
                .position(|w| w.particles.contains(&v))
                .unwrap_or(0) as u16
        };
        let fine = !self.surface_stages.is_empty();
        let coarse = self.surface.coarse_triangles.as_slice();
        let of = |v: u32| match fine {
            false => of_coarse(v),
            true => self
                .surface
                .sources
                .get(v as usize)
                .and_then(|s| coarse.get(s.face as usize))
                .map_or(0, |t| of_coarse(t[0])),
        };
        (names, triangles.iter().map(|t| of(t[0])).collect())
    }

    /// The garment's output triangles (the fine surface's when the scene refines; after
    /// [`Pipeline::start`]).
    pub fn output_triangles(&self) -> Vec<[u32; 3]> {
        if self.surface_stages.is_empty() {
            self.garment.triangulate().0
        } else {
            self.surface.triangles.clone()
        }
    }
}

/// The bounds of the finite points of `p`, if any.
fn finite_bounds(p: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let mut it = p.iter().filter(|x| tryon_core::math::is_finite(x));
    let first = *it.next()?;
    Some(it.fold((first, first), |(lo, hi), x| (lo.inf(x), hi.sup(x))))
}
