//! The detail model as the frame loop runs it ([`SurfaceStage`]): the wrinkle model (or, with it
//! off, only taking the reference surface, timed with refinement), fine penetration removal against
//! the stage's own collider, and normal blending, each a timed part.

use crate::Detail;
use tryon_core::frames::FineSurface;
use tryon_core::stages::{Clock, Collider, LengthJudgement, SurfaceInput, SurfaceStage};

/// [`Detail`] with the collider its fine vertices are tested against (its own tracking caches;
/// `None` when fine collision is off).
pub struct DetailStage {
    pub detail: Detail,
    pub collider: Option<Box<dyn Collider>>,
}

impl std::fmt::Debug for DetailStage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DetailStage")
            .field("params", &self.detail.params)
            .field("collider", &self.collider.as_ref().map(|c| c.name()))
            .finish()
    }
}

impl DetailStage {
    pub fn new(detail: Detail, collider: Option<Box<dyn Collider>>) -> Self {
        DetailStage { detail, collider }
    }

    fn collides(&self) -> bool {
        self.detail.params.fine_collision && self.collider.is_some()
    }

    fn blends(&self) -> bool {
        self.detail.params.blend_normals && (self.detail.params.wrinkles || self.collides())
    }
}

impl SurfaceStage for DetailStage {
    /// The detail model's state, then its collider's (which must be checkpointable too).
    fn save_state(&self) -> Option<Vec<u8>> {
        let collider = match &self.collider {
            Some(c) => Some(c.save_state()?),
            None => None,
        };
        Some(tryon_core::state::encode(&(&self.detail, collider)))
    }
    fn restore_state(&mut self, state: &[u8]) -> Result<(), tryon_core::state::StateError> {
        use tryon_core::state::StateError;
        let (detail, collider): (Detail, Option<Vec<u8>>) = tryon_core::state::decode(state)?;
        match (&mut self.collider, collider) {
            (Some(c), Some(bytes)) => c.restore_state(&bytes)?,
            (None, None) => {}
            _ => {
                return Err(StateError::Mismatch(
                    "fine collision on in one, off in the other".into(),
                ));
            }
        }
        self.detail = detail;
        Ok(())
    }
    fn parts(&self) -> Vec<&'static str> {
        let mut parts = vec![if self.detail.params.wrinkles {
            "wrinkle"
        } else {
            "refine"
        }];
        if self.collides() {
            parts.push("fine_collision");
        }
        if self.blends() {
            parts.push("normals");
        }
        parts
    }

    fn run(&mut self, input: &SurfaceInput<'_>, surface: &mut FineSurface, clock: &mut dyn Clock) {
        let (collides, blends) = (self.collides(), self.blends());
        let coarse = input.coarse;
        let detail = &mut self.detail;
        // With wrinkles off this only takes the reference surface.
        let first = if detail.params.wrinkles {
            "wrinkle"
        } else {
            "refine"
        };
        clock.time(first, &mut || detail.wrinkle(coarse, surface));
        if collides && let Some(c) = &mut self.collider {
            clock.time("fine_collision", &mut || {
                if let Some(b) = input.body {
                    c.update(b);
                }
                detail.fine_collision(coarse, surface, c.as_mut());
            });
        }
        if blends {
            clock.time("normals", &mut || detail.blend_normals(surface));
        }
    }

    fn length_error(&self, surface: &FineSurface) -> Option<LengthJudgement> {
        Some(self.detail.length_judgement(&surface.positions))
    }
}
