//! How far a refined surface gives back the length the coarse cloth lost where it is compressed
//! (P1.4.3's purpose): the figures a surface stage judges and stats.json reports.

use crate::math::Real;

/// Length restoration over the coarse edges compressed on the reference surface (the refined
/// surface before wrinkles): each edge's fine path through the output and through the reference.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LengthJudgement {
    /// Compressed coarse edges counted.
    pub edges: usize,
    /// Mean of |fine path length - rest| / rest, through the output surface.
    pub error: Real,
    /// The same through the reference surface: what the output would be with wrinkles off.
    pub reference_error: Real,
    /// Share of the edges whose path through the output is within [`RESTORED_WITHIN`] of rest.
    pub restored: Real,
    /// The same through the reference surface.
    pub reference_restored: Real,
}

/// A compressed edge counts as restored when its fine path is within this fraction of its rest
/// length.
pub const RESTORED_WITHIN: Real = 0.02;
