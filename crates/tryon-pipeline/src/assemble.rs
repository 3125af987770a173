//! Assembling a scene into a pipeline: only the stages and force terms the scene enables are built.
//! A disabled effect leaves no stage object and no term in the solver. The builders are in
//! `build.rs`; this file orders them and places the garment.

use crate::budget;
use crate::build;
pub use crate::build::AssembleError;
use crate::pipeline::{Options, Pipeline};
use crate::scene::{CollisionMethod, GarmentSection, Scene};
use body_collide::{Bands, BodyFollower, BodyMesh, ExactCollider, FollowParams};
use cloth_dyn::Handle;
use cloth_dyn::self_contact::stage::FineLayers;
use tryon_core::frames::FineSurface;
use tryon_core::interact::Grab;
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Follower, SurfaceStage};

impl Pipeline {
    /// Builds every enabled stage of `scene`.
    pub fn new(scene: Scene) -> Result<Pipeline, AssembleError> {
        Pipeline::with_options(scene, &Options::default())
    }

    /// [`Pipeline::new`] with `options`: progress told how far a long preparation is, and the
    /// run's estimate held against the limits before the costly stages are built.
    pub fn with_options(scene: Scene, options: &Options) -> Result<Pipeline, AssembleError> {
        let progress = options.progress;
        let fx = scene.effects.clone();
        let thickness = scene.cloth.thickness;
        let body = build::body(&scene)?;
        let moving = body.motion.is_some();
        let collides = fx.body_collision != CollisionMethod::None;
        // The garments, each placed clear of the body (judged with the cloth's thickness) and
        // of the layers under it, joined into one cloth.
        let dressed = crate::wardrobe::dress(&scene, &body, collides, progress)?;
        // Folds drawn on the garment (P3): the mesh subdivided and shaped before the cloth is built.
        let (dressed, folds) = crate::folding::apply(&scene, &body.mesh, dressed)?;
        let (garment, placed_moved) = (dressed.mesh.clone(), dressed.placed_moved);
        let attachments = dressed.attachments.clone();
        // The referee judges the true surface.
        let referee = ExactCollider::new(&body.mesh, 0.0)?;
        let bands = if collides {
            bands(&scene, &dressed, &body.mesh, &referee)?
        } else {
            None
        };
        let handles: Vec<Handle> = bands.as_ref().map_or(Vec::new(), |b| {
            b.vertices
                .iter()
                .map(|&v| Handle {
                    particle: v,
                    path: vec![(0.0, garment.positions[v as usize])],
                })
                .collect()
        });
        let kinematic: Vec<u32> = attachments.iter().map(|a| a.vertex).collect();
        let solver = build::solver(
            &scene,
            &garment,
            handles,
            &kinematic,
            &dressed.wear,
            &folds.bends,
        )?;
        let fps = scene.scene.fps;
        let duration = scene
            .scene
            .duration
            .unwrap_or(scene.scene.settle + body.clip_len);
        let frames = (duration * fps).round().max(1.0) as usize;
        let substep = solver.info().nominal_substep;
        let estimate = budget::estimate(
            &scene,
            &garment,
            body.mesh.positions.len(),
            substep,
            options.frames.unwrap_or(frames),
        );
        budget::check(&estimate, &options.limits)?;
        let collider = collides
            .then(|| build::collider(fx.body_collision, body.start_mesh(), thickness, &fx))
            .transpose()?;
        let follower: Option<Box<dyn Follower>> = if fx.follow_body && moving {
            let (root, root_rest) = body.model.rig().map_or((0, Vec3::zeros()), |r| r.root());
            let mut f = BodyFollower::new(BodyMesh::new(&body.mesh)?, FollowParams::default())
                .with_root(root, root_rest);
            if build::self_contact_on(&fx, dressed.wear.len()) {
                // Cloth-cloth contact lets a vertex move only a share of its nearest gap in a
                // step: an edge the carry tore would stay torn (docs/decisions, *carry keeps edges*).
                f = f.with_edges(&garment.triangulate().0);
            }
            Some(Box::new(f))
        } else {
            None
        };
        let mut warnings = body.warnings;
        let body_caps = collider.as_ref().map(|c| (c.name(), c.capabilities()));
        warnings.extend(build::lacking(&scene, body_caps, "body"));
        let mut surface_stages = surface_stages(&scene, &garment, &body.mesh, &mut warnings)?;
        if let Some(stage) = fine_layers(&scene, &dressed, &body.mesh, &surface_stages)? {
            surface_stages.push(stage);
        }
        let grab = match &scene.garment {
            GarmentSection::Square(g) => g.grab.as_ref().map(|path| Grab {
                path: path
                    .iter()
                    .filter_map(|k| match k[..] {
                        [t, x, y, z] => Some((t, Vec3::new(x, y, z))),
                        _ => None,
                    })
                    .collect(),
            }),
            _ => None,
        };
        let mut cloth = solver.initial_frame();
        if let Some(start) = folds
            .start
            .as_ref()
            .filter(|x| x.len() == cloth.positions.len())
        {
            cloth.positions.clone_from(start);
        }
        Ok(Pipeline {
            scene,
            body_mesh: body.mesh,
            body: body.model,
            motion: body.motion,
            retarget: body.retarget,
            follower,
            collider,
            bands,
            attachments,
            solver,
            cloth,
            surface_stages,
            surface: FineSurface::default(),
            referee,
            garment,
            placed_moved,
            warnings,
            estimate,
            wear: dressed.wear,
            layered: dressed.layered,
            pieces: dressed.pieces,
            frames,
            fps,
            grab,
            end_shape: Vec::new(),
            folds,
        })
    }
}

/// The stages of a driver that shapes the body and holds the cloth itself (the kimono's
/// dressing): run on [`Pipeline::advance_coarse`], with no follower, bands, attached pieces,
/// grab or surface stages.
pub struct Parts {
    pub scene: Scene,
    /// The body at the start.
    pub body_mesh: PolyMesh,
    pub body: Box<dyn tryon_core::stages::BodyModel>,
    pub motion: Option<Box<dyn tryon_core::stages::MotionSource>>,
    pub collider: Option<Box<dyn Collider>>,
    pub solver: Box<dyn tryon_core::stages::ClothSolver>,
    pub garment: PolyMesh,
    pub fps: Real,
    pub frames: usize,
}

impl std::fmt::Debug for Parts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Parts")
            .field("scene", &self.scene.scene.name)
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

impl Pipeline {
    /// A pipeline of `parts` (the cloth starts at the solver's initial frame).
    pub fn from_parts(parts: Parts) -> Result<Pipeline, AssembleError> {
        let referee = ExactCollider::new(&parts.body_mesh, 0.0)?;
        Ok(Pipeline {
            scene: parts.scene,
            body_mesh: parts.body_mesh,
            body: parts.body,
            motion: parts.motion,
            retarget: None,
            follower: None,
            collider: parts.collider,
            bands: None,
            attachments: Vec::new(),
            cloth: parts.solver.initial_frame(),
            solver: parts.solver,
            surface_stages: Vec::new(),
            surface: FineSurface::default(),
            referee,
            garment: parts.garment,
            placed_moved: 0,
            warnings: Vec::new(),
            estimate: budget::Estimate::default(),
            wear: Vec::new(),
            layered: Vec::new(),
            pieces: Vec::new(),
            frames: parts.frames,
            fps: parts.fps,
            grab: None,
            end_shape: Vec::new(),
            folds: crate::folding::Folds::default(),
        })
    }
}

/// Elastic bands: border loops lying on the body grip it (each garment's `band_gap`, m; default
/// 6 mm for modelled garments, none for the patterns).
fn bands(
    scene: &Scene,
    dressed: &crate::wardrobe::Dressed,
    body: &PolyMesh,
    referee: &ExactCollider,
) -> Result<Option<Bands>, AssembleError> {
    let garment = &dressed.mesh;
    let loops = garment_fit::boundary_loops(garment)?;
    let mut attached: Vec<u32> = dressed.attachments.iter().map(|a| a.vertex).collect();
    attached.sort_unstable();
    let mut vertices = dressed.tied.clone();
    for worn in scene.garments() {
        let (band_gap, waist_gap) = match worn.garment {
            GarmentSection::Dress(g) => (g.band_gap, 0.0),
            GarmentSection::Skirt(g) => (g.band_gap, 0.0),
            GarmentSection::Shirt(g) => (g.band_gap, 0.0),
            GarmentSection::Mhclo(g) => (g.band_gap, g.waist_gap),
            GarmentSection::Square(_) | GarmentSection::Kimono(_) => (0.0, 0.0),
        };
        if !(band_gap > 0.0 || waist_gap > 0.0) {
            continue;
        }
        let own: Vec<Vec<u32>> = loops
            .iter()
            .filter(|l| {
                l.first()
                    .is_some_and(|&v| dressed.garment_of(v) == worn.index)
            })
            .cloned()
            .collect();
        let gap = |v: u32| {
            referee
                .project(&garment.positions[v as usize])
                .map_or(Real::INFINITY, |p| p.distance)
        };
        vertices.extend(garment_fit::select_bands(&own, 8, band_gap, gap));
        if waist_gap > 0.0 {
            let piece = garment_fit::components(garment);
            let waists = garment_fit::bands::select_waists(
                &own,
                (&piece, &garment.positions),
                shoulder_height(body),
                (8, waist_gap),
                gap,
            );
            vertices.extend(waists);
        }
    }
    vertices.sort_unstable();
    vertices.dedup();
    vertices.retain(|v| attached.binary_search(v).is_err());
    if vertices.is_empty() {
        return Ok(None);
    }
    Ok(Bands::bind(body, &garment.positions, &vertices)?)
}

/// The height (y) a garment piece must reach to hang from the body's shoulders
/// ([`garment_fit::bands::SHOULDER_SHARE`] of the body's height in its fitted pose).
fn shoulder_height(body: &PolyMesh) -> Real {
    let (lo, hi) = body
        .positions
        .iter()
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.y), hi.max(p.y))
        });
    lo + garment_fit::bands::SHOULDER_SHARE * (hi - lo)
}

/// The surface stages (P1 section 4), when the scene refines: PN refinement, then the detail model
/// (wrinkles, fine collision, normal blending) with its own collider.
fn surface_stages(
    scene: &Scene,
    garment: &PolyMesh,
    body: &PolyMesh,
    warnings: &mut Vec<String>,
) -> Result<Vec<Box<dyn SurfaceStage>>, AssembleError> {
    let fx = &scene.effects;
    if fx.refine == 0 {
        return Ok(Vec::new());
    }
    let refiner = pnt_surface::PnRefiner::new(garment, fx.refine)?;
    let orientation = outward_orientation(garment, body)?;
    let mut pn = pnt_surface::PnStage::new(refiner, orientation);
    let mut surface = FineSurface::default();
    pn.evaluate(&garment.positions, &mut surface);
    let params = wrinkle::DetailParams {
        wrinkles: fx.wrinkles,
        model: fx.wrinkle_model.into(),
        period: fx.wrinkle_period,
        min_compression: fx.wrinkle_min_compression,
        max_compression: fx.wrinkle_max_compression,
        fine_collision: fx.fine_collision && fx.body_collision != CollisionMethod::None,
        blend_normals: fx.blend_normals,
        k_out_plane: fx.k_out_plane,
        h_normal: fx.h_normal,
        dt: 1.0 / scene.scene.fps,
        skin: fx.fine_skin,
        margin: fx.fine_margin,
        max_fine_stretch: fx.max_fine_stretch,
        pokes: fx.fine_pokes,
    };
    let detail = wrinkle::Detail::new(&surface, &garment.positions, params.clone())?;
    let fine_collider = if params.fine_collision {
        let method = fx.fine_collider.unwrap_or(fx.body_collision);
        let c = build::collider(method, body, 0.0, fx)?;
        warnings.extend(build::lacking(
            scene,
            Some((c.name(), c.capabilities())),
            "fine",
        ));
        Some(c)
    } else {
        None
    };
    Ok(vec![
        Box::new(pn),
        Box::new(wrinkle::DetailStage::new(detail, fine_collider)),
    ])
}

/// With several garments kept apart (`cloth_collision`) on a refined surface: the fine surface's
/// garments untangled after the other surface stages (`FineLayers`).
fn fine_layers(
    scene: &Scene,
    dressed: &crate::wardrobe::Dressed,
    body: &PolyMesh,
    stages: &[Box<dyn SurfaceStage>],
) -> Result<Option<Box<dyn SurfaceStage>>, AssembleError> {
    if !(scene.effects.cloth_collision && dressed.wear.len() > 1) || stages.is_empty() {
        return Ok(None);
    }
    let n = dressed.mesh.positions.len();
    let (mut garment, mut layer) = (vec![0u16; n], vec![0u32; n]);
    for (g, w) in dressed.wear.iter().enumerate() {
        for v in w.particles.clone() {
            garment[v as usize] = g as u16;
            layer[v as usize] = w.layer;
        }
    }
    let mut pn = pnt_surface::PnStage::new(
        pnt_surface::PnRefiner::new(&dressed.mesh, scene.effects.refine)?,
        1.0,
    );
    let mut surface = FineSurface::default();
    pn.evaluate(&dressed.mesh.positions, &mut surface);
    let orientation = outward_orientation(&dressed.mesh, body)?;
    let gap = scene.cloth.self_thickness;
    let stage = FineLayers::new(&surface, (&garment, &layer), gap, orientation);
    Ok(Some(Box::new(stage)))
}

/// Which way the garment's triangles wind: -1 when their normals point into the body (judged on
/// the vertices within 3 cm of it), else 1.
fn outward_orientation(garment: &PolyMesh, body: &PolyMesh) -> Result<Real, AssembleError> {
    let (tris, _) = garment.triangulate();
    let mut normals = Vec::new();
    vertex_normals(&garment.positions, &tris, &mut normals);
    let near: Vec<u32> = (0..garment.positions.len() as u32).collect();
    let mut probes = Vec::new();
    let mut r = ExactCollider::new(body, 0.0)?;
    r.probe(&garment.positions, &near, &mut probes);
    let facing: Real = probes
        .iter()
        .zip(&normals)
        .filter(|(p, _)| p.distance.abs() < 0.03)
        .map(|(p, n)| p.normal.dot(n))
        .sum();
    Ok(if facing < 0.0 { -1.0 } else { 1.0 })
}
