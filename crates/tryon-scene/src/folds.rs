//! The scene's folds (P3): each `[[fold]]` a line drawn on the garment, and `[folding]` how the
//! folds are shaped (smoothing rounds) and held (the bend springs across each line).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use tryon_core::math::Real;

/// One fold drawn on the garment (`[[fold]]`, as many as wanted): a line given either as points
/// on the garment as it is placed on the body at the start (`points`, world coordinates, m), each
/// snapped to the nearest surface point within `[folding] snap`, or, as P3 draws it, in the
/// picture `tryon canvas` writes (`screen`, pixels), each landing where its pixel shows the garment.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FoldSpec {
    /// A ridge stands out of the garment (along its outward normal), a valley sinks in.
    #[serde(default)]
    pub shape: FoldShape,
    /// The line's points in order, at least two (m; or give `screen`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub points: Vec<[Real; 3]>,
    /// The line's points in order, at least two, as pixels `[x, y]` of the canvas picture
    /// (`tryon canvas`: the dressed garment as the preview frames it, `[output] preview_width` x
    /// `preview_height`, x to the right and y down from the top-left corner; or give `points`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub screen: Vec<[Real; 2]>,
    /// The line of the scene file the fold was read from (for errors).
    #[serde(skip)]
    #[schemars(skip)]
    pub line: Option<usize>,
    /// How far the ridge stands out, or the valley sinks in (m).
    #[schemars(range(min = 0.001, max = 1.0))]
    pub height: Real,
}

/// Which way a fold stands.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FoldShape {
    #[default]
    Ridge,
    Valley,
}

/// One smoothing round's kind.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SmoothName {
    /// Every vertex sees all its neighbours: the ridge sinks and widens.
    Plain,
    /// Taubin's hierarchical constraint: the line's vertices see only each other, so the ridge
    /// is smoothed along its length and keeps its height.
    Constrained,
}

/// Which bend springs a fold shortens and stiffens.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum HoldName {
    /// P3's rule: the springs crossing the drawn line.
    #[default]
    Line,
    /// Every spring spanning an edge of the smoothed fold.
    Fold,
}

/// How the `[[fold]]` lines are shaped and held (P3 3.4-3.5).
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct FoldingSection {
    /// The smoothing rounds after the spiky fold is made, in order.
    pub rounds: Vec<SmoothName>,
    /// Each round moves a vertex this fraction of the way to its neighbours' mean.
    #[schemars(range(min = 0.01, max = 1.0))]
    pub lambda: Real,
    /// Rings of vertices around a line that smoothing moves.
    #[schemars(range(min = 0, max = 20))]
    pub rings: u32,
    /// Farthest a line's point may be from the garment (m).
    #[schemars(range(min = 0.0, max = 1.0))]
    pub snap: Real,
    /// Rest length of the bend springs crossing a line, as a share of their folded length.
    #[schemars(range(min = 0.1, max = 1.0))]
    pub bend_shorten: Real,
    /// Stiffness of the bend springs crossing a line, as a multiple of the others'.
    #[schemars(range(min = 1.0, max = 1000.0))]
    pub bend_stiffen: Real,
    /// Which bend springs are shortened and stiffened: `line` (P3's rule: those crossing the
    /// drawn line) or `fold` (every one spanning an edge of the smoothed fold, so its whole
    /// cross-section is held).
    pub hold: HoldName,
    /// Seconds the garment hangs on the body, held in the motion's first pose, before the folds
    /// are drawn on it (P3 draws on a garment at rest; a fold drawn on the garment as placed is
    /// pushed about while it settles). The garment's cut is kept: the fold is carried onto its
    /// modelled shape for the rest lengths, and the cloth starts from the draped shape, folded.
    /// 0 draws on the garment as placed.
    #[schemars(range(min = 0.0, max = 10.0))]
    pub drape: Real,
}

impl Default for FoldingSection {
    fn default() -> Self {
        let p = fold::FoldParams::default();
        FoldingSection {
            rounds: p
                .rounds
                .iter()
                .map(|r| match r {
                    fold::Round::Plain => SmoothName::Plain,
                    fold::Round::Constrained => SmoothName::Constrained,
                })
                .collect(),
            lambda: p.lambda,
            rings: p.rings,
            snap: p.snap,
            bend_shorten: p.bend_shorten,
            bend_stiffen: p.bend_stiffen,
            hold: HoldName::Line,
            drape: 1.0,
        }
    }
}

impl FoldingSection {
    /// The fold stage's parameters.
    pub fn params(&self) -> fold::FoldParams {
        fold::FoldParams {
            rounds: self
                .rounds
                .iter()
                .map(|r| match r {
                    SmoothName::Plain => fold::Round::Plain,
                    SmoothName::Constrained => fold::Round::Constrained,
                })
                .collect(),
            lambda: self.lambda,
            rings: self.rings,
            snap: self.snap,
            bend_shorten: self.bend_shorten,
            bend_stiffen: self.bend_stiffen,
            hold: match self.hold {
                HoldName::Line => fold::Hold::Line,
                HoldName::Fold => fold::Hold::Fold,
            },
        }
    }
}

impl FoldSpec {
    /// The fold stage's line.
    pub fn line(&self) -> fold::FoldLine {
        fold::FoldLine {
            kind: match self.shape {
                FoldShape::Ridge => fold::FoldKind::Ridge,
                FoldShape::Valley => fold::FoldKind::Valley,
            },
            points: self
                .points
                .iter()
                .map(|p| tryon_core::math::Vec3::new(p[0], p[1], p[2]))
                .collect(),
            height: self.height,
        }
    }
}
