//! One builder per stage of a scene: the body and its motion, the garment placed on it, the cloth
//! solver, the colliders, the bands and the surface stages. `assemble.rs` calls them in order.

pub use crate::garments::garment_of;
use crate::real;
use crate::scene::BroadPhaseName;
use crate::scene::{
    BodySection, CollisionMethod, EffectsSection, GarmentSection, IntegratorName, MannequinBody,
    MaterialName, MotionSection, Scene, SolverName,
};
use body_collide::{
    BodyError, DepthMapCollider, ExactCollider, NearestVertexCollider, SdfCollider,
};
use body_model::{Mannequin, SkinnedBody};
use cloth_dyn::self_contact::SelfParams;
use cloth_dyn::self_contact::broad::BroadPhase;
use cloth_dyn::wear::GarmentWear;
use cloth_dyn::{
    BuildClothError, ClothModel, ClothParams, ClothSim, Handle, IntegratorKind, VbdSim, XpbdSim,
    presets,
};
use garment_fit::PatternError;
use mocap_retarget::{ArmRaise, ClipError, Walk, WalkParams};
use thiserror::Error;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::MeasureError;
use tryon_core::mesh::PolyMesh;
use tryon_core::shapes::icosphere;
use tryon_core::stages::{
    BodyModel, Capabilities, ClothSolver, Collider, MotionSource, NoCollider, StaticBody,
};

/// Why a scene could not be assembled (after it parsed and passed its range checks).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AssembleError {
    #[error("body: {0}")]
    Measurements(#[from] MeasureError),
    #[error(transparent)]
    Budget(#[from] crate::budget::BudgetError),
    #[error("{file}: the object has no faces (`f` lines) to stand on the table")]
    EmptyObject { file: String },
    /// (Says "body mesh" or "body frame" itself.)
    #[error(transparent)]
    Body(#[from] BodyError),
    #[error("garment: {0}")]
    Pattern(#[from] PatternError),
    #[error("cloth: {0}")]
    Cloth(#[from] BuildClothError),
    #[error("cloth: {0}")]
    Params(#[from] cloth_dyn::params::ParamError),
    #[error("motion: {0}")]
    Motion(#[from] ClipError),
    #[error(transparent)]
    Asset(#[from] crate::real::AssetError),
    #[error("garment mesh: {0}")]
    GarmentTopology(#[from] tryon_core::topology::TopologyError),
    #[error("refine: {0}")]
    Refine(#[from] pnt_surface::RefineError),
    #[error("surface detail: {0}")]
    Detail(#[from] wrinkle::DetailError),
    #[error("kimono: {0}")]
    Kimono(#[from] crate::kimono::KimonoError),
    #[error("a kimono is worn on the mannequin: set [body] kind = \"mannequin\"")]
    KimonoBody,
    #[error("kimono, putting it on: {0}")]
    KimonoWear(#[from] crate::kimono_wear::WearError),
    #[error("garments: {0}")]
    Wear(#[from] cloth_dyn::wear::WearError),
    #[error("[[fold]] {0}")]
    Fold(#[from] fold::FoldError),
    #[error("[[fold]]: folds are drawn on a scene with one garment; this one wears {0}")]
    FoldGarments(usize),
    #[error("[[fold]] fold {fold}: screen point {point} {pixel:?} {reason}")]
    FoldScreen {
        fold: usize,
        point: usize,
        pixel: [Real; 2],
        reason: &'static str,
    },
    #[error("canvas: {0}")]
    Canvas(tryon_io::preview::PreviewError),
    /// An error about something read from a line of the scene file.
    #[error("{file}:{line}: {source}")]
    At {
        file: String,
        line: usize,
        source: Box<AssembleError>,
    },
}

impl AssembleError {
    /// This error placed at the line of the scene's `[[fold]]` it is about, when it is about one
    /// read from a file.
    pub fn at_fold(self, scene: &Scene) -> AssembleError {
        let n = match &self {
            AssembleError::Fold(e) => e.fold(),
            AssembleError::FoldScreen { fold, .. } => Some(*fold),
            _ => None,
        };
        let line = n.and_then(|n| scene.fold.get(n)).and_then(|f| f.line);
        match (line, &scene.source) {
            (Some(line), Some(file)) => AssembleError::At {
                file: file.display().to_string(),
                line,
                source: Box::new(self),
            },
            _ => self,
        }
    }
}

/// The body as assembled: its rest mesh, the model, the motion (`None` for a body that holds
/// still), the MakeHuman body a garment binds to, and the length of the clip (s).
pub(crate) struct BuiltBody {
    pub mesh: PolyMesh,
    pub model: Box<dyn BodyModel>,
    pub motion: Option<Box<dyn MotionSource>>,
    pub makehuman: Option<body_model::MakeHumanBody>,
    pub clip_len: Real,
    /// What retargeting a captured clip changed (`None` for other motions).
    pub retarget: Option<crate::run::RetargetStats>,
    /// The body in the motion's first pose where that is not the rest pose (a kimono's lead-in):
    /// the garment is placed against it and the collider starts from it.
    pub start: Option<PolyMesh>,
    /// What was mended in the input and how (a welded OBJ), for the user to read.
    pub warnings: Vec<String>,
}

impl BuiltBody {
    /// The body the garment starts on.
    pub fn start_mesh(&self) -> &PolyMesh {
        self.start.as_ref().unwrap_or(&self.mesh)
    }
}

/// A body that holds still at `mesh`.
fn fixed(mesh: PolyMesh, clip_len: Real) -> BuiltBody {
    let (triangles, _) = mesh.triangulate();
    BuiltBody {
        model: Box::new(StaticBody {
            positions: mesh.positions.clone(),
            triangles,
        }),
        mesh,
        motion: None,
        makehuman: None,
        clip_len,
        retarget: None,
        start: None,
        warnings: Vec::new(),
    }
}

/// The scene's body and the motion driving it.
pub(crate) fn body(scene: &Scene) -> Result<BuiltBody, AssembleError> {
    let still = match &scene.motion {
        MotionSection::Still(s) => s.duration,
        _ => None,
    };
    Ok(match &scene.body {
        BodySection::Sphere(s) => {
            let mesh = icosphere(s.radius, s.subdivisions, Vec3::zeros());
            fixed(mesh, still.unwrap_or(2.0))
        }
        BodySection::Object(o) => {
            let (mesh, warnings) = crate::object::object_on_table(scene, o)?;
            BuiltBody {
                warnings,
                ..fixed(mesh, still.unwrap_or(3.0))
            }
        }
        BodySection::Mannequin(m) => mannequin(scene, m)?,
        BodySection::Makehuman(spec) => {
            let b = real::makehuman_body(scene, spec)?;
            let mesh = b.mesh();
            let mut built = if let MotionSection::Bvh(bvh) = &scene.motion {
                let tips = b.joint_tails.iter().map(|t| Some(*t)).collect();
                let skin = real::BodySkin {
                    points: &b.rest[..b.body_vertices],
                    joints: &b.skin.joints,
                    weights: &b.skin.weights,
                };
                let r = real::bvh_motion(scene, bvh, &b.skeleton, &b.joint_rest, tips, Some(skin))?;
                BuiltBody {
                    retarget: Some(r.clearance.into()),
                    clip_len: r.duration(),
                    model: Box::new(press(b.skinned(), scene)),
                    motion: Some(Box::new(r)),
                    mesh,
                    makehuman: None,
                    start: None,
                    warnings: Vec::new(),
                }
            } else {
                fixed(mesh, still.unwrap_or(2.0))
            };
            built.makehuman = Some(b);
            built
        }
    })
}

/// The parametric mannequin and its motion.
fn mannequin(scene: &Scene, spec: &MannequinBody) -> Result<BuiltBody, AssembleError> {
    let m = spec.measurements();
    let man = Mannequin::new(&m)?;
    let mut retarget = None;
    let kimono = crate::kimono_wear::scene::spec(scene);
    let motion: Box<dyn MotionSource> = match &scene.motion {
        MotionSection::Still(s) if kimono.is_none() => {
            return Ok(fixed(man.mesh, s.duration.unwrap_or(2.0)));
        }
        MotionSection::Still(s) => Box::new(tryon_core::stages::StillMotion {
            joints: man.skeleton.names.len(),
            duration: s.duration.unwrap_or(2.0),
        }),
        MotionSection::Walk(w) => Box::new(Walk::new(
            &man.skeleton,
            WalkParams {
                period: w.period,
                hip_deg: w.hip_deg,
                knee_deg: w.knee_deg,
                arm_deg: w.arm_deg,
                duration: w.duration,
                leg_length: man.landmarks.crotch + 0.06 * m.scale(),
                ..WalkParams::default()
            },
        )?),
        MotionSection::ArmRaise(a) => {
            let clip = ArmRaise::new(&man.skeleton, a.raise_deg)?;
            Box::new(match a.elbow_deg {
                Some(deg) => clip.with_elbow(deg)?,
                None => clip,
            })
        }
        MotionSection::Bvh(bvh) => {
            let r = real::bvh_motion(
                scene,
                bvh,
                &man.skeleton,
                &man.joint_rest,
                vec![None; man.joint_rest.len()],
                Some(real::BodySkin {
                    points: &man.mesh.positions,
                    joints: &man.skin.joints,
                    weights: &man.skin.weights,
                }),
            )?;
            retarget = Some(r.clearance.into());
            Box::new(r)
        }
    };
    let motion = match kimono {
        Some(k) => crate::kimono_wear::scene::lead_in(&man.skeleton, k, motion),
        None => motion,
    };
    let (tris, _) = man.mesh.triangulate();
    let clip_len = motion.duration();
    let model = press(
        SkinnedBody::new(
            man.mesh.positions.clone(),
            tris,
            man.skeleton,
            man.joint_rest,
            man.skin,
        ),
        scene,
    );
    let start = kimono.map(|_| {
        let mut first = tryon_core::pose::Pose::default();
        motion.sample(0.0, &mut first);
        let mut positions = Vec::new();
        model.shape_at(&first, &mut positions);
        PolyMesh {
            positions,
            faces: man.mesh.faces.clone(),
        }
    });
    Ok(BuiltBody {
        mesh: man.mesh,
        model: Box::new(model),
        motion: Some(motion),
        makehuman: None,
        clip_len,
        retarget,
        start,
        warnings: Vec::new(),
    })
}

/// `body` pressed apart where its parts meet, if the scene asks for it: the gap holds two layers
/// of the cloth's thickness.
fn press(body: SkinnedBody, scene: &Scene) -> SkinnedBody {
    match scene.effects.body_press {
        true => real::pressed(body, 2.0 * scene.cloth.thickness),
        false => body,
    }
}

/// The cloth's material: the preset for the garment's resolution, then the scene's values.
pub fn cloth_params(scene: &Scene, garment: &PolyMesh) -> Result<ClothParams, AssembleError> {
    let (c, fx) = (&scene.cloth, &scene.effects);
    let density = c.density;
    let mut p = match (c.material, &scene.garment) {
        // The grid's spacing (the mean triangle edge counts the quads' diagonals).
        (MaterialName::Sheet, GarmentSection::Square(g)) => {
            presets::sheet(g.size / (g.particles.max(2) - 1) as Real, density)
        }
        _ => presets::garment(presets::mean_edge(garment), density),
    };
    if matches!(scene.garment, GarmentSection::Mhclo(_)) {
        p = presets::modelled(p);
    }
    let set = |dst: &mut Real, v: Option<Real>| {
        if let Some(v) = v {
            *dst = v;
        }
    };
    set(&mut p.k_stretch, c.k_stretch);
    set(&mut p.k_compress, c.k_compress);
    set(&mut p.k_shear, c.k_shear);
    set(&mut p.k_bend, c.k_bend);
    set(&mut p.spring_damping, c.spring_damping);
    set(&mut p.max_substep, c.p1.substep);
    if let Some(s) = c.p1.max_strain {
        p.max_strain = (s > 0.0).then_some(s);
    }
    if let Some(n) = c.p1.strain_iterations {
        p.strain_iterations = n;
    }
    if let Some(r) = c.p1.stretch_guard {
        p.stretch_guard = (r > 0.0).then_some(r);
    }
    set(&mut p.rest_scale, c.rest_scale);
    p.gravity = if fx.gravity {
        tryon_core::math::GRAVITY
    } else {
        Vec3::zeros()
    };
    p.air_drag = fx.air_drag;
    let wind = |i: usize| fx.wind.get(i).copied().unwrap_or(0.0);
    p.wind = Vec3::new(wind(0), wind(1), wind(2));
    p.friction = fx.friction;
    p.velocity_damping = fx.velocity_damping;
    p.validate()?;
    Ok(p)
}

/// The scene's garment solver. Adding a solver is a variant of `SolverName` and its arm here.
pub fn solver(
    scene: &Scene,
    garment: &PolyMesh,
    handles: Vec<Handle>,
    kinematic: &[u32],
    wear: &[GarmentWear],
    bends: &[cloth_dyn::bends::BendChange],
) -> Result<Box<dyn ClothSolver>, AssembleError> {
    let model = |p: &ClothParams| -> Result<ClothModel, AssembleError> {
        let mut m = ClothModel::build_with_kinematic(garment, p, handles.clone(), kinematic)?;
        if !wear.is_empty() {
            m.wear(wear)?;
        }
        m.change_bends(bends);
        Ok(m)
    };
    Ok(match scene.cloth.solver {
        SolverName::P1 => {
            let p = cloth_params(scene, garment)?;
            Box::new(ClothSim::new(model(&p)?, p, integrator(scene)))
        }
        SolverName::Xpbd => {
            let mut p = cloth_params(scene, garment)?;
            // XPBD's edges are inextensible: a garment cut 5% small (P1's worn-under-tension
            // rest scale) would be torn between its edges and the body (stretch 2.0 by frame 3 on
            // makehuman-dress-walk); it is worn at its modelled size unless the scene says.
            p.rest_scale = scene.cloth.rest_scale.unwrap_or(1.0);
            let model = model(&p)?;
            Box::new(XpbdSim::new(model, p, scene.cloth.xpbd.clone()))
        }
        SolverName::Vbd => {
            let mut p = cloth_params(scene, garment)?;
            p.rest_scale = scene.cloth.rest_scale.unwrap_or(1.0);
            let model = model(&p)?;
            let c = &scene.cloth;
            let fx = &scene.effects;
            let contact = self_contact_on(fx, wear.len());
            let self_params = contact.then(|| SelfParams {
                thickness: c.self_thickness,
                friction: fx.friction,
                broad: match c.self_broad_phase {
                    BroadPhaseName::Tree => BroadPhase::Tree,
                    BroadPhaseName::Hash => BroadPhase::Hash,
                },
                within: fx.self_collision,
                between: fx.cloth_collision,
                ..SelfParams::default()
            });
            let v = VbdSim::new(model, p, c.vbd.clone(), c.thickness);
            Box::new(v.with_self_contact(self_params))
        }
    })
}

/// P1's particle cloth with the scene's integrator. `handles` (the
/// bands, in order) are the model's first handles; `kinematic` particles are placed by others.
pub fn cloth_sim(
    scene: &Scene,
    garment: &PolyMesh,
    handles: Vec<Handle>,
    kinematic: &[u32],
) -> Result<ClothSim, AssembleError> {
    let p = cloth_params(scene, garment)?;
    let model = ClothModel::build_with_kinematic(garment, &p, handles, kinematic)?;
    Ok(ClothSim::new(model, p, integrator(scene)))
}

/// The scene's integrator for P1's solver.
fn integrator(scene: &Scene) -> IntegratorKind {
    match scene.cloth.p1.integrator {
        IntegratorName::Rk4 => IntegratorKind::Rk4,
        IntegratorName::SymplecticEuler => IntegratorKind::SymplecticEuler,
        IntegratorName::ImplicitEuler => IntegratorKind::ImplicitEuler,
    }
}

/// The collider `method` over `body`, keeping `thickness` from it. Adding a collider is one arm
/// here and one variant of `CollisionMethod`.
pub fn collider(
    method: CollisionMethod,
    body: &PolyMesh,
    thickness: Real,
    fx: &EffectsSection,
) -> Result<Box<dyn Collider>, BodyError> {
    Ok(match method {
        CollisionMethod::NearestVertex => Box::new(NearestVertexCollider::new(body, thickness)?),
        CollisionMethod::Exact => Box::new(ExactCollider::new(body, thickness)?),
        CollisionMethod::Sdf => Box::new(SdfCollider::new(body, thickness, fx.sdf.resolution)?),
        CollisionMethod::DepthMaps => Box::new(DepthMapCollider::new(
            body,
            thickness,
            fx.depth_maps.resolution,
        )?),
        CollisionMethod::None => Box::new(NoCollider),
    })
}

/// What the scene asks of a collider (`which`: the "body" or the "fine" one) that it lacks, as
/// warnings naming the key that then does nothing.
pub fn lacking(
    scene: &Scene,
    collider: Option<(&'static str, Capabilities)>,
    which: &str,
) -> Vec<String> {
    let Some((name, has)) = collider else {
        return Vec::new();
    };
    let vbd = scene.cloth.solver == SolverName::Vbd;
    let asks: &[(bool, Capabilities, &str)] = match which {
        "body" => &[(
            vbd && scene.cloth.vbd.swept,
            Capabilities {
                sweep: true,
                ..Capabilities::NONE
            },
            "[cloth.vbd] swept",
        )],
        _ => &[(
            scene.effects.fine_pokes,
            Capabilities {
                pokes: true,
                ..Capabilities::NONE
            },
            "[effects] fine_pokes",
        )],
    };
    asks.iter()
        .filter(|(on, _, _)| *on)
        .flat_map(|(_, wanted, key)| {
            has.missing(*wanted).into_iter().map(move |lack| {
                format!("the {which} collider `{name}` has no {lack}: {key} does nothing with it")
            })
        })
        .collect()
}

/// Whether the cloth keeps apart from itself: its own pieces (`self_collision`), or several
/// garments from each other (`cloth_collision` with more than one).
pub fn self_contact_on(fx: &EffectsSection, garments: usize) -> bool {
    fx.self_collision || (fx.cloth_collision && garments > 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::topology::TopologyError;

    #[test]
    fn a_body_mesh_error_says_body_mesh_once() {
        let e = AssembleError::from(BodyError::Topology(TopologyError::NonManifoldEdge {
            a: 1,
            b: 2,
            faces: vec![3, 4, 5],
        }));
        let text = e.to_string();
        assert_eq!(text.matches("body mesh").count(), 1, "{text}");
        assert!(text.starts_with("body mesh: edge (1, 2)"), "{text}");
    }
}
