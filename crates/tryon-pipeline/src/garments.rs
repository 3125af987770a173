//! The scene's garments as made, before they are placed on the body: the patterns cut for the
//! mannequin (dress, skirt, shirt), a square, a MakeHuman garment fitted to its body, and the
//! kimono fitted and put on.

use crate::build::AssembleError;
use crate::real;
use crate::scene::{BodySection, GarmentSection, Scene, ShirtSpec};
use body_collide::ExactCollider;
use body_model::Mannequin;
use garment_fit::{DressParams, PatternError, ShirtParams, SkirtParams};
use tryon_core::math::Vec3;
use tryon_core::mesh::{PolyMesh, grid_xz};

/// The shirt of `g` cut from the mannequin of `m` (the scene's body: both are built from the same
/// measurements). A vertex belongs to an arm when its strongest influence is that arm's upper arm,
/// forearm or hand.
fn shirt(m: &tryon_core::measure::Measurements, g: &ShirtSpec) -> Result<PolyMesh, AssembleError> {
    use tryon_core::pose::mannequin_joints as j;
    let man = Mannequin::new(m)?;
    let joint = |name: &str| man.skeleton.names.iter().position(|n| n == name);
    let chains = [
        [j::UPPERARM_L, j::FOREARM_L, j::HAND_L],
        [j::UPPERARM_R, j::FOREARM_R, j::HAND_R],
    ]
    .map(|c| c.map(joint));
    let arm_of: Vec<Option<u8>> = (0..man.mesh.positions.len())
        .map(|v| {
            let (w, js) = (man.skin.weights[v], man.skin.joints[v]);
            let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
            let strongest = Some(js[k] as usize);
            (0..2u8).find(|&a| chains[a as usize].contains(&strongest))
        })
        .collect();
    let arms = chains.map(|c| {
        let (root, elbow) = match (c[0], c[1]) {
            (Some(a), Some(b)) => (man.joint_rest[a], man.joint_rest[b]),
            _ => (Vec3::zeros(), Vec3::x()),
        };
        garment_fit::Arm {
            root,
            dir: (elbow - root).try_normalize(1e-12).unwrap_or_else(Vec3::x),
        }
    });
    let body = garment_fit::ShirtBody {
        mesh: &man.mesh,
        arm_of: &arm_of,
        arms,
    };
    let p = ShirtParams {
        ease: [g.ease[0], g.ease[1], g.ease[2]],
        sleeve_ease: g.sleeve_ease,
        sleeve_length: g.sleeve_length,
        hem_below_hip: g.hem_below_hip,
        subdivisions: g.subdivisions,
    };
    // The least clearance over the skin: the cloth's thickness at the default figure.
    let mut collider = ExactCollider::new(&man.mesh, 0.004 * m.scale())?;
    let mesh = garment_fit::shirt(m, &body, &mut collider, &p)?.mesh;
    // A heavy figure's mannequin has its arms through its sides in the A-pose: a shirt cut from it
    // crosses itself there and tears at the first frame.
    let (tris, _) = mesh.triangulate();
    let crossing = body_collide::crossings::crossings(&mesh.positions, &tris).len();
    if crossing > 0 {
        let (body_tris, _) = man.mesh.triangulate();
        let body = body_collide::crossings::crossings(&man.mesh.positions, &body_tris).len();
        return Err(PatternError::Cut(format!(
            "the shirt crosses itself in {crossing} triangle pairs (the mannequin of these \
             measurements crosses itself in {body}: its arms pass into its sides, so the \
             sleeves would too)"
        ))
        .into());
    }
    Ok(mesh)
}

/// One of the scene's garments, `garment`, before it is placed on the body.
pub fn garment_of(
    scene: &Scene,
    garment: &GarmentSection,
    makehuman: Option<&body_model::MakeHumanBody>,
) -> Result<PolyMesh, AssembleError> {
    made(scene, garment, makehuman, &|_| {}).map(|g| g.mesh)
}

/// A garment as made, before it is placed.
pub(crate) struct Made {
    pub mesh: PolyMesh,
    /// Vertices held to the body (a kimono's cord).
    pub tied: Vec<u32>,
}

/// [`garment_of`], with the vertices the garment is tied to the body by.
pub(crate) fn made(
    scene: &Scene,
    garment: &GarmentSection,
    makehuman: Option<&body_model::MakeHumanBody>,
    progress: crate::Progress,
) -> Result<Made, AssembleError> {
    let m = match &scene.body {
        BodySection::Mannequin(b) => b.measurements(),
        _ => tryon_core::measure::Measurements::default(),
    };
    let mut tied = Vec::new();
    let mesh = match garment {
        GarmentSection::Dress(g) => {
            let p = DressParams {
                ease: [g.ease[0], g.ease[1], g.ease[2]],
                flare: g.flare,
                hem_above_knee: g.hem_above_knee,
                columns: g.columns,
                row_spacing: g.row_spacing,
            };
            garment_fit::dress(&m, &p)?.mesh
        }
        GarmentSection::Shirt(g) => shirt(&m, g)?,
        GarmentSection::Kimono(k) => {
            if !matches!(scene.body, BodySection::Mannequin(_)) {
                return Err(AssembleError::KimonoBody);
            }
            let worn = crate::kimono_wear::scene::garment(&m, k, progress)?;
            tied = worn.tied;
            worn.mesh
        }
        GarmentSection::Skirt(g) => {
            let p = SkirtParams {
                ease: [g.ease[0], g.ease[1]],
                flare: g.flare,
                hem_above_knee: g.hem_above_knee,
                columns: g.columns,
                row_spacing: g.row_spacing,
            };
            garment_fit::skirt(&m, &p)?.mesh
        }
        GarmentSection::Square(g) => {
            let n = g.particles.max(2) - 1;
            grid_xz(n, n, g.size, g.size, g.drop_height)
        }
        GarmentSection::Mhclo(g) => {
            let (binding, obj) = real::mhclo(scene, &g.file)?;
            let rest = makehuman.map(|b| b.rest.as_slice()).unwrap_or(&[]);
            let fitted = garment_fit::fit_garment(&binding, &obj, rest)
                .map_err(|e| AssembleError::Asset(e.into()))?;
            // Collapse sliver edges (doubled hems): below 15% of the median edge.
            let min_len = 0.15 * garment_fit::median_edge(&fitted);
            let mesh_error = |source| {
                let name = binding.name.clone();
                AssembleError::Asset(garment_fit::FitError::Mesh { name, source }.into())
            };
            let welded = garment_fit::weld_short_edges(&fitted, min_len).map_err(mesh_error)?;
            // Close what the modeller left touching (a buttoned front).
            if g.closures > 0.0 {
                let gap = g.closures * garment_fit::median_edge(&welded.mesh);
                let closed =
                    garment_fit::close_openings(&welded.mesh, gap).map_err(|e| match e {
                        garment_fit::CloseError::Mesh(m) => mesh_error(m),
                        garment_fit::CloseError::Topology(t) => AssembleError::Asset(
                            garment_fit::FitError::Topology {
                                name: binding.name.clone(),
                                source: t,
                            }
                            .into(),
                        ),
                    })?;
                closed.0.mesh
            } else {
                welded.mesh
            }
        }
    };
    Ok(Made { mesh, tied })
}
