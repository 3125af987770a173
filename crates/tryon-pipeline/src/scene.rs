//! The scene file: TOML read through serde with unknown keys rejected, then every value checked
//! against its allowed range. Errors name the file, the line, the key and what is allowed.

use serde::Deserialize;
use std::path::{Path, PathBuf};
use thiserror::Error;
use tryon_core::math::Real;
use tryon_core::measure::Measurements;

mod check;

/// Why a scene file was rejected.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum SceneError {
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}:{line}:{column}: {message}", file.display())]
    Syntax {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{}:{}: `{key}` = {value}: expected {expected}", file.display(), line.map_or("?".to_string(), |l| l.to_string()))]
    Invalid {
        file: PathBuf,
        /// Line of the key, or of its table when the key was left out.
        line: Option<usize>,
        key: String,
        value: String,
        expected: String,
    },
}

/// How fast and how long the scene runs.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SceneSection {
    pub name: String,
    /// Output frames per second.
    pub fps: Real,
    /// Length of the run (s); when absent, the motion's length plus the settle time.
    pub duration: Option<Real>,
    /// Time the body holds its rest pose before the motion starts, letting the garment settle (s).
    pub settle: Real,
    /// Run frame n+1's coarse step and frame n's surface stages at the same time (two threads).
    pub pipelined: bool,
}

impl Default for SceneSection {
    fn default() -> Self {
        SceneSection {
            name: "scene".into(),
            fps: 30.0,
            duration: None,
            settle: 0.3,
            pipelined: false,
        }
    }
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum BodyKind {
    Mannequin,
    Sphere,
    /// MakeHuman's base mesh from the shared assets, morphed toward any measurements given.
    Makehuman,
    /// A rigid object from an OBJ file (`file`, `scale`), standing on a table (P4's scene).
    Object,
}

/// The rig that skins a MakeHuman body.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum RigName {
    /// MakeHuman's cmu_mb (31 bones, CMU names).
    CmuMb,
    /// MakeHuman's default rig (163 bones).
    Default,
}

/// The body: the parametric mannequin (measurements in metres), a MakeHuman body or a fixed sphere.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodySection {
    pub kind: BodyKind,
    /// MakeHuman: the skinning rig (default `cmu_mb`).
    pub rig: Option<RigName>,
    /// MakeHuman: 0 female ..= 1 male; 0.5 (the default) is the raw base mesh.
    pub gender: Option<Real>,
    pub height: Option<Real>,
    pub bust: Option<Real>,
    pub waist: Option<Real>,
    pub hip: Option<Real>,
    pub shoulder_width: Option<Real>,
    pub arm_length: Option<Real>,
    pub inseam: Option<Real>,
    /// Sphere radius (m).
    pub radius: Option<Real>,
    /// Sphere icosphere subdivisions.
    pub subdivisions: Option<u32>,
    /// Object: the OBJ file (relative to the scene file, else to the shared asset folder).
    pub file: Option<String>,
    /// Object: uniform scale from file units to metres (default 1).
    pub scale: Option<Real>,
    /// Object: side of the square table top it stands on, centred under it (m); 0 = no table.
    /// Default 1.5.
    pub table: Option<Real>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum GarmentKind {
    Dress,
    Skirt,
    /// A horizontal square sheet (the drape scene).
    Square,
    /// A MakeHuman garment (.mhclo binding and its OBJ) fitted onto the MakeHuman body.
    Mhclo,
}

/// The garment: a pattern sized from the body's measurements, or a square sheet.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GarmentSection {
    pub kind: GarmentKind,
    /// Ease at [bust, waist, hip] (dress) or [waist, hip] (skirt), m.
    pub ease: Option<Vec<Real>>,
    pub flare: Option<Real>,
    pub hem_above_knee: Option<Real>,
    pub columns: Option<usize>,
    pub row_spacing: Option<Real>,
    /// Square: particles per side, side length (m) and height above the origin (m).
    pub particles: Option<usize>,
    pub size: Option<Real>,
    pub drop_height: Option<Real>,
    /// Mhclo: the .mhclo file (relative to the scene file, else to the shared asset folder).
    pub file: Option<String>,
    /// Square: at the first key's time a kinematic handle grabs the particle then nearest the first
    /// point and moves it by the path's displacements, `[[t, x, y, z], ...]` (s, m), holding the
    /// last point (P4's user dragging the cloth).
    pub grab: Option<Vec<[Real; 4]>>,
    /// Elastic bands (m): border loops lying within this distance of the body when fitted (90% of
    /// their vertices) grip it and move with it, as a waistband, collar or cuff does. 0 turns them
    /// off. Default 0.006 for `mhclo` garments, 0 for the patterns.
    pub band_gap: Option<Real>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MotionKind {
    Still,
    Walk,
    ArmRaise,
    /// A BVH clip retargeted onto the body's skeleton (P1.6).
    Bvh,
}

/// The motion driving the body.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MotionSection {
    pub kind: MotionKind,
    /// Clip length (s) for `still` and `walk`.
    pub duration: Option<Real>,
    pub period: Option<Real>,
    pub hip_deg: Option<Real>,
    pub knee_deg: Option<Real>,
    pub arm_deg: Option<Real>,
    pub raise_deg: Option<Real>,
    /// Bvh: the clip (relative to the scene file, else to the shared asset folder).
    pub file: Option<String>,
    /// Bvh: seconds of the clip to skip.
    pub start: Option<Real>,
    /// Bvh: blend-in time from the rest pose (s).
    pub ease_in: Option<Real>,
    /// Bvh: metres per file unit (guessed from the figure's size when absent).
    pub unit: Option<Real>,
}

impl Default for MotionSection {
    fn default() -> Self {
        MotionSection {
            kind: MotionKind::Still,
            duration: None,
            period: None,
            hip_deg: None,
            knee_deg: None,
            arm_deg: None,
            raise_deg: None,
            file: None,
            start: None,
            ease_in: None,
            unit: None,
        }
    }
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorName {
    Rk4,
    SymplecticEuler,
    /// Baraff and Witkin's linearised backward Euler, solved by conjugate gradients.
    ImplicitEuler,
}

/// Which material the garment's resolution sets the defaults from.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MaterialName {
    /// Garments (P1): asymmetric springs, flexion springs with the bending limit, Provot's limit at
    /// 1.03 (over-relaxed).
    #[default]
    Garment,
    /// A flat sheet (the drape fixture's material): Bergou et al.'s quadratic bending, which
    /// assumes a flat rest shape, and the strain limit at rest length with long-range lines. Only
    /// for `kind = "square"`.
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

/// Cloth material and solver settings; absent values take the garment's defaults.
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ClothSection {
    pub integrator: Option<IntegratorName>,
    /// Material defaults ("garment" unless set).
    pub material: Option<MaterialName>,
    /// Largest substep (s).
    pub substep: Option<Real>,
    /// kg/m^2.
    pub density: Option<Real>,
    /// Spring stiffness in N/m for the whole garment (scaled per spring by the solver's model).
    pub k_stretch: Option<Real>,
    pub k_compress: Option<Real>,
    pub k_shear: Option<Real>,
    pub k_bend: Option<Real>,
    pub spring_damping: Option<Real>,
    /// Provot's strain limit (1.0 < x); 0 turns it off.
    pub max_strain: Option<Real>,
    pub strain_iterations: Option<u32>,
    /// Quality guard: a substep that stretches a structural edge past this ratio of its rest length
    /// is retried at half the step; 0 turns it off.
    pub stretch_guard: Option<Real>,
    /// Distance the cloth keeps from the body (m).
    pub thickness: Option<Real>,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CollisionMethod {
    /// P1's nearest-vertex tracking.
    NearestVertex,
    /// Closest point on the whole mesh (parry): the referee, slow but exact.
    Exact,
    /// P3's signed distance grid (trilinear), rebuilt when the body moves.
    Sdf,
    /// P4's six-view depth and normal maps, re-rendered when the body moves.
    DepthMaps,
    None,
}

impl CollisionMethod {
    /// The name the scene file uses.
    pub fn as_str(self) -> &'static str {
        match self {
            CollisionMethod::NearestVertex => "nearest_vertex",
            CollisionMethod::Exact => "exact",
            CollisionMethod::Sdf => "sdf",
            CollisionMethod::DepthMaps => "depth_maps",
            CollisionMethod::None => "none",
        }
    }
}

/// Which effects act. A disabled effect is not assembled at all.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EffectsSection {
    pub gravity: bool,
    /// Air drag coefficient (N s/m^3 per unit area); 0 turns drag off.
    pub air_drag: Real,
    /// Wind velocity (m/s); only acts through air drag.
    pub wind: [Real; 3],
    /// Coulomb friction coefficient at body contacts; 0 turns friction off.
    pub friction: Real,
    pub body_collision: CollisionMethod,
    /// Collider of the fine surface (P1.4.2); the body collider's method when absent (`none` is
    /// not allowed: turn `fine_collision` off instead).
    pub fine_collider: Option<CollisionMethod>,
    /// Grid cells along the body's longest side for `sdf`.
    pub sdf_resolution: usize,
    /// Pixels along the body's longest side for `depth_maps`.
    pub depth_resolution: usize,
    /// P1.3.4: carry the cloth with the moving body.
    pub follow_body: bool,
    /// Velocity damping (1/s); 0 turns it off.
    pub velocity_damping: Real,
    /// P1.4.1: PN-triangle refinement level, 2^level segments per coarse edge; 0 = the coarse
    /// mesh is the output (and no surface stage runs).
    pub refine: u8,
    /// P1.4.2: raise fine vertices out of the body (when refine > 0 and the body collides).
    pub fine_collision: bool,
    /// P1.4.3: the wrinkle model (when refine > 0).
    pub wrinkles: bool,
    /// P1.4.4: blend normals by wrinkle height (when refine > 0 and wrinkles or fine collision run).
    pub blend_normals: bool,
    /// k_out-plane of P1 eqs. 10 and 12 (m/N).
    pub k_out_plane: Real,
    /// Height at which the deformed surface's normal takes over (m), P1 eq. 13.
    pub h_normal: Real,
    /// Distance fine vertices keep from the body (m).
    pub fine_skin: Real,
    /// Fine vertices within this distance of the body count as touching it (m).
    pub fine_margin: Real,
    /// Longest a fine edge may get through wrinkle height differences, over its reference length.
    pub max_fine_stretch: Real,
}

impl Default for EffectsSection {
    fn default() -> Self {
        EffectsSection {
            gravity: true,
            air_drag: 0.0,
            wind: [0.0; 3],
            friction: 0.5,
            body_collision: CollisionMethod::NearestVertex,
            fine_collider: None,
            sdf_resolution: 64,
            depth_resolution: 256,
            follow_body: true,
            velocity_damping: 0.2,
            refine: 0,
            fine_collision: true,
            wrinkles: false,
            blend_normals: true,
            k_out_plane: 1.0,
            h_normal: 0.005,
            fine_skin: 0.001,
            fine_margin: 0.01,
            max_fine_stretch: 1.25,
        }
    }
}

/// What to write.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSection {
    pub glb: bool,
    pub preview: bool,
    pub stats: bool,
    /// Frame drawn in the preview; the last frame when absent.
    pub preview_frame: Option<usize>,
    pub preview_width: u32,
    pub preview_height: u32,
}

impl Default for OutputSection {
    fn default() -> Self {
        OutputSection {
            glb: true,
            preview: true,
            stats: true,
            preview_frame: None,
            preview_width: 800,
            preview_height: 1000,
        }
    }
}

/// A scene as written in its file.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    #[serde(default)]
    pub scene: SceneSection,
    pub body: BodySection,
    pub garment: GarmentSection,
    #[serde(default)]
    pub motion: MotionSection,
    #[serde(default)]
    pub cloth: ClothSection,
    #[serde(default)]
    pub effects: EffectsSection,
    #[serde(default)]
    pub output: OutputSection,
    /// The file the scene was read from (asset paths are resolved beside it).
    #[serde(skip)]
    pub source: Option<PathBuf>,
}

/// The embedded default scene (`tryon demo`): the mannequin in the dress, walking.
pub const DEMO_SCENE: &str = include_str!("../../../data/scenes/demo-dress-walk.toml");

/// Line (1-based) and column of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

/// Line of `key` inside `[table]` (or of the table header when the key is absent).
pub fn line_of(text: &str, table: &str, key: &str) -> Option<usize> {
    let mut current = String::new();
    let mut header = None;
    for (i, raw) in text.lines().enumerate() {
        let l = raw.trim();
        if let Some(name) = l.strip_prefix('[').and_then(|s| s.strip_suffix(']')) {
            current = name.trim().to_string();
            if current == table {
                header = Some(i + 1);
            }
            continue;
        }
        if current == table
            && let Some((k, _)) = l.split_once('=')
            && k.trim() == key
        {
            return Some(i + 1);
        }
    }
    header
}

impl Scene {
    /// Parses and checks a scene; `file` names it in errors.
    pub fn parse(text: &str, file: &Path) -> Result<Scene, SceneError> {
        let scene: Scene = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((0, 0), |s| line_col(text, s.start));
            SceneError::Syntax {
                file: file.to_path_buf(),
                line,
                column,
                message: e.message().to_string(),
            }
        })?;
        scene.check(text, file)?;
        Ok(scene)
    }

    /// Reads, parses and checks a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut scene = Scene::parse(&text, path)?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// Parses a scene with `table.key=value` overrides applied first (the value in TOML syntax; a
    /// bare word is taken as a string), as `tryon run --set` does. Errors name the override.
    pub fn parse_with_overrides(
        text: &str,
        file: &Path,
        sets: &[String],
    ) -> Result<Scene, SceneError> {
        if sets.is_empty() {
            return Scene::parse(text, file);
        }
        let mut table: toml::Table = toml::from_str(text).map_err(|e| {
            let (line, column) = e.span().map_or((0, 0), |s| line_col(text, s.start));
            SceneError::Syntax {
                file: file.to_path_buf(),
                line,
                column,
                message: e.message().to_string(),
            }
        })?;
        for set in sets {
            let bad = |expected: &str| SceneError::Invalid {
                file: file.to_path_buf(),
                line: None,
                key: "--set".into(),
                value: set.clone(),
                expected: expected.into(),
            };
            let (key, value) = set.split_once('=').ok_or_else(|| bad("table.key=value"))?;
            let (t, k) = key
                .trim()
                .split_once('.')
                .ok_or_else(|| bad("table.key=value (for example effects.refine=2)"))?;
            let value = value.trim();
            let parsed = toml::from_str::<toml::Table>(&format!("v = {value}"))
                .ok()
                .and_then(|mut v| v.remove("v"))
                .unwrap_or_else(|| toml::Value::String(value.to_string()));
            let entry = table
                .entry(t.to_string())
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let toml::Value::Table(section) = entry else {
                return Err(bad("a key inside a [table]"));
            };
            section.insert(k.to_string(), parsed);
        }
        let merged = toml::to_string(&table).map_err(|e| SceneError::Syntax {
            file: file.to_path_buf(),
            line: 0,
            column: 0,
            message: e.to_string(),
        })?;
        let named = PathBuf::from(format!(
            "{} (with --set {})",
            file.display(),
            sets.join(" ")
        ));
        Scene::parse(&merged, &named)
    }

    /// Reads a scene file and applies `table.key=value` overrides.
    pub fn load_with_overrides(path: &Path, sets: &[String]) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut scene = Scene::parse_with_overrides(&text, path, sets)?;
        scene.source = Some(path.to_path_buf());
        Ok(scene)
    }

    /// The scene's body measurements, defaults filled in.
    pub fn measurements(&self) -> Measurements {
        let d = Measurements::default();
        let b = &self.body;
        Measurements {
            height: b.height.unwrap_or(d.height),
            bust: b.bust.unwrap_or(d.bust),
            waist: b.waist.unwrap_or(d.waist),
            hip: b.hip.unwrap_or(d.hip),
            shoulder_width: b.shoulder_width.unwrap_or(d.shoulder_width),
            arm_length: b.arm_length.unwrap_or(d.arm_length),
            inseam: b.inseam.unwrap_or(d.inseam),
        }
    }

    /// The embedded demo scene.
    pub fn demo() -> Scene {
        Scene::parse(DEMO_SCENE, Path::new("<embedded demo-dress-walk.toml>"))
            .unwrap_or_else(|e| unreachable!("the embedded demo scene is checked by tests: {e}"))
    }
}
