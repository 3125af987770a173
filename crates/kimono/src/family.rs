//! The kimono family P2 blends: an initial shape and ten target shapes, each a kimono tailored to
//! one body size, all built on one [`Layout`] so they share a topology. P2 scanned real kimonos
//! worn on mannequins; here each is the flat tailored kimono ([`crate::mesh`]).

use crate::dims::{Dimensions, TailorError, Wearer, tailor};
use crate::levels::{Layout, LevelError};
use crate::mesh::{KimonoMesh, build};
use thiserror::Error;
use tryon_core::math::{Real, Vec3};

/// The initial shape's wearer: a medium figure.
pub const BASE: Wearer = Wearer::new(1.58, 0.84, 0.66, 0.92);

/// The ten target shapes' wearers: heights 1.48–1.78 m, slim to full.
pub const TARGETS: [Wearer; 10] = [
    Wearer::new(1.48, 0.80, 0.62, 0.86),
    Wearer::new(1.52, 0.84, 0.66, 0.90),
    Wearer::new(1.55, 0.90, 0.72, 0.94),
    Wearer::new(1.58, 0.80, 0.60, 0.86),
    Wearer::new(1.60, 0.96, 0.80, 1.00),
    Wearer::new(1.63, 0.86, 0.66, 0.92),
    Wearer::new(1.66, 0.92, 0.74, 0.98),
    Wearer::new(1.70, 0.88, 0.68, 0.94),
    Wearer::new(1.74, 1.00, 0.84, 1.06),
    Wearer::new(1.78, 0.92, 0.72, 1.00),
];

/// Edge length of the family's layout on the initial shape, m.
pub const EDGE: Real = 0.03;

/// Why the family cannot be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FamilyError {
    #[error("{what}: {source}")]
    Tailor {
        what: String,
        #[source]
        source: TailorError,
    },
    #[error("{what}: {source}")]
    Levels {
        what: String,
        #[source]
        source: LevelError,
    },
}

/// The initial mesh and the target shapes' positions.
#[derive(Clone, Debug, PartialEq)]
pub struct Family {
    pub layout: Layout,
    pub base_dims: Dimensions,
    pub base: KimonoMesh,
    pub targets: Vec<Vec<Vec3>>,
}

/// The flat family: the initial kimono and the ten targets, tailored and built.
pub fn flat_family() -> Result<Family, FamilyError> {
    let tail =
        |what: String, w: &Wearer| tailor(w).map_err(|source| FamilyError::Tailor { what, source });
    let base_dims = tail("the initial shape".into(), &BASE)?;
    let lv = |what: String| move |source| FamilyError::Levels { what, source };
    let layout = Layout::for_dims(&base_dims, EDGE).map_err(lv("the initial shape".into()))?;
    let base = build(&base_dims, &layout).map_err(lv("the initial shape".into()))?;
    let mut targets = Vec::new();
    for (k, w) in TARGETS.iter().enumerate() {
        let what = format!("target {k}");
        let d = tail(what.clone(), w)?;
        targets.push(build(&d, &layout).map_err(lv(what))?.positions);
    }
    Ok(Family {
        layout,
        base_dims,
        base,
        targets,
    })
}
