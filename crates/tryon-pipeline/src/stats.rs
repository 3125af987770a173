//! What a run reports: stats.json's figures (counts, accuracy metrics judged by the exact referee,
//! per-frame figures, stage times).

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use tryon_core::math::Real;

pub use crate::timers::StageTime;

/// Counts of the scene's meshes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Counts {
    pub coarse_vertices: usize,
    pub coarse_faces: usize,
    pub springs: usize,
    pub body_vertices: usize,
    pub body_triangles: usize,
    /// Vertices of the refined surface (when the scene refines).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fine_vertices: Option<usize>,
}

/// Accuracy and robustness over the run, judged by the exact referee.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
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
    /// The 99th percentile of structural edge length / rest length over every edge of every
    /// judged frame (to 1e-4).
    #[serde(default)]
    pub p99_stretch: Real,
    /// Largest share, over frames, of garment vertices detached from the body (torn, slid or
    /// fallen off; `body_collide::hold`): 0 while the garment stays on.
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
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_error: Option<Real>,
    /// The same error through the reference surface, the refined surface before wrinkles: what
    /// `length_error` would be with wrinkles off, judged on the same frames.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_error_reference: Option<Real>,
    /// Mean over frames of the share of compressed coarse edges whose fine path is back within 2%
    /// of rest, through the output and through the reference surface.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_restored_share: Option<Real>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub length_restored_share_reference: Option<Real>,
    /// With `[effects] body_press`: body vertices pressed out of another part per pose (mean), and
    /// the deepest overlap of two parts found before pressing (m). The GLB's body does not carry
    /// the press (its joints alone animate it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body_pressed_per_pose: Option<Real>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body_press_deepest_m: Option<Real>,
    /// Garment vertices moved out of the body when placing it on the rest pose.
    pub placement_moved: usize,
    /// Frames the referee judged (`[output] referee_every`); the figures above are over these.
    pub judged_frames: usize,
    /// The referee judged every this many frames (and the last): `referee_every` times the stride
    /// estimated to hold it to `referee_share` of the run's time.
    #[serde(default)]
    pub judged_every: usize,
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
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub untangle: Option<UntangleStats>,
    /// Per `[[fold]]`, its height over the surrounding cloth at the last frame over its drawn
    /// height (P3's open problem: how far simulation drifts from the drawn shape); null where
    /// a fold could not be measured. Absent without folds.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fold_retention: Vec<Option<Real>>,
    /// The same before the simulation, as shaped (smoothing alone lowers a fold).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fold_retention_shaped: Vec<Option<Real>>,
}

/// What untangling the starting shape did (`tryon_core::stages::Untangled`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
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
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameStats {
    pub frame: usize,
    pub max_penetration_m: Real,
    pub p99_penetration_m: Real,
    pub max_stretch: Real,
    /// Share of garment vertices detached from the body (`body_collide::hold`).
    pub detached_share: Real,
    /// Crossing pairs of garment triangles.
    pub cloth_intersections: usize,
    pub contacts: u32,
    pub retries: u32,
    /// Sub-frames the body moved in.
    pub body_parts: u32,
    /// Each fold's height over its drawn height (NaN where not measurable; absent without folds).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub fold_retention: Vec<Real>,
}

/// Everything stats.json holds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub scene: String,
    pub frames: usize,
    pub fps: Real,
    pub integrator: String,
    pub substep_s: Real,
    pub collider: String,
    pub counts: Counts,
    /// What retargeting the clip changed (absent for motions that are not captured clips).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retarget: Option<RetargetStats>,
    /// Only the stages that ran.
    pub stages: BTreeMap<String, StageTime>,
    pub metrics: Metrics,
    /// Wall time of the whole frame loop, s.
    pub loop_s: Real,
    /// What was mended in the input while assembling (absent when nothing was).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    pub per_frame: Vec<FrameStats>,
    /// Each judged frame's wall time per stage (ms), in `per_frame`'s order (the viewer plots
    /// them). Wall times: unlike `per_frame`, they differ from run to run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub frame_ms: Vec<std::collections::BTreeMap<String, Real>>,
}

/// [`Stats`] inside a checkpoint: CBOR (which, like stats.json's JSON, names its fields, so the
/// fields stats.json leaves out when empty come back) as one byte string of the compact form.
pub(crate) mod self_described {
    use super::Stats;
    use serde::{Deserializer, Serializer};

    pub fn serialize<S: Serializer>(stats: &Stats, s: S) -> Result<S::Ok, S::Error> {
        let mut bytes = Vec::new();
        ciborium::into_writer(stats, &mut bytes).map_err(serde::ser::Error::custom)?;
        s.serialize_bytes(&bytes)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Stats, D::Error> {
        let bytes: Vec<u8> = serde::Deserialize::deserialize(d)?;
        ciborium::from_reader(bytes.as_slice()).map_err(serde::de::Error::custom)
    }
}

/// Sums over judged frames of the length restoration figures (`Metrics::length_error` and the
/// rest), for their means at the run's end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LengthSums {
    pub frames: usize,
    pub error: Real,
    pub reference_error: Real,
    pub restored: Real,
    pub reference_restored: Real,
}

impl LengthSums {
    /// Adds a frame's judgement (frames without compressed edges are not counted).
    pub fn add(&mut self, j: &tryon_core::stages::LengthJudgement) {
        if j.edges == 0 {
            return;
        }
        self.frames += 1;
        self.error += j.error;
        self.reference_error += j.reference_error;
        self.restored += j.restored;
        self.reference_restored += j.reference_restored;
    }

    /// Writes the means into `m`.
    pub fn fill(&self, m: &mut Metrics) {
        let n = self.frames.max(1) as Real;
        m.length_error = Some(self.error / n);
        m.length_error_reference = Some(self.reference_error / n);
        m.length_restored_share = Some(self.restored / n);
        m.length_restored_share_reference = Some(self.reference_restored / n);
    }
}
