//! The scene's garment patterns (`[garment] kind = "dress"`, `"skirt"`, `"shirt"`): each kind's
//! keys, with garment-fit's defaults.

use garment_fit::{DressParams, ShirtParams, SkirtParams};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use tryon_core::math::Real;

/// A dress pattern; garment-fit's defaults.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct DressSpec {
    /// Ease (extra girth) at bust, waist and hip (m).
    #[schemars(length(equal = 3), inner(range(min = 0.0, max = 0.5)))]
    pub ease: Vec<Real>,
    /// Extra girth at the hem over the hip girth (m).
    #[schemars(range(min = 0.0, max = 2.0))]
    pub flare: Real,
    /// Hem height above the knee (m; negative: below).
    #[schemars(range(min = -0.3, max = 0.3))]
    pub hem_above_knee: Real,
    /// Samples around a ring.
    #[schemars(range(min = 16, max = 192))]
    pub columns: usize,
    /// Spacing of rings (m).
    #[schemars(range(min = 0.005, max = 0.2))]
    pub row_spacing: Real,
    /// Elastic bands (m): border loops lying within this distance of the body grip it; 0 = none.
    #[schemars(range(min = 0.0, max = 0.05))]
    pub band_gap: Real,
}

impl Default for DressSpec {
    fn default() -> Self {
        let d = DressParams::default();
        DressSpec {
            ease: d.ease.to_vec(),
            flare: d.flare,
            hem_above_knee: d.hem_above_knee,
            columns: d.columns,
            row_spacing: d.row_spacing,
            band_gap: 0.0,
        }
    }
}

/// A skirt pattern; garment-fit's defaults.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SkirtSpec {
    /// Ease (extra girth) at waist and hip (m).
    #[schemars(length(equal = 2), inner(range(min = 0.0, max = 0.5)))]
    pub ease: Vec<Real>,
    /// Extra girth at the hem over the hip girth (m).
    #[schemars(range(min = 0.0, max = 2.0))]
    pub flare: Real,
    /// Hem height above the knee (m; negative: below).
    #[schemars(range(min = -0.3, max = 0.3))]
    pub hem_above_knee: Real,
    /// Samples around a ring.
    #[schemars(range(min = 16, max = 192))]
    pub columns: usize,
    /// Spacing of rings (m).
    #[schemars(range(min = 0.005, max = 0.2))]
    pub row_spacing: Real,
    /// Elastic bands (m): border loops lying within this distance of the body grip it; 0 = none.
    #[schemars(range(min = 0.0, max = 0.05))]
    pub band_gap: Real,
}

impl Default for SkirtSpec {
    fn default() -> Self {
        let d = SkirtParams::default();
        SkirtSpec {
            ease: d.ease.to_vec(),
            flare: d.flare,
            hem_above_knee: d.hem_above_knee,
            columns: d.columns,
            row_spacing: d.row_spacing,
            band_gap: 0.0,
        }
    }
}

/// A short-sleeved shirt; garment-fit's defaults.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ShirtSpec {
    /// Ease (extra girth) at bust, waist and hip (m).
    #[schemars(length(equal = 3), inner(range(min = 0.0, max = 0.5)))]
    pub ease: Vec<Real>,
    /// Extra girth of the sleeves over the arm's (m).
    #[schemars(range(min = 0.0, max = 0.5))]
    pub sleeve_ease: Real,
    /// Length of the sleeves from the shoulder joint along the arm (m).
    #[schemars(range(min = 0.1, max = 0.7))]
    pub sleeve_length: Real,
    /// Height of the hem below the hip (m; negative: above).
    #[schemars(range(min = -0.2, max = 0.05))]
    pub hem_below_hip: Real,
    /// Rounds of splitting each of the body's triangles into four (the mannequin's surface: about
    /// 3,600 triangles at 0, 14,400 at 1).
    #[schemars(range(min = 0, max = 3))]
    pub subdivisions: u32,
    /// Elastic bands (m): border loops lying within this distance of the body grip it; 0 = none.
    #[schemars(range(min = 0.0, max = 0.05))]
    pub band_gap: Real,
}

impl Default for ShirtSpec {
    fn default() -> Self {
        let d = ShirtParams::default();
        ShirtSpec {
            ease: d.ease.to_vec(),
            sleeve_ease: d.sleeve_ease,
            sleeve_length: d.sleeve_length,
            hem_below_hip: d.hem_below_hip,
            subdivisions: d.subdivisions,
            // The neckline grips as a rib band: without it the shirt slid off the shoulders.
            band_gap: 0.01,
        }
    }
}

/// A kimono (P2) fitted to the mannequin's height, bust, waist and hip (the blend of the flat
/// target shapes), put on the mannequin with its arms raised as the worn targets were, and tied;
/// the body lowers its arms over `lead` seconds before the motion starts.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct KimonoSpec {
    /// 裄 (back-neck centre to the wrist bone, m); absent, height x 0.4 + 0.02.
    #[schemars(range(min = 0.55, max = 0.7))]
    pub yuki: Option<Real>,
    /// 袖丈: the sleeve's length (m; at most 75% of the height); absent, height x 0.3.
    #[schemars(range(min = 0.35, max = 1.3))]
    pub sleeve_length: Option<Real>,
    /// Time the body takes to lower its arms from the pose the kimono was put on in (s).
    #[schemars(range(min = 0.1, max = 10.0))]
    pub lead: Real,
    /// Frames the cord holds the kimono on the mannequin after tying it, before the scene starts.
    #[schemars(range(max = 600))]
    pub hold_frames: usize,
    /// Tie a row 7 cm under the bust too (the datejime), so the fronts cross at the chest; off,
    /// they open in a V down to the cord.
    pub under_bust_tie: bool,
}

impl Default for KimonoSpec {
    fn default() -> Self {
        KimonoSpec {
            yuki: None,
            sleeve_length: None,
            lead: 1.0,
            hold_frames: 60,
            under_bust_tie: true,
        }
    }
}
