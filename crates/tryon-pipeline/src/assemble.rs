//! Assembling a scene into a pipeline: only the stages and force terms the scene enables are built.
//! A disabled effect leaves no stage in the list and no term in the solver.

use crate::coarse::CoarseLoop;
use crate::real;
use crate::scene::{
    BodyKind, CollisionMethod, GarmentKind, IntegratorName, MaterialName, MotionKind, Scene,
};
use body_collide::{
    BodyError, BodyFollower, BodyMesh, DepthMapCollider, ExactCollider, FollowParams, Mannequin,
    NearestVertexCollider, SdfCollider, SkinnedBody, SurfaceBinding,
};
use cloth_dyn::{BuildClothError, ClothModel, ClothParams, ClothSim, Handle, IntegratorKind};
use garment_fit::{DressParams, PatternError, SkirtParams};
use mocap_retarget::{ArmRaise, ClipError, Walk, WalkParams};
use thiserror::Error;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::{MeasureError, Measurements};
use tryon_core::mesh::{Face, PolyMesh, grid_xz};
use tryon_core::shapes::icosphere;
use tryon_core::stages::{Collider, MotionSource, NoCollider, StillMotion};

/// Why a scene could not be assembled (after it parsed and passed its range checks).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum AssembleError {
    #[error("body: {0}")]
    Measurements(#[from] MeasureError),
    #[error("body mesh: {0}")]
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
}

/// The body as the pipeline drives it.
pub enum BodyDriver {
    /// A fixed mesh (the sphere).
    Fixed,
    /// A skinned body and the motion that poses it.
    Skinned {
        body: Box<SkinnedBody>,
        motion: Box<dyn MotionSource>,
    },
}

impl std::fmt::Debug for BodyDriver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            BodyDriver::Fixed => f.write_str("Fixed"),
            BodyDriver::Skinned { .. } => f.write_str("Skinned"),
        }
    }
}

/// Garment vertices of elastic bands, each bound to the body's surface and driven there as a
/// kinematic handle of the cloth (handles `first_handle..` of the cloth model, in this order).
#[derive(Clone, Debug)]
pub struct Bands {
    pub vertices: Vec<u32>,
    pub bindings: Vec<SurfaceBinding>,
    pub first_handle: usize,
    /// The body's current shape, on which the bindings are evaluated.
    pub body: BodyMesh,
}

impl Bands {
    /// Moves every band handle to its binding on the body's new shape.
    pub fn update(&mut self, frame: &BodyFrame, handles: &mut [cloth_dyn::Handle]) {
        if self.body.set_frame(frame).is_err() {
            return;
        }
        for (k, b) in self.bindings.iter().enumerate() {
            let p = b.position(&self.body);
            if let Some(h) = handles.get_mut(self.first_handle + k)
                && tryon_core::math::is_finite(&p)
            {
                h.path.clear();
                h.path.push((0.0, p));
            }
        }
    }
}

/// A scene ready to run.
#[derive(Debug)]
pub struct Pipeline {
    pub scene: Scene,
    /// Names of the per-frame stages that will run, in order.
    pub stages: Vec<&'static str>,
    /// The body in its rest pose.
    pub body_mesh: PolyMesh,
    pub driver: BodyDriver,
    /// The garment as placed on the rest pose (after clearing the body).
    pub garment: PolyMesh,
    /// Garment vertices moved out of the body when placing it.
    pub placed_moved: usize,
    /// Vertices of small separate pieces (pockets, patches) attached to the piece beneath.
    pub attachments: Vec<garment_fit::Attachment>,
    /// Elastic bands bound to the body (waistbands, collars, cuffs), when the scene has any.
    pub bands: Option<Bands>,
    pub coarse: CoarseLoop,
    /// The surface stages (P1 section 4), when the scene refines.
    pub fine: Option<crate::fine::FineStage>,
    /// The exact referee judging penetration (always the body's true surface, no skin).
    pub referee: ExactCollider,
    /// The mannequin, when the body is one (for exports: skeleton and weights).
    pub mannequin: Option<Mannequin>,
    pub frames: usize,
    pub fps: Real,
    /// A grab still to happen: path keys (time, position); see `[garment] grab`.
    pub grab: Option<Vec<(Real, Vec3)>>,
}

/// Default material for a garment whose edges average `h` metres: the springs scale with particle
/// mass (see `drape_params`), inextensibility comes from the strain limit.
pub fn garment_params(h: Real, density: Real) -> ClothParams {
    let base = ClothParams::default();
    let m = density * h * h;
    let k = 2500.0 * m;
    ClothParams {
        density,
        k_stretch: k,
        k_compress: 0.1 * k,
        k_shear: 0.1 * k,
        k_bend: 0.02 * k,
        spring_damping: 0.02 * m * 120.0,
        max_strain: Some(1.03),
        strain_iterations: 6,
        strain_relaxation: 1.8,
        min_bend_ratio: Some(0.97),
        stretch_guard: Some(1.1),
        ..base
    }
}

/// The scene's body measurements, defaults filled in.
pub fn measurements(s: &Scene) -> Measurements {
    let d = Measurements::default();
    let b = &s.body;
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

fn mean_edge(mesh: &PolyMesh) -> Real {
    let (tris, _) = mesh.triangulate();
    let mut sum = 0.0;
    for t in &tris {
        for e in 0..3 {
            sum += (mesh.positions[t[e] as usize] - mesh.positions[t[(e + 1) % 3] as usize]).norm();
        }
    }
    sum / (3 * tris.len()).max(1) as Real
}

impl Pipeline {
    /// Builds every enabled stage of `scene`.
    pub fn new(scene: Scene) -> Result<Pipeline, AssembleError> {
        let fx = scene.effects.clone();
        let thickness = scene.cloth.thickness.unwrap_or(0.004);
        let mut stages: Vec<&'static str> = Vec::new();
        let mut makehuman: Option<body_collide::MakeHumanBody> = None;
        // Body and motion.
        let (body_mesh, driver, mannequin, clip_len) = match scene.body.kind {
            BodyKind::Sphere => {
                let r = scene.body.radius.unwrap_or(0.3);
                let mesh = icosphere(r, scene.body.subdivisions.unwrap_or(4), Vec3::zeros());
                (
                    mesh,
                    BodyDriver::Fixed,
                    None,
                    scene.motion.duration.unwrap_or(2.0),
                )
            }
            BodyKind::Object => (
                object_on_table(&scene)?,
                BodyDriver::Fixed,
                None,
                scene.motion.duration.unwrap_or(3.0),
            ),
            BodyKind::Mannequin => {
                let m = measurements(&scene);
                let man = Mannequin::new(&m)?;
                let (tris, _) = man.mesh.triangulate();
                let body = SkinnedBody::new(
                    man.mesh.positions.clone(),
                    tris,
                    man.skeleton.clone(),
                    man.joint_rest.clone(),
                    man.skin.clone(),
                );
                let mo = &scene.motion;
                let motion: Box<dyn MotionSource> = match mo.kind {
                    MotionKind::Still => Box::new(StillMotion {
                        joints: man.skeleton.names.len(),
                        duration: mo.duration.unwrap_or(2.0),
                    }),
                    MotionKind::Walk => {
                        let d = WalkParams::default();
                        let lm = man.landmarks;
                        Box::new(Walk::new(
                            &man.skeleton,
                            WalkParams {
                                period: mo.period.unwrap_or(d.period),
                                hip_deg: mo.hip_deg.unwrap_or(d.hip_deg),
                                knee_deg: mo.knee_deg.unwrap_or(d.knee_deg),
                                arm_deg: mo.arm_deg.unwrap_or(d.arm_deg),
                                duration: mo.duration.unwrap_or(d.duration),
                                leg_length: lm.crotch + 0.06 * m.scale(),
                                ..d
                            },
                        )?)
                    }
                    MotionKind::ArmRaise => {
                        Box::new(ArmRaise::new(&man.skeleton, mo.raise_deg.unwrap_or(100.0))?)
                    }
                    MotionKind::Bvh => Box::new(real::bvh_motion(
                        &scene,
                        mo.file.as_deref().unwrap_or_default(),
                        &man.skeleton,
                        &man.joint_rest,
                        vec![None; man.joint_rest.len()],
                    )?),
                };
                let len = motion.duration();
                let moving = mo.kind != MotionKind::Still;
                let mesh = man.mesh.clone();
                let driver = if moving {
                    BodyDriver::Skinned {
                        body: Box::new(body),
                        motion,
                    }
                } else {
                    BodyDriver::Fixed
                };
                (mesh, driver, Some(man), len)
            }
            BodyKind::Makehuman => {
                let b = real::makehuman_body(&scene)?;
                let mo = &scene.motion;
                let (motion, len): (Option<Box<dyn MotionSource>>, Real) = match mo.kind {
                    MotionKind::Bvh => {
                        let tips = b.joint_tails.iter().map(|t| Some(*t)).collect();
                        let r = real::bvh_motion(
                            &scene,
                            mo.file.as_deref().unwrap_or_default(),
                            &b.skeleton,
                            &b.joint_rest,
                            tips,
                        )?;
                        let len = r.duration();
                        (Some(Box::new(r)), len)
                    }
                    _ => (None, mo.duration.unwrap_or(2.0)),
                };
                let mesh = b.mesh();
                let driver = match motion {
                    Some(motion) => BodyDriver::Skinned {
                        body: Box::new(b.skinned()),
                        motion,
                    },
                    None => BodyDriver::Fixed,
                };
                makehuman = Some(b);
                (mesh, driver, None, len)
            }
        };
        let moving = matches!(driver, BodyDriver::Skinned { .. });
        if moving {
            stages.extend(["motion", "skinning"]);
        }
        let mut referee = ExactCollider::new(&body_mesh, thickness)?;

        // Garment, placed clear of the body.
        let m = measurements(&scene);
        let g = &scene.garment;
        let mut garment = match g.kind {
            GarmentKind::Dress => {
                let d = DressParams::default();
                let e = g.ease.clone().unwrap_or(d.ease.to_vec());
                garment_fit::dress(
                    &m,
                    &DressParams {
                        ease: [e[0], e[1], e[2]],
                        flare: g.flare.unwrap_or(d.flare),
                        hem_above_knee: g.hem_above_knee.unwrap_or(d.hem_above_knee),
                        columns: g.columns.unwrap_or(d.columns),
                        row_spacing: g.row_spacing.unwrap_or(d.row_spacing),
                    },
                )?
                .mesh
            }
            GarmentKind::Skirt => {
                let d = SkirtParams::default();
                let e = g.ease.clone().unwrap_or(d.ease.to_vec());
                garment_fit::skirt(
                    &m,
                    &SkirtParams {
                        ease: [e[0], e[1]],
                        flare: g.flare.unwrap_or(d.flare),
                        hem_above_knee: g.hem_above_knee.unwrap_or(d.hem_above_knee),
                        columns: g.columns.unwrap_or(d.columns),
                        row_spacing: g.row_spacing.unwrap_or(d.row_spacing),
                    },
                )?
                .mesh
            }
            GarmentKind::Square => {
                let n = g.particles.unwrap_or(32).max(2) - 1;
                let size = g.size.unwrap_or(1.0);
                grid_xz(n, n, size, size, g.drop_height.unwrap_or(0.5))
            }
            GarmentKind::Mhclo => {
                let (binding, obj) = real::mhclo(&scene, g.file.as_deref().unwrap_or_default())?;
                let rest = makehuman.as_ref().map(|b| b.rest.as_slice()).unwrap_or(&[]);
                let fitted = garment_fit::fit_garment(&binding, &obj, rest)
                    .map_err(|e| AssembleError::Asset(e.into()))?;
                // Collapse sliver edges (doubled hems): below 15% of the median edge.
                let min_len = 0.15 * garment_fit::median_edge(&fitted);
                garment_fit::weld_short_edges(&fitted, min_len)
                    .map_err(|e| {
                        AssembleError::Asset(
                            garment_fit::FitError::Mesh {
                                name: binding.name.clone(),
                                source: e,
                            }
                            .into(),
                        )
                    })?
                    .mesh
            }
        };
        let placed_moved = if fx.body_collision == CollisionMethod::None {
            0
        } else {
            garment_fit::place_outside(&mut garment, &mut referee)
        };
        // Small separate pieces of a real garment ride on the piece beneath them.
        let attachments = if g.kind == GarmentKind::Mhclo {
            garment_fit::attach_small_pieces(&garment, 0.1, 0.03)
        } else {
            Vec::new()
        };
        // The referee judges the true surface.
        let referee = ExactCollider::new(&body_mesh, 0.0)?;
        // Elastic bands: border loops lying on the body grip it.
        let band_gap = g.band_gap.unwrap_or(if g.kind == GarmentKind::Mhclo {
            0.006
        } else {
            0.0
        });
        let bands = if band_gap > 0.0 && fx.body_collision != CollisionMethod::None {
            let loops = garment_fit::boundary_loops(&garment)?;
            let attached: Vec<u32> = attachments.iter().map(|a| a.vertex).collect();
            let mut vertices = garment_fit::select_bands(&loops, 8, band_gap, |v| {
                referee
                    .project(&garment.positions[v as usize])
                    .map_or(Real::INFINITY, |p| p.distance)
            });
            vertices.retain(|v| attached.binary_search(v).is_err());
            let body = BodyMesh::new(&body_mesh)?;
            let mut kept = Vec::new();
            let mut bindings = Vec::new();
            for v in vertices {
                if let Some(b) = SurfaceBinding::bind(&body, &garment.positions[v as usize]) {
                    kept.push(v);
                    bindings.push(b);
                }
            }
            (!kept.is_empty()).then_some(Bands {
                vertices: kept,
                bindings,
                first_handle: 0,
                body,
            })
        } else {
            None
        };

        // Cloth: material from the garment's resolution, then the scene's overrides and effects.
        let c = &scene.cloth;
        let density = c.density.unwrap_or(0.2);
        let mut p = match c.material.unwrap_or_default() {
            MaterialName::Garment => garment_params(mean_edge(&garment), density),
            // The grid's spacing (the mean triangle edge counts the quads' diagonals).
            MaterialName::Sheet => {
                let n = scene.garment.particles.unwrap_or(32).max(2) - 1;
                crate::drape::sheet_params(scene.garment.size.unwrap_or(1.0) / n as Real, density)
            }
        };
        if g.kind == GarmentKind::Mhclo {
            // Garments modelled for rendering have slivers (0.5 mm edges beside 1.5 cm ones).
            p.mass_floor = 0.3;
            // Worn under a little tension, so that friction holds waistbands (see rest_scale).
            p.rest_scale = 0.95;
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
        set(&mut p.max_substep, c.substep);
        if let Some(s) = c.max_strain {
            p.max_strain = (s > 0.0).then_some(s);
        }
        if let Some(n) = c.strain_iterations {
            p.strain_iterations = n;
        }
        if let Some(r) = c.stretch_guard {
            p.stretch_guard = (r > 0.0).then_some(r);
        }
        p.gravity = if fx.gravity {
            tryon_core::math::GRAVITY
        } else {
            Vec3::zeros()
        };
        p.air_drag = fx.air_drag;
        p.wind = Vec3::from(fx.wind);
        p.friction = fx.friction;
        p.velocity_damping = fx.velocity_damping;
        p.validate()?;
        let kind = match c.integrator.unwrap_or(IntegratorName::Rk4) {
            IntegratorName::Rk4 => IntegratorKind::Rk4,
            IntegratorName::SymplecticEuler => IntegratorKind::SymplecticEuler,
            IntegratorName::ImplicitEuler => IntegratorKind::ImplicitEuler,
        };
        let kinematic: Vec<u32> = attachments.iter().map(|a| a.vertex).collect();
        let handles: Vec<Handle> = bands.as_ref().map_or(Vec::new(), |b| {
            b.vertices
                .iter()
                .map(|&v| Handle {
                    particle: v,
                    path: vec![(0.0, garment.positions[v as usize])],
                })
                .collect()
        });
        let grab = g.grab.as_ref().map(|path| {
            path.iter()
                .map(|k| (k[0], Vec3::new(k[1], k[2], k[3])))
                .collect::<Vec<_>>()
        });
        if grab.is_some() {
            stages.push("grab");
        }
        let model = ClothModel::build_with_kinematic(&garment, &p, handles, &kinematic)?;
        let sim = ClothSim::new(model, p, kind);
        let collider = make_collider(fx.body_collision, &body_mesh, thickness, &fx)?;
        let follower = (fx.follow_body && moving)
            .then(|| {
                BodyMesh::new(&body_mesh).map(|b| BodyFollower::new(b, FollowParams::default()))
            })
            .transpose()?;
        if follower.is_some() {
            stages.push("follow_body");
        }
        if moving && fx.body_collision != CollisionMethod::None {
            stages.push("collider_update");
        }
        if bands.is_some() && moving {
            stages.push("bands");
        }
        stages.push("cloth");
        if !attachments.is_empty() {
            stages.push("attach_pieces");
        }
        // The surface stages (P1 section 4).
        let fine = if fx.refine > 0 {
            let refiner = pnt_surface::PnRefiner::new(&garment, fx.refine)?;
            let (tris, _) = garment.triangulate();
            let mut normals = Vec::new();
            tryon_core::math::vertex_normals(&garment.positions, &tris, &mut normals);
            // Which way the garment's triangles wind: normals should leave the body.
            let near: Vec<u32> = (0..garment.positions.len() as u32).collect();
            let mut probes = Vec::new();
            let mut r = ExactCollider::new(&body_mesh, 0.0)?;
            r.probe(&garment.positions, &near, &mut probes);
            let facing: Real = probes
                .iter()
                .zip(&normals)
                .filter(|(p, _)| p.distance.abs() < 0.03)
                .map(|(p, n)| p.normal.dot(n))
                .sum();
            let orientation = if facing < 0.0 { -1.0 } else { 1.0 };
            let mut surface = tryon_core::frames::FineSurface::default();
            let mut flipped = normals.clone();
            if orientation < 0.0 {
                flipped.iter_mut().for_each(|n| *n = -*n);
            }
            let mut rf = refiner.clone();
            rf.evaluate(&garment.positions, &flipped, &mut surface);
            let params = wrinkle::DetailParams {
                wrinkles: fx.wrinkles,
                fine_collision: fx.fine_collision && fx.body_collision != CollisionMethod::None,
                blend_normals: fx.blend_normals,
                k_out_plane: fx.k_out_plane,
                h_normal: fx.h_normal,
                dt: 1.0 / scene.scene.fps,
                skin: fx.fine_skin,
                margin: fx.fine_margin,
                max_fine_stretch: fx.max_fine_stretch,
            };
            let detail = wrinkle::Detail::new(&surface, &garment.positions, params.clone())?;
            let fine_collider: Option<Box<dyn Collider>> = if params.fine_collision {
                let method = fx.fine_collider.unwrap_or(fx.body_collision);
                Some(make_collider(method, &body_mesh, 0.0, &fx)?)
            } else {
                None
            };
            stages.push("refine");
            if params.wrinkles {
                stages.push("wrinkle");
            }
            if params.fine_collision {
                stages.push("fine_collision");
            }
            if params.blend_normals && (params.wrinkles || params.fine_collision) {
                stages.push("normals");
            }
            Some(crate::fine::FineStage::new(
                refiner,
                detail,
                fine_collider,
                orientation,
            ))
        } else {
            None
        };
        stages.push("referee");
        let coarse = CoarseLoop::new(sim, collider, follower);
        let fps = scene.scene.fps;
        let duration = scene
            .scene
            .duration
            .unwrap_or(scene.scene.settle + clip_len);
        let frames = (duration * fps).round().max(1.0) as usize;
        Ok(Pipeline {
            scene,
            stages,
            body_mesh,
            driver,
            garment,
            placed_moved,
            attachments,
            bands,
            coarse,
            fine,
            referee,
            mannequin,
            frames,
            fps,
            grab,
        })
    }
}

/// The collider a scene asks for, keeping `thickness` from the body.
fn make_collider(
    method: CollisionMethod,
    body: &PolyMesh,
    thickness: Real,
    fx: &crate::scene::EffectsSection,
) -> Result<Box<dyn Collider>, BodyError> {
    Ok(match method {
        CollisionMethod::NearestVertex => Box::new(NearestVertexCollider::new(body, thickness)?),
        CollisionMethod::Exact => Box::new(ExactCollider::new(body, thickness)?),
        CollisionMethod::Sdf => Box::new(SdfCollider::new(body, thickness, fx.sdf_resolution)?),
        CollisionMethod::DepthMaps => {
            Box::new(DepthMapCollider::new(body, thickness, fx.depth_resolution)?)
        }
        CollisionMethod::None => Box::new(NoCollider),
    })
}

/// P4's scene body: the scene's OBJ scaled to metres, centred over the origin and standing on a
/// closed table slab whose top is y = 0.
fn object_on_table(scene: &Scene) -> Result<PolyMesh, AssembleError> {
    let b = &scene.body;
    let path = crate::real::resolve(scene, "body.file", b.file.as_deref().unwrap_or_default())?;
    let obj = tryon_io::read_obj(&path).map_err(crate::real::AssetError::from)?;
    let scale = b.scale.unwrap_or(1.0);
    let mut mesh = PolyMesh {
        positions: obj.positions.iter().map(|p| p * scale).collect(),
        faces: obj.faces,
    };
    let (mut lo, mut hi) = (
        Vec3::repeat(Real::INFINITY),
        Vec3::repeat(Real::NEG_INFINITY),
    );
    for p in &mesh.positions {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let shift = Vec3::new(-(lo.x + hi.x) / 2.0, -lo.y, -(lo.z + hi.z) / 2.0);
    for p in &mut mesh.positions {
        *p += shift;
    }
    let side = b.table.unwrap_or(1.5);
    if side > 0.0 {
        let cells = ((side / 0.03).ceil() as usize).clamp(2, 200);
        let slab = table_slab(side, 0.04, cells);
        let base = mesh.positions.len() as u32;
        mesh.positions.extend_from_slice(&slab.positions);
        mesh.faces.extend(slab.faces.iter().map(|f| match f {
            Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
            Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
        }));
    }
    Ok(mesh)
}

/// A closed box `side` x `thick` x `side` with its top face at y = 0, the top and bottom split
/// into `cells` x `cells` quads (so nearest-vertex tracking has vertices everywhere), faces
/// wound outward.
pub fn table_slab(side: Real, thick: Real, cells: usize) -> PolyMesh {
    use std::collections::HashMap;
    let n = cells.max(1);
    let mut index: HashMap<(usize, usize, usize), u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut vertex = |i: usize, j: usize, k: usize| -> u32 {
        *index.entry((i, j, k)).or_insert_with(|| {
            positions.push(Vec3::new(
                side * (i as Real / n as Real - 0.5),
                if j == 1 { 0.0 } else { -thick },
                side * (k as Real / n as Real - 0.5),
            ));
            (positions.len() - 1) as u32
        })
    };
    let mut quads: Vec<[u32; 4]> = Vec::new();
    for a in 0..n {
        for c in 0..n {
            for j in [0, 1] {
                quads.push([
                    vertex(a, j, c),
                    vertex(a + 1, j, c),
                    vertex(a + 1, j, c + 1),
                    vertex(a, j, c + 1),
                ]);
            }
        }
        for edge in [0, n] {
            quads.push([
                vertex(a, 0, edge),
                vertex(a + 1, 0, edge),
                vertex(a + 1, 1, edge),
                vertex(a, 1, edge),
            ]);
            quads.push([
                vertex(edge, 0, a),
                vertex(edge, 0, a + 1),
                vertex(edge, 1, a + 1),
                vertex(edge, 1, a),
            ]);
        }
    }
    let centre = Vec3::new(0.0, -thick / 2.0, 0.0);
    let faces = quads
        .into_iter()
        .map(|q| {
            let p = q.map(|v| positions[v as usize]);
            let normal = (p[1] - p[0]).cross(&(p[2] - p[0]));
            let mid = (p[0] + p[1] + p[2] + p[3]) / 4.0;
            if normal.dot(&(mid - centre)) < 0.0 {
                Face::Quad([q[3], q[2], q[1], q[0]])
            } else {
                Face::Quad(q)
            }
        })
        .collect();
    PolyMesh { positions, faces }
}
