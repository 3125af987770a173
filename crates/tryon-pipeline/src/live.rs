//! A scene run live, as `tryon view SCENE` drives it: one frame at a time for as long as the page
//! watches (the clip's last pose holds once it ends), each judged for the page's plots and
//! colours, while the user's hand grabs a particle of the coarse cloth and drags it (P4's
//! interaction, through [`ClothSolver::grab`](tryon_core::stages::ClothSolver::grab) and
//! `release`).

use crate::export::{ViewMeshes, view_header};
use crate::metrics::stretch;
use crate::pipeline::Pipeline;
use crate::run::{RunContext, RunState, Timers};
use std::time::Instant;
use thiserror::Error;
use tryon_core::interact::Handle;
use tryon_core::math::{Real, Vec3};
use tryon_io::{LiveFrame, ViewHeader};

/// Farthest the hand's point may lie from the cloth particle it takes (m).
pub const GRAB_REACH: Real = 0.15;

/// Why the hand took nothing.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum GrabError {
    #[error("no cloth within {GRAB_REACH} m of ({:.3}, {:.3}, {:.3}) (the nearest particle is {nearest:.3} m away)", .point[0], .point[1], .point[2])]
    NoCloth { point: [Real; 3], nearest: Real },
    #[error("particle {0} is held by the garment itself (a band or pin); grab the cloth beside it")]
    Held(u32),
}

/// The particle in the user's hand and where the hand is.
#[derive(Clone, Copy, Debug)]
struct Hand {
    particle: u32,
    target: Vec3,
}

/// A scene running live.
#[derive(Debug)]
pub struct Live {
    pipeline: Pipeline,
    ctx: RunContext,
    state: RunState,
    timers: Timers,
    hand: Option<Hand>,
    header: ViewHeader,
    /// Particles held by the garment itself (bands): never grabbed.
    held: Vec<u32>,
    /// The last frame's depths and deepest point, as [`Live::judge`] gave them.
    judged: (Vec<u8>, Real),
    /// The output garment as the scene started (where a scene's `[[fold]]` points lie).
    start: Vec<Vec3>,
}

impl Live {
    /// Starts `pipeline` (as a run starts: the body posed, the referee on it).
    pub fn new(mut pipeline: Pipeline) -> Live {
        let (ctx, state) = pipeline.prepare(None);
        let garment = pipeline.output_garment().len();
        let coarse = match ctx.refines {
            true => pipeline.cloth.positions.len(),
            false => 0,
        };
        let meshes = ViewMeshes {
            body: &ctx.body_triangles,
            coarse: &ctx.coarse_triangles,
            garment: &ctx.garment_triangles,
            triangle_garment: &ctx.triangle_garment,
            names: &ctx.garment_names,
        };
        let counts = [pipeline.body_mesh.positions.len(), coarse, garment];
        let mut header = view_header(&pipeline.scene.scene.name, pipeline.fps, &meshes, counts);
        header.depth = true;
        let held = pipeline
            .bands
            .as_ref()
            .map_or(Vec::new(), |b| b.vertices.clone());
        let start = pipeline.output_garment().to_vec();
        let timers = Timers::restored(&state.timers, &pipeline.stages());
        let mut live = Live {
            pipeline,
            ctx,
            state,
            timers,
            hand: None,
            header,
            held,
            judged: (Vec::new(), 0.0),
            start,
        };
        // The first frame's figures are the starting shape's.
        live.judge_last();
        live
    }

    /// What stays the same: the meshes, the name, the frame rate.
    pub fn header(&self) -> &ViewHeader {
        &self.header
    }

    /// Makes the next frame: the hand's particle carried to its target over the frame, the scene
    /// stepped. Its depths and deepest point are the frame before's ([`Live::judge_last`]).
    pub fn step(&mut self) -> LiveFrame {
        let k = self.state.next;
        self.state.next += 1;
        let p = &mut self.pipeline;
        let t = p.frame_time(k);
        if let Some(h) = self.hand {
            let here = p.cloth.positions[h.particle as usize];
            p.solver.grab(Handle {
                particle: h.particle,
                path: vec![(p.cloth.time, here), (t, h.target)],
            });
        }
        let start = Instant::now();
        let st = &mut self.state.loop_state;
        let timers = &mut self.timers;
        rayon::scope(|_| p.advance(st, t, timers));
        let ms = start.elapsed().as_secs_f64() * 1e3;
        self.timers.end_frame();
        let p = &self.pipeline;
        let (_, max_stretch, _) = stretch(
            &self.ctx.info.edges,
            &self.ctx.info.rest,
            &p.cloth.positions,
        );
        LiveFrame {
            frame: k as u32,
            time: t,
            ms,
            max_stretch,
            grabbed: self.hand.map(|h| h.particle),
            body: self.state.loop_state.body_frame.positions.clone(),
            coarse: match self.ctx.refines {
                true => p.cloth.positions.clone(),
                false => Vec::new(),
            },
            garment: p.output_garment().to_vec(),
            depth: self.judged.0.clone(),
            max_penetration_m: self.judged.1,
        }
    }

    /// Judges the frame [`Live::step`] made last, for the next frame's figures (the referee
    /// takes about as long as the frame itself: done once the frame is on its way, it does not
    /// delay it).
    pub fn judge_last(&mut self) {
        self.judged = self.judge();
    }

    /// Each output vertex's depth in the body (quarter millimetres, at most 255) and the deepest.
    fn judge(&mut self) -> (Vec<u8>, Real) {
        let p = &mut self.pipeline;
        if self.ctx.moving {
            tryon_core::stages::Collider::update(&mut p.referee, &self.state.loop_state.body_frame);
        }
        let output = match p.surface_stages.is_empty() {
            true => &p.cloth.positions,
            false => &p.surface.positions,
        };
        let signed = crate::metrics::distances(&mut p.referee, output);
        let deepest = signed.iter().map(|d| (-d).max(0.0)).fold(0.0, Real::max);
        let depth = signed.iter().map(|d| tryon_io::depth_code(-d)).collect();
        (depth, deepest)
    }

    /// Takes the coarse particle nearest `point` into the hand (letting go of any other).
    pub fn grab(&mut self, point: Vec3) -> Result<u32, GrabError> {
        let x = &self.pipeline.cloth.positions;
        let (k, d) = (x.iter().enumerate())
            .map(|(k, q)| (k, (q - point).norm()))
            .filter(|(_, d)| d.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, Real::INFINITY));
        if d > GRAB_REACH {
            return Err(GrabError::NoCloth {
                point: point.into(),
                nearest: d,
            });
        }
        let k = k as u32;
        if self.held.contains(&k) {
            return Err(GrabError::Held(k));
        }
        let target = x[k as usize];
        self.release();
        self.hand = Some(Hand {
            particle: k,
            target,
        });
        Ok(k)
    }

    /// Moves the hand to `target` (reached over the next frame); nothing without a grab.
    pub fn drag(&mut self, target: Vec3) {
        if let Some(h) = &mut self.hand {
            h.target = target;
        }
    }

    /// Lets go of the hand's particle.
    pub fn release(&mut self) {
        if let Some(h) = self.hand.take() {
            self.pipeline.solver.release(h.particle);
        }
    }

    /// Points on the garment as it is now carried to where the same places were when the scene
    /// started (each by its nearest output vertex, when within [`GRAB_REACH`] of it): a
    /// line drawn on the moving garment as a scene's `[[fold]] points` take it. A point farther
    /// from the garment is left where it is, for the scene's own check to name.
    pub fn to_start(&self, points: &[Vec3]) -> Vec<Vec3> {
        let now = self.pipeline.output_garment();
        points
            .iter()
            .map(|p| {
                let nearest = (now.iter().enumerate())
                    .map(|(k, q)| (k, (q - p).norm()))
                    .min_by(|a, b| a.1.total_cmp(&b.1));
                match nearest {
                    // The vertex's start, and the point's offset from it (small: the point is
                    // on the surface beside it).
                    Some((k, d)) if d <= GRAB_REACH => {
                        self.start.get(k).map_or(*p, |s| s + (p - now[k]))
                    }
                    _ => *p,
                }
            })
            .collect()
    }

    /// The cloth's coarse particles now.
    pub fn coarse(&self) -> &[Vec3] {
        &self.pipeline.cloth.positions
    }
}
