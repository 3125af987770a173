//! The surface stages of P1 section 4 as the pipeline runs them: PN refinement (pnt-surface), then
//! the wrinkle model, fine penetration removal and normal blending (wrinkle), each timed apart.

use crate::run::Timers;
use pnt_surface::PnRefiner;
use tryon_core::frames::{BodyFrame, CoarseFrame, FineSurface};
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_core::stages::Collider;
use wrinkle::Detail;

/// The fine surface's state between frames.
pub struct FineStage {
    pub refiner: PnRefiner,
    pub detail: Detail,
    /// Collider for fine vertices (its own tracking caches); `None` without body collision.
    pub collider: Option<Box<dyn Collider>>,
    pub surface: FineSurface,
    /// -1 when the garment's triangles wind inward (normals are flipped to face away from the body).
    pub orientation: Real,
    coarse_normals: Vec<Vec3>,
    /// Sum over frames of the mean length restoration error and frames counted.
    pub length_error_sum: Real,
    pub length_frames: usize,
}

impl std::fmt::Debug for FineStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FineStage")
            .field("level", &self.refiner.level)
            .field("fine_vertices", &self.refiner.fine_vertices())
            .field("collider", &self.collider.as_ref().map(|c| c.name()))
            .finish()
    }
}

impl FineStage {
    pub fn new(
        refiner: PnRefiner,
        detail: Detail,
        collider: Option<Box<dyn Collider>>,
        orientation: Real,
    ) -> Self {
        FineStage {
            refiner,
            detail,
            collider,
            surface: FineSurface::default(),
            orientation,
            coarse_normals: Vec::new(),
            length_error_sum: 0.0,
            length_frames: 0,
        }
    }

    /// Runs the enabled surface stages on a coarse frame (body already in `body`).
    pub fn run(&mut self, coarse: &CoarseFrame, body: Option<&BodyFrame>, timers: &mut Timers) {
        let p = self.detail.params.clone();
        let wrinkles = p.wrinkles;
        timers.time("refine", || {
            vertex_normals(
                &coarse.positions,
                &self.refiner.coarse_triangles,
                &mut self.coarse_normals,
            );
            if self.orientation < 0.0 {
                self.coarse_normals.iter_mut().for_each(|n| *n = -*n);
            }
            self.refiner
                .evaluate(&coarse.positions, &self.coarse_normals, &mut self.surface);
            if !wrinkles {
                // Takes the reference surface only.
                self.detail.wrinkle(coarse, &mut self.surface);
            }
        });
        if wrinkles {
            timers.time("wrinkle", || self.detail.wrinkle(coarse, &mut self.surface));
        }
        let collide = p.fine_collision && self.collider.is_some();
        if collide && let Some(c) = &mut self.collider {
            timers.time("fine_collision", || {
                if let Some(b) = body {
                    c.update(b);
                }
                self.detail
                    .fine_collision(coarse, &mut self.surface, c.as_mut());
            });
        }
        if p.blend_normals && (wrinkles || collide) {
            timers.time("normals", || self.detail.blend_normals(&mut self.surface));
        }
    }

    /// Adds this frame's length restoration error (a metric, not a surface stage: the pipeline
    /// times it with the referee).
    pub fn record_length_error(&mut self) {
        let (e, n) = self.detail.length_error(&self.surface.positions);
        if n > 0 {
            self.length_error_sum += e;
            self.length_frames += 1;
        }
    }
}
