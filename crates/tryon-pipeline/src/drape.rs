//! The drape scene (a reusable fixture): an N x N-particle cloth of 1 m side, horizontal, 0.5 m above
//! a fixed sphere of radius 0.3 m at the origin, under gravity, 60 output frames per second for 2 s.
//! It is a scene like any other, assembled into a [`Pipeline`] and stepped by its frame loop, with
//! the cloth solver set from the fixture's own parameters. It reports the median time per output
//! frame, the largest edge stretch over the run and the deepest penetration of any particle into
//! the sphere mesh judged by the exact referee.

use crate::assemble::AssembleError;
use crate::metrics::{Baseline, median, penetration};
use crate::pipeline::{LoopState, Pipeline};
use crate::scene::{Scene, SceneError};
use crate::timers::Timers;
use cloth_dyn::{BuildClothError, ClothModel, ClothParams, ClothSim, IntegratorKind, presets};
use std::path::Path;
use std::time::Instant;
use thiserror::Error;
use tryon_core::frames::{CoarseFrame, StepReport};
use tryon_core::math::{Real, Vec3};

pub use cloth_dyn::presets::drape as drape_params;

/// Settings of the drape scene.
#[derive(Clone, Debug, PartialEq)]
pub struct DrapeConfig {
    /// Particles per side (the cloth has n x n particles, (n-1)^2 quads).
    pub n: usize,
    pub integrator: IntegratorKind,
    pub fps: Real,
    pub duration: Real,
    pub params: ClothParams,
    /// Skin the cloth keeps from the sphere (m).
    pub thickness: Real,
    /// Icosphere subdivision level of the sphere mesh.
    pub sphere_subdivisions: u32,
    /// Judge penetration with the exact referee after every frame (not timed).
    pub measure_penetration: bool,
    /// Height of the sheet above the sphere's centre (m).
    pub drop_height: Real,
}

/// What one frame of a drape run looked like (handed to the caller's progress callback).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameTrace {
    pub frame: usize,
    pub frames: usize,
    /// Largest structural stretch this frame and where (first end of the worst edge).
    pub stretch: Real,
    pub worst_at: Vec3,
    pub contacts: u32,
    pub ms: Real,
    /// The cloth's centroid.
    pub centroid: Vec3,
    /// The cloth's kinetic energy (J).
    pub kinetic: Real,
}

impl DrapeConfig {
    /// The scene at `n` particles per side with default material for that resolution.
    pub fn new(n: usize, integrator: IntegratorKind) -> Self {
        DrapeConfig {
            n,
            integrator,
            fps: 60.0,
            duration: 2.0,
            params: presets::drape(n),
            thickness: 0.002,
            sphere_subdivisions: 4,
            measure_penetration: true,
            drop_height: 0.5,
        }
    }

    /// The fixture as a scene file.
    pub fn scene_text(&self) -> String {
        format!(
            "[scene]\nname = \"drape\"\nfps = {}\nduration = {}\nsettle = 0.0\n\
             [body]\nkind = \"sphere\"\nradius = 0.3\nsubdivisions = {}\n\
             [garment]\nkind = \"square\"\nparticles = {}\nsize = 1.0\ndrop_height = {}\n\
             [cloth]\nsolver = \"p1\"\nmaterial = \"sheet\"\nthickness = {}\n\
             [effects]\nfollow_body = false\nbody_collision = \"nearest_vertex\"\nrefine = 0\n",
            self.fps,
            self.duration,
            self.sphere_subdivisions,
            self.n,
            self.drop_height,
            self.thickness
        )
    }
}

/// Why the drape scene could not be built.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum DrapeError {
    #[error("drape needs at least 2 particles per side, got {0}")]
    TooSmall(usize),
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Assemble(#[from] AssembleError),
    #[error(transparent)]
    Cloth(#[from] BuildClothError),
}

/// What a drape run measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DrapeReport {
    pub n: usize,
    pub particles: usize,
    pub springs: usize,
    pub integrator: &'static str,
    pub frames: usize,
    pub substep: Real,
    /// Median and mean wall time of one output frame (ms); only the cloth step is timed.
    pub median_ms: Real,
    pub mean_ms: Real,
    /// Largest structural edge length / rest length over the run.
    pub max_stretch: Real,
    /// Deepest particle inside the sphere mesh over the run (m), by the exact referee.
    pub max_penetration: Real,
    /// Largest horizontal distance of the cloth's centroid from the sphere's vertical axis over the
    /// run (m). The drop is centred and symmetric, so the cloth should stay centred.
    pub max_drift: Real,
    pub steps: StepReport,
}

/// The drape scene on the pipeline, ready to step.
pub struct DrapeScene {
    pub config: DrapeConfig,
    pub pipeline: Pipeline,
    state: LoopState,
    timers: Timers,
    /// Output frames stepped so far.
    pub stepped: usize,
}

impl std::fmt::Debug for DrapeScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DrapeScene")
            .field("config", &self.config)
            .field("pipeline", &self.pipeline)
            .finish()
    }
}

impl DrapeScene {
    /// Assembles the scene, sets its cloth solver from the configuration and starts the loop.
    pub fn new(config: DrapeConfig) -> Result<Self, DrapeError> {
        let pipeline = Self::pipeline(&config)?;
        Ok(Self::started(config, pipeline))
    }

    /// The fixture's scene assembled with the cloth solver the configuration asks for, not yet
    /// started: a caller may still replace stages (a solver, a moving body), then call
    /// [`DrapeScene::started`].
    pub fn pipeline(config: &DrapeConfig) -> Result<Pipeline, DrapeError> {
        if config.n < 2 {
            return Err(DrapeError::TooSmall(config.n));
        }
        let scene = Scene::parse(&config.scene_text(), Path::new("<drape fixture>"))?;
        let mut pipeline = Pipeline::new(scene)?;
        let model = ClothModel::build(&pipeline.garment, &config.params, vec![])?;
        let sim = ClothSim::new(model, config.params.clone(), config.integrator);
        pipeline.set_solver(Box::new(sim));
        Ok(pipeline)
    }

    /// The fixture over an assembled pipeline, its loop started.
    pub fn started(config: DrapeConfig, mut pipeline: Pipeline) -> Self {
        let state = pipeline.start();
        DrapeScene {
            config,
            pipeline,
            state,
            timers: Timers::default(),
            stepped: 0,
        }
    }

    /// The cloth's state.
    pub fn frame(&self) -> &CoarseFrame {
        &self.pipeline.cloth
    }

    /// Number of output frames in the run.
    pub fn frame_count(&self) -> usize {
        (self.config.duration * self.config.fps).round() as usize
    }

    /// Steps one output frame through the pipeline's frame loop.
    pub fn step(&mut self) -> StepReport {
        self.stepped += 1;
        let t = self.pipeline.frame_time(self.stepped);
        let r = self.pipeline.advance(&mut self.state, t, &mut self.timers);
        self.timers.end_frame();
        r
    }

    /// Runs the whole scene, calling `progress` after each frame.
    pub fn run(&mut self, mut progress: impl FnMut(&FrameTrace)) -> DrapeReport {
        let frames = self.frame_count();
        let info = self.pipeline.solver.info();
        let (edges, rest) = (&info.edges, &info.rest);
        let mut times = Vec::with_capacity(frames);
        let mut report = DrapeReport {
            n: self.config.n,
            particles: info.particles,
            springs: info.springs,
            integrator: info.method,
            frames,
            substep: info.nominal_substep,
            ..DrapeReport::default()
        };
        for k in 0..frames {
            let t0 = Instant::now();
            let r = self.step();
            times.push(t0.elapsed().as_secs_f64() * 1e3);
            report.steps.accumulate(&r);
            let x = &self.pipeline.cloth.positions;
            let ratio =
                |e: usize| (x[edges[e][0] as usize] - x[edges[e][1] as usize]).norm() / rest[e];
            let worst = (0..edges.len())
                .max_by(|&a, &b| ratio(a).total_cmp(&ratio(b)))
                .unwrap_or(0);
            let frame_stretch = if edges.is_empty() { 1.0 } else { ratio(worst) };
            report.max_stretch = report.max_stretch.max(frame_stretch);
            report.max_drift = report.max_drift.max(horizontal_drift(x));
            if self.config.measure_penetration {
                report.max_penetration = report
                    .max_penetration
                    .max(penetration(&mut self.pipeline.referee, x, &Baseline::default()).max);
            }
            let v = &self.pipeline.cloth.velocities;
            progress(&FrameTrace {
                frame: k + 1,
                frames,
                stretch: frame_stretch,
                worst_at: edges.get(worst).map_or(Vec3::zeros(), |e| x[e[0] as usize]),
                contacts: r.contacts,
                ms: times[k],
                centroid: centroid(x),
                kinetic: v
                    .iter()
                    .zip(&info.masses)
                    .map(|(v, m)| 0.5 * m * v.norm_squared())
                    .sum(),
            });
        }
        report.median_ms = median(&times);
        report.mean_ms = times.iter().sum::<Real>() / frames.max(1) as Real;
        report
    }
}

/// Horizontal distance of the centroid of `points` from the vertical axis through the origin.
pub fn horizontal_drift(points: &[Vec3]) -> Real {
    let c = centroid(points);
    c.x.hypot(c.z)
}

/// The mean of `points` (the origin for none).
pub fn centroid(points: &[Vec3]) -> Vec3 {
    if points.is_empty() {
        return Vec3::zeros();
    }
    points.iter().sum::<Vec3>() / points.len() as Real
}
