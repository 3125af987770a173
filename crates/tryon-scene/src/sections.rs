//! The flat tables of the scene schema: `[cloth]` (overrides of the material preset), `[effects]`
//! (what acts, and the surface detail's parameters) and `[output]`.

use super::schema::{IntegratorName, MaterialName};
use cloth_dyn::presets::{self, Environment};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use tryon_core::math::Real;

/// Cloth material and solver settings; absent values take the material preset's, scaled to the
/// garment's resolution. Each solver's own settings are its table: `[cloth.p1]`, `[cloth.vbd]`,
/// `[cloth.xpbd]`.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct ClothSection {
    /// The garment solver.
    pub solver: SolverName,
    /// The material preset.
    pub material: MaterialName,
    /// Area density (kg/m^2).
    #[schemars(range(min = 1e-3, max = 10.0))]
    pub density: Real,
    /// Stretch stiffness (N/m per unit strain) for the whole garment.
    #[schemars(range(min = 0.0, max = 1e9))]
    pub k_stretch: Option<Real>,
    /// Compression stiffness (N/m), P1's soft side of eq. 1.
    #[schemars(range(min = 0.0, max = 1e9))]
    pub k_compress: Option<Real>,
    /// Shear stiffness (N/m).
    #[schemars(range(min = 0.0, max = 1e9))]
    pub k_shear: Option<Real>,
    /// Bending (flexion spring) stiffness (N/m).
    #[schemars(range(min = 0.0, max = 1e9))]
    pub k_bend: Option<Real>,
    /// Spring damping (N s/m).
    #[schemars(range(min = 0.0, max = 1e9))]
    pub spring_damping: Option<Real>,
    /// Rest lengths as a share of the modelled ones (below 1 the garment is worn under tension;
    /// the preset's when absent: 0.95 for .mhclo garments with `p1`, 1 otherwise).
    #[schemars(range(min = 0.5, max = 1.5))]
    pub rest_scale: Option<Real>,
    /// Distance the cloth keeps from the body (m).
    #[schemars(range(min = 0.0, max = 0.05))]
    pub thickness: Real,
    /// Distance the cloth keeps from itself with `effects.self_collision` (m).
    #[schemars(range(min = 1e-4, max = 0.02))]
    pub self_thickness: Real,
    /// How self-contact finds candidate pairs: `tree` (bounding volume hierarchies refitted
    /// each step) or `hash` (a spatial hash rebuilt each step); the results agree, the tree is
    /// faster (docs/decisions, *self contact*).
    pub self_broad_phase: BroadPhaseName,
    /// The `p1` solver's settings.
    pub p1: P1Section,
    /// The `vbd` solver's settings.
    pub vbd: cloth_dyn::VbdParams,
    /// The `xpbd` solver's settings.
    pub xpbd: cloth_dyn::XpbdParams,
}

/// The `p1` solver's settings (`[cloth.p1]`); absent values take the material preset's.
#[derive(Clone, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct P1Section {
    /// The integrator.
    pub integrator: IntegratorName,
    /// Largest substep (s); the preset's stability bound when absent.
    #[schemars(range(min = 1e-5, max = 0.1))]
    pub substep: Option<Real>,
    /// Provot's strain limit, a ratio in [1, 2]; 0 turns it off.
    pub max_strain: Option<Real>,
    /// Passes of the strain limit per substep.
    #[schemars(range(max = 100))]
    pub strain_iterations: Option<u32>,
    /// Quality guard: a substep that stretches a structural edge past this ratio of its rest
    /// length is retried at half the step, a ratio in (1, 10]; 0 turns it off.
    pub stretch_guard: Option<Real>,
}

/// A broad phase of self-contact.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum BroadPhaseName {
    /// Bounding volume hierarchies over triangles and edges, refitted each step.
    #[default]
    Tree,
    /// A spatial hash of the triangles, rebuilt each step.
    Hash,
}

impl Default for ClothSection {
    fn default() -> Self {
        ClothSection {
            solver: SolverName::default(),
            material: MaterialName::default(),
            density: presets::DENSITY,
            k_stretch: None,
            k_compress: None,
            k_shear: None,
            k_bend: None,
            spring_damping: None,
            rest_scale: None,
            thickness: presets::THICKNESS,
            self_thickness: cloth_dyn::self_contact::SelfParams::default().thickness,
            self_broad_phase: BroadPhaseName::default(),
            p1: P1Section::default(),
            vbd: cloth_dyn::VbdParams::default(),
            xpbd: cloth_dyn::XpbdParams::default(),
        }
    }
}

/// Where wrinkle heights come from (`wrinkle::WrinkleModel`).
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum WrinkleModelName {
    /// P1.4.3 as written: heights driven by the coarse elastic forces (eqs. 4-12).
    Force,
    /// Stripes across each region's compression direction, as high as gives the lost length back.
    #[default]
    Compression,
}

impl From<WrinkleModelName> for wrinkle::WrinkleModel {
    fn from(m: WrinkleModelName) -> Self {
        match m {
            WrinkleModelName::Force => wrinkle::WrinkleModel::Force,
            WrinkleModelName::Compression => wrinkle::WrinkleModel::Compression,
        }
    }
}

/// The garment solver. Adding one: its settings table in [`ClothSection`], a variant here (and
/// in [`SolverName::ALL`] and its methods) and its arm in `build::solver`.
#[derive(Clone, Copy, Debug, Default, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SolverName {
    /// P1's sparse-particle cloth (cloth-dyn's `ClothSim`): springs integrated by `integrator`,
    /// Provot's strain limit, collision and friction between substeps.
    P1,
    /// Extended position-based dynamics with small substeps (cloth-dyn's `XpbdSim`): distance
    /// and dihedral constraints with compliance, body contact and friction inside every substep.
    Xpbd,
    /// Vertex block descent (cloth-dyn's `VbdSim`): the implicit step's energy (inertia, springs,
    /// body contact with friction) minimised vertex by vertex, colour by colour. The default
    /// (docs/decisions, *solver: vbd*).
    #[default]
    Vbd,
}

impl SolverName {
    /// Every solver: the reference, the budget and the tradeoff sweeps take them from here.
    pub const ALL: [SolverName; 3] = [SolverName::P1, SolverName::Xpbd, SolverName::Vbd];

    /// The name the scene file uses (also its settings table's, `[cloth.NAME]`).
    pub fn as_str(self) -> &'static str {
        match self {
            SolverName::P1 => "p1",
            SolverName::Xpbd => "xpbd",
            SolverName::Vbd => "vbd",
        }
    }

    /// Passes over the cloth per substep, as the budget counts them.
    pub fn iterations(self, c: &ClothSection) -> usize {
        match self {
            SolverName::P1 => 1,
            SolverName::Xpbd => c.xpbd.iterations as usize,
            SolverName::Vbd => c.vbd.iterations as usize,
        }
    }

    /// What to change when a frame would take too many substeps.
    pub fn substep_hint(self) -> &'static str {
        match self {
            SolverName::P1 => {
                "P1's stable substep shrinks as the stiffnesses (cloth.k_*) and cloth.spring_damping grow: lower them, or use cloth.solver = \"vbd\" (stable at any stiffness)"
            }
            SolverName::Xpbd => "raise cloth.xpbd.substep",
            SolverName::Vbd => "raise cloth.vbd.substep",
        }
    }
}

/// A way of colliding with the body. Adding one: a variant here and its arm in
/// `build::collider`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CollisionMethod {
    /// P1's nearest-vertex tracking.
    NearestVertex,
    /// Closest point on the whole mesh (parry), as the referee judges: the default
    /// (docs/decisions, *collider: exact on real scenes*).
    Exact,
    /// P3's signed distance grid (trilinear), rebuilt when the body moves.
    Sdf,
    /// P4's six-view depth and normal maps, re-rendered when the body moves.
    DepthMaps,
    /// No collision.
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
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct EffectsSection {
    /// Gravity.
    pub gravity: bool,
    /// Air drag coefficient (N s/m^3 per unit area); 0 turns drag off.
    #[schemars(range(min = 0.0, max = 100.0))]
    pub air_drag: Real,
    /// Wind velocity (m/s); only acts through air drag.
    #[schemars(length(equal = 3), inner(range(min = -100.0, max = 100.0)))]
    pub wind: Vec<Real>,
    /// Coulomb friction coefficient at body contacts; 0 turns friction off.
    #[schemars(range(min = 0.0, max = 5.0))]
    pub friction: Real,
    /// How the cloth collides with the body (`nearest_vertex` is P1's, cheaper on the
    /// mannequin).
    pub body_collision: CollisionMethod,
    /// Collider of the fine surface (P1.4.2); the body collider's method when absent (`none` is
    /// not allowed: turn `fine_collision` off instead).
    pub fine_collider: Option<CollisionMethod>,
    /// P1.3.4: carry the cloth with the moving body.
    pub follow_body: bool,
    /// Press a skinned body's parts apart where they meet in a pose (an arm against the chest,
    /// thighs together), leaving two cloth thicknesses between them, as flesh gives way; off,
    /// the parts pass into each other as linear blend skinning puts them.
    pub body_press: bool,
    /// The cloth's contact with itself (the `vbd` solver): layers and folds keep
    /// `cloth.self_thickness` apart and never pass through each other where they were apart in
    /// the modelled shape; friction between layers is `friction`.
    pub self_collision: bool,
    /// Contact between garments (the `vbd` solver), with several `[[garment]]`: each keeps
    /// `cloth.self_thickness` from the others, the outer never passing through the inner.
    pub cloth_collision: bool,
    /// Velocity damping (1/s); 0 turns it off.
    #[schemars(range(min = 0.0, max = 100.0))]
    pub velocity_damping: Real,
    /// P1.4.1: PN-triangle refinement level, 2^level segments per coarse edge; 0 = the coarse
    /// mesh is the output (and no surface stage runs).
    #[schemars(range(max = 4))]
    pub refine: u8,
    /// P1.4.2: raise fine vertices out of the body (when refine > 0 and the body collides).
    pub fine_collision: bool,
    /// P1.4.3: the wrinkle model (when refine > 0).
    pub wrinkles: bool,
    /// P1.4.4: blend normals by wrinkle height (when refine > 0 and wrinkles or fine collision
    /// run).
    pub blend_normals: bool,
    /// Where wrinkle heights come from: `compression` lays stripes across each region's
    /// compression direction with the amplitude that gives back the length the coarse cloth lost;
    /// `force` is P1.4.3 as written (heights driven by the coarse elastic forces, eqs. 4-12).
    pub wrinkle_model: WrinkleModelName,
    /// Wavelength of the `compression` wrinkles, in fine edges.
    #[schemars(range(min = 2.0, max = 64.0))]
    pub wrinkle_period: Real,
    /// Compression the fabric takes up in its plane without buckling (`1/s - 1`, s the smallest
    /// principal stretch of a coarse triangle): the `compression` wrinkles give back only what
    /// lies beyond it.
    #[schemars(range(min = 0.0, max = 0.2))]
    pub wrinkle_min_compression: Real,
    /// Largest compression (`1/s - 1`, s the smallest principal stretch of a coarse triangle) the
    /// `compression` wrinkles give back.
    #[schemars(range(min = 0.0, max = 1.0))]
    pub wrinkle_max_compression: Real,
    /// k_out-plane of P1 eqs. 10 and 12 (m/N), for the `force` wrinkles.
    #[schemars(range(min = 0.0, max = 100.0))]
    pub k_out_plane: Real,
    /// Height at which the deformed surface's normal takes over (m), P1 eq. 13.
    #[schemars(range(min = 1e-5, max = 1.0))]
    pub h_normal: Real,
    /// Distance fine vertices keep from the body (m).
    #[schemars(range(min = 0.0, max = 0.05))]
    pub fine_skin: Real,
    /// Fine collision probes a finer level's vertex where the body may be within this distance
    /// of it, bounded from its coarser neighbours' distances (m; at least `fine_skin`).
    #[schemars(range(min = 0.0, max = 0.2))]
    pub fine_margin: Real,
    /// Longest a fine edge may get through wrinkle height differences, over its reference length.
    #[schemars(range(min = 1.0, max = 3.0))]
    pub max_fine_stretch: Real,
    /// The fine collision also lifts the fine surface over body vertices that poke through
    /// between its vertices (a nipple, a shoulder's tip), `fine_skin` out.
    pub fine_pokes: bool,
    /// The `sdf` collider's settings (P3's grid).
    pub sdf: SdfSection,
    /// The `depth_maps` collider's settings (P4's six views).
    pub depth_maps: DepthMapsSection,
}

impl Default for EffectsSection {
    fn default() -> Self {
        let env = Environment::default();
        let detail = wrinkle::DetailParams::default();
        EffectsSection {
            gravity: env.gravity,
            air_drag: env.air_drag,
            wind: env.wind.to_vec(),
            friction: env.friction,
            body_collision: CollisionMethod::Exact,
            fine_collider: None,
            follow_body: true,
            body_press: true,
            self_collision: false,
            cloth_collision: false,
            velocity_damping: env.velocity_damping,
            refine: 1,
            // The surface stages a refined scene gets unless it says otherwise: fine collision
            // and blended normals on, the wrinkle model (the costly one) off.
            fine_collision: true,
            wrinkles: false,
            blend_normals: true,
            wrinkle_model: WrinkleModelName::default(),
            wrinkle_period: detail.period,
            wrinkle_min_compression: detail.min_compression,
            wrinkle_max_compression: detail.max_compression,
            k_out_plane: detail.k_out_plane,
            h_normal: detail.h_normal,
            fine_skin: detail.skin,
            fine_margin: detail.margin,
            max_fine_stretch: detail.max_fine_stretch,
            fine_pokes: detail.pokes,
            sdf: SdfSection::default(),
            depth_maps: DepthMapsSection::default(),
        }
    }
}

/// The `sdf` collider's settings (`[effects.sdf]`).
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SdfSection {
    /// Grid cells along the body's longest side.
    #[schemars(range(min = 8, max = 512))]
    pub resolution: usize,
}

impl Default for SdfSection {
    fn default() -> Self {
        SdfSection {
            resolution: body_collide::SdfCollider::DEFAULT_RESOLUTION,
        }
    }
}

/// The `depth_maps` collider's settings (`[effects.depth_maps]`).
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct DepthMapsSection {
    /// Pixels along the body's longest side.
    #[schemars(range(min = 16, max = 4096))]
    pub resolution: usize,
}

impl Default for DepthMapsSection {
    fn default() -> Self {
        DepthMapsSection {
            resolution: body_collide::DepthMapCollider::DEFAULT_RESOLUTION,
        }
    }
}

/// What to write.
#[derive(Clone, Debug, Deserialize, Serialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSection {
    /// scene.glb: the skinned body and the garment's frames as morph targets.
    pub glb: bool,
    /// preview.png: one frame, shaded.
    pub preview: bool,
    /// stats.json: counts, per-stage times, metrics, per-frame figures.
    pub stats: bool,
    /// Frame drawn in the preview; the last frame when absent.
    pub preview_frame: Option<usize>,
    /// Preview width (pixels).
    #[schemars(range(min = 16, max = 8192))]
    pub preview_width: u32,
    /// Preview height (pixels).
    #[schemars(range(min = 16, max = 8192))]
    pub preview_height: u32,
    /// Judge every n-th frame with the exact referee (penetration, detachment, stretch, length
    /// error); 0 = never (the metrics then read 0 and `metrics.judged_frames` says so). The
    /// referee is measurement, not product: `referee_share` bounds what it costs.
    #[schemars(range(max = 100000))]
    pub referee_every: usize,
    /// About the most of a run's time the referee may take: it judges only every n-th due frame
    /// (and the last), n estimated before the run from the scene's counts (what an exact body
    /// query and a crossing test per output vertex cost against the solver's sweeps and the
    /// surface), so which frames are judged is the same on every machine and in a resumed run
    /// (`metrics.judged_every` says which). 1 judges every due frame.
    #[schemars(range(min = 0.01, max = 1.0))]
    pub referee_share: Real,
    /// garment.pc2: the garment's frames as a PC2 point cache (Blender's Mesh Cache modifier,
    /// 3ds Max, Maya), to play on garment-obj/garment_00000.obj or the GLB's garment.
    pub pc2: bool,
    /// garment-obj/garment_NNNNN.obj: the garment as one OBJ a frame (an OBJ sequence), each
    /// garment its own group.
    pub obj_sequence: bool,
    /// run.gif: the whole run as an animated GIF beside the still preview (the body and each
    /// garment in their colours, the camera following the body).
    pub gif: bool,
    /// The GIF's width (pixels; its height keeps the preview's proportions).
    #[schemars(range(min = 16, max = 2048))]
    pub gif_width: u32,
    /// Draw every n-th frame into the GIF.
    #[schemars(range(min = 1, max = 1000))]
    pub gif_every: usize,
    /// run.usda: a USD stage (Houdini, Omniverse, Blender, Maya, usdview) with the garment's
    /// points time-sampled every frame, each garment a `GeomSubset`.
    pub usd: bool,
    /// Put the moving body into run.usda too (time-sampled points; a collider in Houdini).
    pub usd_body: bool,
    /// view.bin: the body, the coarse cloth and the garment every frame, as `tryon view DIR`
    /// plays them (about 200 kB a frame on the demo).
    pub view: bool,
    /// Write every n-th frame into view.bin.
    #[schemars(range(min = 1, max = 1000))]
    pub view_every: usize,
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
            referee_every: 1,
            referee_share: 0.25,
            pc2: false,
            obj_sequence: false,
            gif: false,
            gif_width: 320,
            gif_every: 2,
            usd: false,
            usd_body: true,
            view: true,
            view_every: 1,
        }
    }
}
