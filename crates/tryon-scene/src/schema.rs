//! The scene schema: one struct per table, and for `[body]`, `[garment]` and `[motion]` one
//! variant per `kind`, each owning only its keys. Defaults come from the stage that uses the value
//! (measurements from tryon-core, patterns from garment-fit, clips from mocap-retarget, material
//! and environment from cloth-dyn, surface detail from wrinkle, resolutions from body-collide);
//! allowed ranges are `schemars` attributes, read by the checks and by the generated reference
//! (docs/scenes.md), so the two cannot disagree.

use mocap_retarget::{ArmRaise, RetargetOptions, WalkParams};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use tryon_core::math::Real;
use tryon_core::measure::Measurements;

pub use super::patterns::{DressSpec, KimonoSpec, ShirtSpec, SkirtSpec};

/// How fast and how long the scene runs.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SceneSection {
    /// The scene's name: stats.json and the default output folder `out/<name>`.
    pub name: String,
    /// Output frames per second.
    #[schemars(range(min = 1.0, max = 1000.0))]
    pub fps: Real,
    /// Length of the run (s); when absent, the motion's length plus the settle time.
    #[schemars(range(min = 0.0, max = 3600.0))]
    pub duration: Option<Real>,
    /// Time the body holds its rest pose before the motion starts, letting the garment settle (s).
    #[schemars(range(min = 0.0, max = 60.0))]
    pub settle: Real,
    /// Run frame n+1's coarse step and frame n's surface stages at the same time (two threads;
    /// the same frames).
    pub pipelined: bool,
    /// Farthest a body vertex may move between two collision updates (m): a frame in which the
    /// body moves farther is stepped in sub-frames, the body posed between the frames; 0 = one
    /// update per frame.
    #[schemars(range(min = 0.0, max = 1.0))]
    pub body_step: Real,
}

impl Default for SceneSection {
    fn default() -> Self {
        SceneSection {
            name: "scene".into(),
            fps: 30.0,
            duration: None,
            settle: 0.3,
            pipelined: false,
            body_step: crate::BODY_STEP,
        }
    }
}

/// The body the garment is worn on.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum BodySection {
    /// The parametric mannequin, built from body measurements (m).
    Mannequin(MannequinBody),
    /// A fixed sphere at the origin (the drape test).
    Sphere(SphereBody),
    /// MakeHuman's base mesh from the shared assets, morphed toward any measurements given.
    Makehuman(MakeHumanSpec),
    /// A rigid object from an OBJ file standing on a table (P4's scene).
    Object(ObjectBody),
}

/// The mannequin's measurements (m); the body-model's defaults.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct MannequinBody {
    /// Standing height (m).
    #[schemars(range(min = 1.2, max = 2.2))]
    pub height: Real,
    /// Bust girth (m).
    #[schemars(range(min = 0.5, max = 1.8))]
    pub bust: Real,
    /// Waist girth (m).
    #[schemars(range(min = 0.4, max = 1.6))]
    pub waist: Real,
    /// Hip girth (m).
    #[schemars(range(min = 0.5, max = 1.8))]
    pub hip: Real,
    /// Shoulder width (m).
    #[schemars(range(min = 0.25, max = 0.6))]
    pub shoulder_width: Real,
    /// Arm length (m).
    #[schemars(range(min = 0.35, max = 0.85))]
    pub arm_length: Real,
    /// Inseam (m).
    #[schemars(range(min = 0.5, max = 1.1))]
    pub inseam: Real,
}

impl Default for MannequinBody {
    fn default() -> Self {
        MannequinBody::from(Measurements::default())
    }
}

impl From<Measurements> for MannequinBody {
    fn from(m: Measurements) -> Self {
        MannequinBody {
            height: m.height,
            bust: m.bust,
            waist: m.waist,
            hip: m.hip,
            shoulder_width: m.shoulder_width,
            arm_length: m.arm_length,
            inseam: m.inseam,
        }
    }
}

impl MannequinBody {
    pub fn measurements(&self) -> Measurements {
        Measurements {
            height: self.height,
            bust: self.bust,
            waist: self.waist,
            hip: self.hip,
            shoulder_width: self.shoulder_width,
            arm_length: self.arm_length,
            inseam: self.inseam,
        }
    }
}

/// A fixed sphere.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SphereBody {
    /// Radius (m).
    #[schemars(range(min = 0.01, max = 5.0))]
    pub radius: Real,
    /// Icosphere subdivisions (10 * 4^n + 2 vertices).
    #[schemars(range(max = 6))]
    pub subdivisions: u32,
}

impl Default for SphereBody {
    fn default() -> Self {
        SphereBody {
            radius: 0.3,
            subdivisions: 4,
        }
    }
}

/// The rig that skins a MakeHuman body.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RigName {
    /// MakeHuman's cmu_mb (31 bones, CMU names).
    #[default]
    CmuMb,
    /// MakeHuman's default rig (163 bones).
    Default,
}

/// A MakeHuman body; measurements left out keep the base mesh's.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct MakeHumanSpec {
    /// The skinning rig.
    pub rig: RigName,
    /// 0 female ..= 1 male; 0.5 is the raw base mesh.
    #[schemars(range(min = 0.0, max = 1.0))]
    pub gender: Real,
    /// Standing height to scale to (m).
    #[schemars(range(min = 1.2, max = 2.2))]
    pub height: Option<Real>,
    /// Bust girth to morph toward (m).
    #[schemars(range(min = 0.5, max = 1.8))]
    pub bust: Option<Real>,
    /// Waist girth to morph toward (m).
    #[schemars(range(min = 0.4, max = 1.6))]
    pub waist: Option<Real>,
    /// Hip girth to morph toward (m).
    #[schemars(range(min = 0.5, max = 1.8))]
    pub hip: Option<Real>,
}

impl Default for MakeHumanSpec {
    fn default() -> Self {
        MakeHumanSpec {
            rig: RigName::default(),
            gender: body_model::makehuman::NEUTRAL_GENDER,
            height: None,
            bust: None,
            waist: None,
            hip: None,
        }
    }
}

/// A rigid object on a table.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ObjectBody {
    /// The OBJ file (relative to the scene file, else to the shared asset folder).
    pub file: String,
    /// Uniform scale from file units to metres.
    #[serde(default = "one")]
    #[schemars(range(min = 1e-4, max = 1e4))]
    pub scale: Real,
    /// Side of the square table top it stands on, centred under it (m); 0 = no table.
    #[serde(default = "table_side")]
    #[schemars(range(min = 0.0, max = 20.0))]
    pub table: Real,
}

fn one() -> Real {
    1.0
}

fn table_side() -> Real {
    1.5
}

/// The garment.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum GarmentSection {
    /// A dress cut from the mannequin's measurements.
    Dress(DressSpec),
    /// A skirt cut from the mannequin's measurements.
    Skirt(SkirtSpec),
    /// A short-sleeved shirt cut from the mannequin's own surface.
    Shirt(ShirtSpec),
    /// A horizontal square sheet (the drape and P4's scene).
    Square(SquareSpec),
    /// A MakeHuman garment (.mhclo binding and its OBJ) fitted onto the MakeHuman body.
    Mhclo(MhcloSpec),
    /// A kimono (P2) fitted to the mannequin's measurements.
    Kimono(KimonoSpec),
}

/// How one garment is worn among several (`[[garment]]`): its layer and its own material. Every
/// kind of garment takes these keys.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct WearSpec {
    /// Layer order, the body's skin being below 0: a garment of a higher layer is worn over one
    /// of a lower (placed outside it, and pulled out where they cross at the start); absent, the
    /// order the garments are listed in.
    #[schemars(range(min = 0, max = 15))]
    pub layer: Option<u32>,
    /// This garment's areal density (kg/m^2); absent, `cloth.density`.
    #[schemars(range(min = 0.001, max = 10.0))]
    pub density: Option<Real>,
    /// This garment's stiffness (its stretch, shear and flexion springs) as a multiple of the
    /// cloth's.
    #[schemars(range(min = 0.01, max = 100.0))]
    pub stiffness: Real,
}

impl Default for WearSpec {
    fn default() -> Self {
        WearSpec {
            layer: None,
            density: None,
            stiffness: 1.0,
        }
    }
}

impl WearSpec {
    /// The keys every garment kind takes.
    pub const KEYS: [&'static str; 3] = ["layer", "density", "stiffness"];
}

/// A square sheet.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SquareSpec {
    /// Particles per side.
    #[schemars(range(min = 2, max = 256))]
    pub particles: usize,
    /// Side length (m).
    #[schemars(range(min = 0.05, max = 10.0))]
    pub size: Real,
    /// Height above the origin (m).
    #[schemars(range(min = -10.0, max = 10.0))]
    pub drop_height: Real,
    /// At the first key's time a handle grabs the particle then nearest the first point and moves
    /// it by the path's displacements, `[[t, x, y, z], ...]` (s, m), holding the last point (P4's
    /// user dragging the cloth).
    pub grab: Option<Vec<Vec<Real>>>,
}

impl Default for SquareSpec {
    fn default() -> Self {
        SquareSpec {
            particles: 32,
            size: 1.0,
            drop_height: 0.5,
            grab: None,
        }
    }
}

/// A MakeHuman garment.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MhcloSpec {
    /// The .mhclo file (relative to the scene file, else to the shared asset folder).
    pub file: String,
    /// Elastic bands (m): border loops lying within this distance of the body when fitted (90% of
    /// their vertices) grip it and move with it, as a waistband, collar or cuff does; 0 = none.
    #[serde(default = "modelled_band_gap")]
    #[schemars(range(min = 0.0, max = 0.05))]
    pub band_gap: Real,
    /// Waists held as a belt holds them (m): of each piece that does not reach the shoulders
    /// (trousers, shorts, a skirt), its highest border loop grips the body where it was fitted
    /// when 90% of it lies within this distance of the body; 0 = none.
    #[serde(default = "modelled_waist_gap")]
    #[schemars(range(min = 0.0, max = 0.1))]
    pub waist_gap: Real,
    /// Closures (fraction of the median edge): border vertices the modeller left touching, as a
    /// buttoned front or a shut slit, closer than this are sewn together, where they form a seam of
    /// at least two pairs; 0 = none.
    #[serde(default = "closure_gap")]
    #[schemars(range(min = 0.0, max = 2.0))]
    pub closures: Real,
}

fn closure_gap() -> Real {
    garment_fit::close::MODELLED_CLOSURE_GAP
}

fn modelled_waist_gap() -> Real {
    garment_fit::bands::MODELLED_WAIST_GAP
}

fn modelled_band_gap() -> Real {
    garment_fit::bands::MODELLED_BAND_GAP
}

/// The motion driving the body.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(rename_all = "snake_case")]
pub enum MotionSection {
    /// The body holds its rest pose.
    Still(StillSpec),
    /// The built-in walk (the mannequin).
    Walk(WalkSpec),
    /// Both arms raised sideways (the mannequin).
    ArmRaise(ArmRaiseSpec),
    /// A BVH clip retargeted onto the body's skeleton (P1.6).
    Bvh(BvhSpec),
}

impl Default for MotionSection {
    fn default() -> Self {
        MotionSection::Still(StillSpec::default())
    }
}

/// Holding still.
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct StillSpec {
    /// Length of the clip (s): 2, or 3 for an object body, when absent.
    #[schemars(range(min = 0.0, max = 3600.0))]
    pub duration: Option<Real>,
}

/// The walk; mocap-retarget's defaults.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct WalkSpec {
    /// Length of the clip (s).
    #[schemars(range(min = 0.0, max = 3600.0))]
    pub duration: Real,
    /// Stride period (s).
    #[schemars(range(min = 0.3, max = 5.0))]
    pub period: Real,
    /// Hip flexion amplitude (degrees).
    #[schemars(range(min = 0.0, max = 60.0))]
    pub hip_deg: Real,
    /// Knee flexion in swing (degrees).
    #[schemars(range(min = 0.0, max = 120.0))]
    pub knee_deg: Real,
    /// Arm swing amplitude (degrees).
    #[schemars(range(min = 0.0, max = 60.0))]
    pub arm_deg: Real,
}

impl Default for WalkSpec {
    fn default() -> Self {
        let d = WalkParams::default();
        WalkSpec {
            duration: d.duration,
            period: d.period,
            hip_deg: d.hip_deg,
            knee_deg: d.knee_deg,
            arm_deg: d.arm_deg,
        }
    }
}

/// Raising the arms.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ArmRaiseSpec {
    /// How far the arms rise from the rest pose (degrees).
    #[schemars(range(min = 0.0, max = 150.0))]
    pub raise_deg: Real,
    /// How far the elbows bend at the top (degrees); absent, 15% of `raise_deg`.
    #[schemars(range(min = 0.0, max = 150.0))]
    pub elbow_deg: Option<Real>,
}

impl Default for ArmRaiseSpec {
    fn default() -> Self {
        ArmRaiseSpec {
            raise_deg: ArmRaise::DEFAULT_DEG,
            elbow_deg: None,
        }
    }
}

/// A BVH clip; mocap-retarget's defaults.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BvhSpec {
    /// The clip (relative to the scene file, else to the shared asset folder).
    pub file: String,
    /// Seconds of the clip to skip.
    #[serde(default = "bvh_start")]
    #[schemars(range(min = 0.0, max = 3600.0))]
    pub start: Real,
    /// Seconds of the clip to use; to its end when absent.
    #[serde(default)]
    #[schemars(range(min = 0.0, max = 3600.0))]
    pub duration: Option<Real>,
    /// Blend-in time from the rest pose (s).
    #[serde(default = "bvh_ease_in")]
    #[schemars(range(min = 0.0, max = 10.0))]
    pub ease_in: Real,
    /// Metres per file unit; guessed from the figure's size when absent.
    #[serde(default)]
    #[schemars(range(min = 1e-4, max = 10.0))]
    pub unit: Option<Real>,
    /// Arms are opened sideways, frame by frame and smoothly, until the elbow, wrist and hand
    /// joints lie at least this far (m) outside the body's rest shape (a source whose hips are
    /// narrower than the body's would hang the hands inside the hips), and a hand raised to the
    /// face is swung away from the head until the wrist is 3 cm and the fingertips 1.5 cm off it;
    /// 0 = off.
    #[serde(default = "bvh_arm_clearance")]
    #[schemars(range(min = 0.0, max = 0.2))]
    pub arm_clearance: Real,
    /// Playback speed: 2 plays the clip twice as fast (`start` and `duration` are then in seconds
    /// of the faster clip). The hard cases replay clips at 3x to test tunnelling.
    #[serde(default = "bvh_speed")]
    #[schemars(range(min = 0.1, max = 10.0))]
    pub speed: Real,
    /// Fastest a joint may turn (degrees per second): faster turns in the data (a glitch: 131_01's
    /// right wrist spins 7,760 degrees per second for two frames) are cut to this; 0 = no limit.
    #[serde(default = "bvh_max_turn")]
    #[schemars(range(min = 0.0, max = 100000.0))]
    pub max_turn: Real,
}

fn bvh_speed() -> Real {
    1.0
}

fn bvh_max_turn() -> Real {
    mocap_retarget::turns::DEFAULT_LIMIT_DEG_PER_S
}

fn bvh_arm_clearance() -> Real {
    mocap_retarget::clearance::DEFAULT_MARGIN
}

fn bvh_start() -> Real {
    RetargetOptions::default().start
}

fn bvh_ease_in() -> Real {
    RetargetOptions::default().ease_in
}

/// The coarse cloth's integrator.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorName {
    /// Classical Runge-Kutta (P1).
    #[default]
    Rk4,
    SymplecticEuler,
    /// Baraff and Witkin's linearised backward Euler, solved by conjugate gradients.
    ImplicitEuler,
}

/// Which material preset the garment's resolution sets the defaults from.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MaterialName {
    /// Garments (P1): asymmetric springs, flexion springs with the bending limit, Provot's limit
    /// at 1.03 (over-relaxed).
    #[default]
    Garment,
    /// A flat sheet (the drape fixture's material): Bergou et al.'s quadratic bending and the
    /// strain limit at rest length with long-range lines. Only for `kind = "square"`.
    Sheet,
}

impl MaterialName {
    /// The name the scene file uses.
    pub fn as_str(self) -> &'static str {
        match self {
            MaterialName::Garment => "garment",
            MaterialName::Sheet => "sheet",
        }
    }
}
