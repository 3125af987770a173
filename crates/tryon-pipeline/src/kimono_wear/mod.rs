//! Worn kimono shapes (P2's target shapes, issue 23 item 3) and a kimono in a scene: the flat
//! tailored kimono put on the mannequin of its wearer's size by this project's cloth solver (VBD,
//! self-contact on), on the pipeline's frame loop. The dressing's geometry (placing, the folded
//! start, the inflating body, the tie's rings) is `kimono::dress`; this module poses the
//! mannequin, builds the stages and steps them: the body grows as an [`Inflating`] body model
//! while the fold line is held, then the rows are tied by the solver's anchors.

pub mod embedded;
pub(crate) mod scene;
pub mod store;

use crate::assemble::Parts;
use crate::scene::{CollisionMethod, SolverName};
use crate::timers::Timers;
use crate::{LoopState, Pipeline};
use body_model::Mannequin;
use body_model::skin::SkinnedBody;
use kimono::KimonoMesh;
use kimono::dress::{Stand, Start, tie};
pub use kimono::dress::{WearSettings, Worn};
use std::time::Instant;
use thiserror::Error;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::Measurements;
use tryon_core::mesh::PolyMesh;
use tryon_core::pose::Pose;
use tryon_core::stages::{BodyModel, StillMotion};

/// Why a kimono could not be put on.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum WearError {
    #[error("the wearer's kimono: {0}")]
    Tailor(#[from] kimono::TailorError),
    #[error("the kimono's levels: {0}")]
    Levels(#[from] kimono::LevelError),
    #[error("the wearer's mannequin: {0}")]
    Mannequin(#[from] tryon_core::measure::MeasureError),
    #[error("{0}")]
    Stand(#[from] kimono::dress::DressError),
    #[error("the shape to put on has {found} vertices; the kimono has {expected}")]
    Shape { found: usize, expected: usize },
    #[error("{what}: {message}")]
    Build { what: &'static str, message: String },
}

fn build_err(what: &'static str) -> impl Fn(String) -> WearError {
    move |message| WearError::Build { what, message }
}

/// Puts the kimono `flat` (the initial kimono's topology, laid flat, tailored for `w`) on the
/// mannequin of `w`'s size. `on_frame(act, frame, frames)` reports progress.
pub fn wear(
    w: &kimono::Wearer,
    flat: &[Vec3],
    base: &KimonoMesh,
    s: &WearSettings,
    on_frame: &mut dyn FnMut(&str, usize, usize),
) -> Result<Worn, WearError> {
    let m = kimono::dress::measurements(w);
    wear_on(&m, w, flat, base, s, on_frame)
}

/// The mannequin of measurements `m` standing as the kimono is put on (arms raised).
fn stand(m: &Measurements) -> Result<Stand, WearError> {
    let man = Mannequin::new(m)?;
    let pose = kimono::dress::dress_pose(&man.skeleton);
    let triangles = man.mesh.triangulate().0;
    let skinned = SkinnedBody::new(
        man.mesh.positions.clone(),
        triangles.clone(),
        man.skeleton.clone(),
        man.joint_rest.clone(),
        man.skin.clone(),
    );
    let mut posed = Vec::new();
    skinned.skin_into(&pose, &mut posed);
    Ok(Stand::new(*m, posed, triangles)?)
}

/// The body growing from squashed to its full depth: frame `k` of the run (its pose's time times
/// the frame rate) is [`Start::body_at`] frame `k`.
struct Inflating {
    stand: Stand,
    settings: WearSettings,
}

impl BodyModel for Inflating {
    fn pose(&mut self, pose: &Pose, out: &mut BodyFrame) {
        let body = self.body_at(pose);
        let dt = 1.0 / self.settings.fps;
        out.velocities = match out.positions.len() == body.len() {
            true => body
                .iter()
                .zip(&out.positions)
                .map(|(a, b)| (a - b) / dt)
                .collect(),
            false => vec![Vec3::zeros(); body.len()],
        };
        out.time = pose.time;
        out.positions = body;
    }
    fn shape_at(&self, pose: &Pose, out: &mut Vec<Vec3>) {
        *out = self.body_at(pose);
    }
}

impl Inflating {
    fn body_at(&self, pose: &Pose) -> Vec<Vec3> {
        let f = (pose.time * self.settings.fps).round().max(0.0) as usize;
        Start::body_at(&self.stand, &self.settings, f)
    }
}

/// [`wear`] on the mannequin of measurements `m` (a scene's), the kimono tailored for `w`.
pub fn wear_on(
    m: &Measurements,
    w: &kimono::Wearer,
    flat: &[Vec3],
    base: &KimonoMesh,
    s: &WearSettings,
    on_frame: &mut dyn FnMut(&str, usize, usize),
) -> Result<Worn, WearError> {
    if flat.len() != base.positions.len() {
        return Err(WearError::Shape {
            found: flat.len(),
            expected: base.positions.len(),
        });
    }
    let d = kimono::tailor(w)?;
    let lv = kimono::Levels::new(&d)?;
    let st = stand(m)?;
    let start = Start::new(&st, flat, base, &lv);
    let garment = PolyMesh::from_triangles(start.rest.clone(), &base.triangles)
        .map_err(|e| build_err("the kimono mesh")(e.to_string()))?;
    let mut p = dressing(&st, s, &garment, &start.fold_line)?;
    p.cloth.positions.clone_from(&start.start);
    let crossings = |p: &[Vec3]| body_collide::crossings::crossings(p, &base.triangles).len();
    let start_crossings = crossings(&start.start);
    let clock = Instant::now();
    let mut ls = p.start();
    let mut timers = Timers::default();
    let frames = s.inflate_frames + s.settle_frames;
    let mut free = Some(solver(&p.scene, &garment, &[])?);
    for f in 1..=frames {
        if f > s.inflate_frames + 1 {
            if let Some(x) = free.take() {
                p.solver = x;
            }
        }
        let up = start.band_targets(&p.cloth.positions);
        p.solver.anchor(&start.band_rows, &up, s.hold_stiffness);
        p.advance_coarse(&mut ls, p.frame_time(f), &mut timers);
        on_frame("inflate", f, frames);
    }
    let inflated = crossings(&p.cloth.positions);
    // The body stands still while the kimono is tied.
    p.motion = None;
    p.solver = solver(&p.scene, &garment, &[])?;
    let (tie_frames, row_lag_m, tied) =
        tie_rows(&mut p, &mut ls, &st, &start, base, &lv, s, frames, on_frame);
    let steps = frames + tie_frames;
    let ankle = st.m.landmarks().ankle;
    let positions = std::mem::take(&mut p.cloth.positions);
    Ok(Worn {
        crossings: [start_crossings, inflated, crossings(&positions)],
        hem_above_ankle_m: positions
            .iter()
            .map(|p| p.y)
            .fold(Real::INFINITY, Real::min)
            - ankle,
        positions,
        body: ls.body_frame.positions,
        body_triangles: st.triangles,
        row_lag_m,
        tied,
        frames: steps,
        ms_per_frame: clock.elapsed().as_secs_f64() * 1e3 / steps.max(1) as Real,
    })
}

/// The scene the dressing's solvers are built from (VBD, self-contact on; one sub-frame a frame).
fn dressing_scene() -> crate::Scene {
    let mut scene = crate::Scene::demo();
    scene.cloth.solver = SolverName::Vbd;
    scene.effects.self_collision = true;
    scene.scene.body_step = 0.0;
    scene.scene.settle = 0.0;
    scene
}

fn solver(
    scene: &crate::Scene,
    garment: &PolyMesh,
    held: &[u32],
) -> Result<Box<dyn tryon_core::stages::ClothSolver>, WearError> {
    crate::build::solver(scene, garment, vec![], held, &[], &[])
        .map_err(|e| build_err("the cloth solver")(e.to_string()))
}

/// The pipeline the kimono is put on with: the inflating body against the exact collider, the
/// fold line held.
fn dressing(
    st: &Stand,
    s: &WearSettings,
    garment: &PolyMesh,
    fold_line: &[u32],
) -> Result<Pipeline, WearError> {
    let scene = dressing_scene();
    let flat_body = PolyMesh::from_triangles(st.squashed(kimono::dress::SQUASH), &st.triangles)
        .map_err(|e| build_err("the mannequin mesh")(e.to_string()))?;
    let collider = crate::build::collider(
        CollisionMethod::Exact,
        &flat_body,
        scene.cloth.thickness,
        &scene.effects,
    )
    .map_err(|e| build_err("the body collider")(e.to_string()))?;
    let frames = s.inflate_frames + s.settle_frames;
    let parts = Parts {
        solver: solver(&scene, garment, fold_line)?,
        scene,
        body_mesh: flat_body,
        body: Box::new(Inflating {
            stand: st.clone(),
            settings: *s,
        }),
        motion: Some(Box::new(StillMotion {
            joints: 0,
            duration: frames as Real / s.fps,
        })),
        collider: Some(collider),
        garment: garment.clone(),
        fps: s.fps,
        frames,
    };
    Pipeline::from_parts(parts).map_err(|e| build_err("the dressing")(e.to_string()))
}

/// The tie on `p`'s loop: the rows drawn onto their rings by the solver's anchors, then held.
/// Returns the frames stepped, the rows' lag and the tied vertices (`tie::TiePlan::finish`).
fn tie_rows(
    p: &mut Pipeline,
    ls: &mut LoopState,
    st: &Stand,
    start: &Start,
    base: &KimonoMesh,
    lv: &kimono::Levels,
    s: &WearSettings,
    first: usize,
    on_frame: &mut dyn FnMut(&str, usize, usize),
) -> (usize, [Real; 3], Vec<u32>) {
    let job = tie::TieJob {
        m: &st.m,
        rest: &start.rest,
        base,
        levels: lv,
        frames: s.tie_frames,
        hold_frames: s.hold_frames,
        stiffness: s.hold_stiffness,
        under_bust: s.under_bust_tie,
    };
    let plan = tie::TiePlan::new(&job, &p.cloth.positions);
    let mut targets = plan.targets(0);
    let mut timers = Timers::default();
    for f in 1..=plan.frames {
        targets = plan.targets(f);
        p.solver.anchor(&plan.held, &targets, plan.stiffness);
        // The loop's clock goes on from the inflation's last frame.
        p.advance_coarse(ls, p.frame_time(first + f), &mut timers);
        on_frame("tie", f, plan.frames);
    }
    let (lag, tied) = plan.finish(&p.cloth.positions, &targets);
    (plan.frames, lag, tied)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_dressing_of_no_frames_returns_the_folded_start_and_a_wrong_shape_is_an_error() {
        let fam = kimono::family::flat_family().unwrap();
        let none = WearSettings {
            inflate_frames: 0,
            settle_frames: 0,
            tie_frames: 0,
            hold_frames: 0,
            ..WearSettings::default()
        };
        let w = kimono::family::BASE;
        let worn = wear(&w, &fam.base.positions, &fam.base, &none, &mut |_, _, _| {}).unwrap();
        assert_eq!(worn.positions.len(), fam.base.positions.len());
        assert_eq!(worn.frames, 0);
        // Nothing stepped: the start's crossings are the end's.
        assert_eq!(worn.crossings[0], worn.crossings[2]);
        assert!(worn.row_lag_m.iter().all(|l| l.is_finite()));
        let e = wear(
            &w,
            &fam.base.positions[..5],
            &fam.base,
            &none,
            &mut |_, _, _| {},
        )
        .unwrap_err();
        assert!(matches!(e, WearError::Shape { found: 5, .. }), "{e}");
    }

    #[test]
    fn a_fitted_kimono_is_held_by_its_whole_fold_line_while_the_body_grows() {
        // A fitted kimono's rows lie a few mm off the initial kimono's heights; its fold line
        // must still be held from sleeve end to sleeve end (it once held only the rows that
        // kept their height exactly, and the sleeves fell off the arms).
        let w = kimono::Wearer::new(1.62, 0.84, 0.64, 0.90);
        let fit = crate::kimono::fit_kimono(&w, crate::kimono::Targets::Flat).unwrap();
        let base = &fit.family.base;
        let line = kimono::dress::fold_line(base);
        let subs = base.sub_mesh_vertices();
        let sleeves = [
            kimono::mesh::sub::LEFT_SLEEVE,
            kimono::mesh::sub::RIGHT_SLEEVE,
        ];
        let span = |vs: &mut dyn Iterator<Item = u32>| {
            vs.map(|v| base.positions[v as usize].x)
                .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), x| {
                    (a.min(x), b.max(x))
                })
        };
        let sleeves: Vec<u32> = sleeves
            .iter()
            .flat_map(|&k| subs[k as usize].iter().copied())
            .collect();
        assert_eq!(
            span(&mut line.iter().copied()),
            span(&mut sleeves.iter().copied())
        );
        let off = line
            .iter()
            .map(|&v| (fit.positions[v as usize].y - base.positions[v as usize].y).abs())
            .fold(0.0, Real::max);
        assert!(off > 1e-3, "the fit moved the fold line by {off} m only");
        let grow = WearSettings {
            inflate_frames: 8,
            settle_frames: 0,
            tie_frames: 0,
            hold_frames: 0,
            ..WearSettings::default()
        };
        let worn = wear(&w, &fit.positions, base, &grow, &mut |_, _, _| {}).unwrap();
        // Held, the whole line keeps its place: one shift for every vertex of it.
        let moved = |v: u32| worn.positions[v as usize] - fit.positions[v as usize];
        // (The sleeves' part of it: the fold lays the fronts' layers apart, and the fronts' corners
        // at the armholes with them.)
        let fronts = [
            kimono::mesh::sub::LEFT_FRONT,
            kimono::mesh::sub::RIGHT_FRONT,
        ];
        let on_sleeves: Vec<u32> = line
            .iter()
            .copied()
            .filter(|v| sleeves.contains(v))
            .filter(|v| {
                fronts
                    .iter()
                    .all(|&k| subs[k as usize].binary_search(v).is_err())
            })
            .collect();
        assert!(
            on_sleeves.len() > 10,
            "{} fold vertices on the sleeves",
            on_sleeves.len()
        );
        let worst = on_sleeves
            .iter()
            .map(|&v| (moved(v) - moved(on_sleeves[0])).norm())
            .fold(0.0, Real::max);
        assert!(
            worst < 1e-9,
            "a fold line vertex moved {worst} m off the line's shift"
        );
    }
}
