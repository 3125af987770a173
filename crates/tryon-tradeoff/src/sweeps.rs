//! The sweeps: each point a real run of the pipeline. The report they feed is in `report.rs`.

use crate::plot::{Scale, Series, scatter};
use cloth_dyn::{ClothSim, IntegratorKind};
use pnt_surface::PnRefiner;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;
use tryon_core::frames::{CoarseFrame, FineSurface, lattice_index};
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_pipeline::run::Timers;
use tryon_pipeline::{Pipeline, Scene, Stats};

/// The stages that make up the surface (P1 section 4).
const SURFACE_STAGES: &[&str] = &["refine", "wrinkle", "fine_collision", "normals"];

/// Appends one line to the sweep log and echoes it to stderr as progress.
macro_rules! logln {
    ($log:expr, $($arg:tt)*) => {{
        let line = format!($($arg)*);
        eprintln!("{line}");
        $log.push_str(&line);
        $log.push('\n');
    }};
}

mod layers;
mod report;
mod solvers;

pub use report::run_all;

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/scenes")
}

/// A scene run: its stats and the pipeline afterwards.
fn run_scene(
    file: &str,
    sets: &[String],
    frames: Option<usize>,
) -> Result<(Stats, Pipeline), String> {
    let path = scenes_dir().join(file);
    // Every variant judged on every frame, so their figures compare.
    let mut sets = sets.to_vec();
    sets.push("output.referee_share=1".into());
    let scene = Scene::load_with_overrides(&path, &sets).map_err(|e| e.to_string())?;
    let mut p = Pipeline::new(scene).map_err(|e| format!("{}: {e}", path.display()))?;
    let out = p.run(frames, |_, _| {});
    Ok((out.stats, p))
}

/// Milliseconds per frame of everything but the referee.
fn frame_ms(s: &Stats) -> Real {
    s.stages
        .iter()
        .filter(|(k, _)| k.as_str() != "referee")
        .map(|(_, t)| t.ms_mean)
        .sum()
}

fn stage_ms(s: &Stats, names: &[&str]) -> Real {
    names
        .iter()
        .filter_map(|n| s.stages.get(*n))
        .map(|t| t.ms_mean)
        // (A fold from +0, not `sum`: an empty sum of floats is -0, printed "-0.00".)
        .fold(0.0, |a, b| a + b)
}

/// One collider setting's results on one scene.
#[derive(Clone, Debug)]
struct ColliderPoint {
    scene: &'static str,
    label: String,
    ms: Real,
    collider_ms: Real,
    max_mm: Real,
    p99_mm: Real,
    share: Real,
    stretch: Real,
}

/// The scenes of the collider sweep, by the names its points carry.
const COLLIDER_SCENES: [&str; 4] = ["drape", "drape64", "demo", "makehuman"];

fn collider_sweep(quick: bool, log: &mut String) -> Result<Vec<ColliderPoint>, String> {
    let settings: Vec<(String, Vec<String>)> = {
        let mut v = vec![("nearest_vertex".to_string(), vec![])];
        let sdf: &[usize] = if quick { &[32] } else { &[32, 64, 128] };
        let depth: &[usize] = if quick { &[128] } else { &[128, 256, 512] };
        for r in sdf {
            v.push((
                format!("sdf {r}"),
                vec![
                    "effects.body_collision=\"sdf\"".into(),
                    format!("effects.sdf.resolution={r}"),
                ],
            ));
        }
        for r in depth {
            v.push((
                format!("depth_maps {r}"),
                vec![
                    "effects.body_collision=\"depth_maps\"".into(),
                    format!("effects.depth_maps.resolution={r}"),
                ],
            ));
        }
        v.push((
            "exact".to_string(),
            vec!["effects.body_collision=\"exact\"".into()],
        ));
        v
    };
    let scenes: [(&'static str, &str, &[&str], usize, usize); 4] = [
        ("drape", "drape-sphere.toml", &[], 8, 120),
        // Issue 2's resolution of the same scene.
        (
            "drape64",
            "drape-sphere.toml",
            &["garment.particles=64"],
            4,
            120,
        ),
        ("demo", "demo-dress-walk.toml", &[], 8, 90),
        ("makehuman", "makehuman-dress-walk.toml", &[], 4, 60),
    ];
    let mut out = Vec::new();
    for (name, file, extra, quick_frames, frames) in scenes {
        for (label, sets) in &settings {
            let mut sets = sets.clone();
            sets.extend(extra.iter().map(|s| s.to_string()));
            if label == "nearest_vertex" {
                sets.push("effects.body_collision=\"nearest_vertex\"".into());
            }
            let f = if quick { quick_frames } else { frames };
            let t0 = Instant::now();
            let (s, _) = run_scene(file, &sets, Some(f))?;
            let m = &s.metrics;
            let p = ColliderPoint {
                scene: name,
                label: label.clone(),
                ms: frame_ms(&s),
                collider_ms: stage_ms(&s, &["collider_update", "fine_collision"]),
                max_mm: m.max_penetration_m * 1e3,
                p99_mm: m.p99_penetration_m * 1e3,
                share: m.share_over_1mm,
                stretch: m.max_stretch,
            };
            logln!(
                log,
                "colliders: {name} {label}: {f} frames, {:.2} ms/frame, max {:.2} mm ({:.0} s)",
                p.ms,
                p.max_mm,
                t0.elapsed().as_secs_f64()
            );
            out.push(p);
        }
    }
    Ok(out)
}

/// The drape scene with its cloth solver replaced: for integrator sweeps at exact steps, on the
/// pipeline's own frame loop.
struct Drape {
    scene: Scene,
    /// The solver the scene assembles, whose parameters and model the sweeps vary.
    sim0: ClothSim,
}

impl Drape {
    fn new() -> Result<Self, String> {
        let path = scenes_dir().join("drape-sphere.toml");
        let scene = Scene::load(&path).map_err(|e| e.to_string())?;
        let p = Pipeline::new(scene.clone()).map_err(|e| e.to_string())?;
        let sim0 = tryon_pipeline::build::cloth_sim(&p.scene, &p.garment, vec![], &[])
            .map_err(|e| e.to_string())?;
        Ok(Drape { scene, sim0 })
    }

    /// Simulates `seconds` at fixed substep `h` with `kind` and stretch stiffness times `k_scale`;
    /// `raw` turns Provot's strain limit off (it would hide an unstable integrator).
    /// Returns the final frame, ms per output frame (1/60 s), and whether it stayed stable (no
    /// retry, rollback or non-finite value; no edge at 3 times its rest length: soft cloth without
    /// a strain limit may sag, an unstable step tears it apart).
    fn simulate(
        &self,
        kind: IntegratorKind,
        h: Real,
        seconds: Real,
        k_scale: Real,
        raw: bool,
    ) -> Result<(CoarseFrame, Real, bool), String> {
        let mut params = self.sim0.params.clone();
        if raw {
            params.max_strain = None;
        }
        params.auto_substep = false;
        params.max_substep = h;
        params.max_halvings = 0;
        params.stretch_guard = None;
        params.k_stretch *= k_scale;
        let mut model = self.sim0.model.clone();
        for s in &mut model.springs.k_stretch[model.structural.clone()] {
            *s *= k_scale;
        }
        model.packed = model.springs.packed();
        let mut p = Pipeline::new(self.scene.clone()).map_err(|e| e.to_string())?;
        p.set_solver(Box::new(ClothSim::new(model, params, kind)));
        if raw {
            // A flat sheet in free fall does not deform, so nothing would excite an unstable
            // step: jiggle every particle by up to 1 mm (deterministically).
            for (i, x) in p.cloth.positions.iter_mut().enumerate() {
                let r = |k: Real| ((i as Real + 1.0) * k).sin() * 1e-3;
                *x += Vec3::new(r(12.9898), r(78.233), r(37.719));
            }
        }
        let frames = (seconds * p.fps).round() as usize;
        let mut stable = true;
        let mut st = p.start();
        let mut timers = Timers::default();
        let t0 = Instant::now();
        for k in 1..=frames {
            let r = p.advance(&mut st, p.frame_time(k), &mut timers);
            if r.retries + r.rollbacks + r.non_finite_events > 0 {
                stable = false;
            }
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3 / frames.max(1) as Real;
        let info = p.solver.info();
        let x = &p.cloth.positions;
        let worst = info
            .edges
            .iter()
            .zip(&info.rest)
            .map(|(e, r)| (x[e[0] as usize] - x[e[1] as usize]).norm() / r)
            .fold(0.0, Real::max);
        if !(worst < 3.0) {
            stable = false;
        }
        Ok((p.cloth, ms, stable))
    }
}

#[derive(Clone, Debug)]
struct IntegratorPoint {
    integrator: &'static str,
    h_ms: Real,
    ms: Real,
    error_mm: Real,
    stable: bool,
}

#[derive(Clone, Debug)]
struct StablePoint {
    integrator: &'static str,
    k_scale: Real,
    largest_ms: Option<Real>,
}

const KINDS: [IntegratorKind; 3] = [
    IntegratorKind::Rk4,
    IntegratorKind::SymplecticEuler,
    IntegratorKind::ImplicitEuler,
];

fn integrator_sweep(
    quick: bool,
    log: &mut String,
) -> Result<(Vec<IntegratorPoint>, Vec<StablePoint>, Real), String> {
    let drape = Drape::new()?;
    let seconds = if quick { 0.25 } else { 0.5 };
    let h_ref = if quick { 2e-4 } else { 5e-5 };
    let (reference, _, _) = drape.simulate(IntegratorKind::Rk4, h_ref, seconds, 1.0, false)?;
    let steps: &[Real] = if quick {
        &[1e-3, 4e-3]
    } else {
        &[2.5e-4, 5e-4, 1e-3, 2e-3, 4e-3, 8.333e-3, 1.6667e-2]
    };
    let mut points = Vec::new();
    for kind in KINDS {
        for &h in steps {
            let (f, ms, stable) = drape.simulate(kind, h, seconds, 1.0, false)?;
            let n = f.positions.len().max(1) as Real;
            let rms = (f
                .positions
                .iter()
                .zip(&reference.positions)
                .map(|(a, b)| (a - b).norm_squared())
                .sum::<Real>()
                / n)
                .sqrt();
            let p = IntegratorPoint {
                integrator: kind.as_str(),
                h_ms: h * 1e3,
                ms,
                error_mm: if rms.is_finite() {
                    rms * 1e3
                } else {
                    Real::INFINITY
                },
                stable,
            };
            logln!(
                log,
                "integrators: {} h {:.3} ms: error {:.3} mm, {:.2} ms/frame, stable {}",
                p.integrator,
                p.h_ms,
                p.error_mm,
                p.ms,
                p.stable
            );
            points.push(p);
        }
    }
    // Largest stable step against stiffness: steps 0.25 ms * sqrt(2)^k up to a frame.
    let scales: &[Real] = if quick {
        &[1.0, 16.0]
    } else {
        &[1.0, 4.0, 16.0, 64.0]
    };
    let candidates: Vec<Real> = (0..)
        .map(|k| 2.5e-4 * (2.0 as Real).sqrt().powi(k))
        .take_while(|h| *h <= 1.0 / 60.0 + 1e-9)
        .collect();
    let stable_seconds = if quick { 0.3 } else { 0.5 };
    let mut stable = Vec::new();
    for kind in KINDS {
        for &k in scales {
            let mut largest = None;
            for &h in &candidates {
                let (_, _, ok) = drape.simulate(kind, h, stable_seconds, k, true)?;
                if ok {
                    largest = Some(h * 1e3);
                } else {
                    break;
                }
            }
            logln!(
                log,
                "stability: {} k x{k}: largest stable step {largest:?} ms",
                kind.as_str()
            );
            stable.push(StablePoint {
                integrator: kind.as_str(),
                k_scale: k,
                largest_ms: largest,
            });
        }
    }
    Ok((points, stable, h_ref * 1e3))
}

#[derive(Clone, Debug)]
struct RefinePoint {
    level: u8,
    fine_vertices: usize,
    ms: Real,
    max_dev_mm: Real,
    mean_dev_mm: Real,
}

/// Deviation of the piecewise-linear level-`l` surface from the level-`top` PN surface on the same
/// coarse state: every level-`top` vertex against the level-`l` lattice at the same parameters.
fn deviation(fine: &FineSurface, top: &FineSurface) -> (Real, Real) {
    let n = fine.segments;
    let (mut max, mut sum) = (0.0 as Real, 0.0);
    for (v, src) in top.sources.iter().enumerate() {
        let f = src.face as usize;
        let base = f * tryon_core::frames::lattice_len(n);
        let s = src.bary[1] * n as Real;
        let t = src.bary[2] * n as Real;
        let i0 = (s.floor() as u32).min(n);
        let j0 = (t.floor() as u32).min(n - i0.min(n));
        let (fs, ft) = (s - i0 as Real, t - j0 as Real);
        let at = |i: u32, j: u32| {
            let i = i.min(n);
            let j = j.min(n - i);
            fine.positions[fine.lattice[base + lattice_index(n, i, j)] as usize]
        };
        let p = if i0 + j0 >= n {
            at(i0, j0)
        } else if fs + ft <= 1.0 {
            at(i0, j0) * (1.0 - fs - ft) + at(i0 + 1, j0) * fs + at(i0, j0 + 1) * ft
        } else {
            at(i0 + 1, j0 + 1) * (fs + ft - 1.0)
                + at(i0, j0 + 1) * (1.0 - fs)
                + at(i0 + 1, j0) * (1.0 - ft)
        };
        let d = (p - top.positions[v]).norm();
        max = max.max(d);
        sum += d;
    }
    (max, sum / top.sources.len().max(1) as Real)
}

fn refine_sweep(quick: bool, log: &mut String) -> Result<Vec<RefinePoint>, String> {
    let frames = if quick { 6 } else { 60 };
    let top_level = if quick { 5 } else { 6 };
    let mut out = Vec::new();
    for level in 0..=4u8 {
        let sets = vec![format!("effects.refine={level}")];
        let (s, p) = run_scene("demo-dress-walk.toml", &sets, Some(frames))?;
        let x = &p.cloth.positions;
        let mut normals = Vec::new();
        let (tris, _) = p.garment.triangulate();
        vertex_normals(x, &tris, &mut normals);
        let (mut fine, mut top) = (FineSurface::default(), FineSurface::default());
        PnRefiner::new(&p.garment, level)
            .map_err(|e| e.to_string())?
            .evaluate(x, &normals, &mut fine);
        PnRefiner::new(&p.garment, top_level)
            .map_err(|e| e.to_string())?
            .evaluate(x, &normals, &mut top);
        let (max, mean) = deviation(&fine, &top);
        let point = RefinePoint {
            level,
            fine_vertices: s.counts.fine_vertices.unwrap_or(s.counts.coarse_vertices),
            ms: stage_ms(&s, SURFACE_STAGES),
            max_dev_mm: max * 1e3,
            mean_dev_mm: mean * 1e3,
        };
        logln!(
            log,
            "refine: level {level}: {} fine vertices, {:.2} ms, deviation from level {top_level} max {:.3} mean {:.3} mm",
            point.fine_vertices,
            point.ms,
            point.max_dev_mm,
            point.mean_dev_mm
        );
        out.push(point);
    }
    Ok(out)
}

#[derive(Clone, Debug)]
struct WrinklePoint {
    scene: &'static str,
    /// "off", or the wrinkle model.
    model: &'static str,
    ms: Real,
    length_error: Real,
    /// The same run's reference surface (wrinkles not applied), and the shares restored.
    reference_error: Real,
    restored: Real,
    reference_restored: Real,
}

fn wrinkle_sweep(quick: bool, log: &mut String) -> Result<Vec<WrinklePoint>, String> {
    let frames = if quick { 6 } else { 90 };
    let mut out = Vec::new();
    for scene in ["demo-dress-walk", "shirt-elbow-bend"] {
        for model in ["off", "force", "compression"] {
            let mut sets = vec!["effects.refine=2".to_string()];
            sets.push(format!("effects.wrinkles={}", model != "off"));
            if model != "off" {
                sets.push(format!("effects.wrinkle_model=\"{model}\""));
            }
            let (s, _) = run_scene(&format!("{scene}.toml"), &sets, Some(frames))?;
            let m = &s.metrics;
            let p = WrinklePoint {
                scene,
                model,
                ms: stage_ms(&s, SURFACE_STAGES),
                length_error: m.length_error.unwrap_or(Real::NAN),
                reference_error: m.length_error_reference.unwrap_or(Real::NAN),
                restored: m.length_restored_share.unwrap_or(Real::NAN),
                reference_restored: m.length_restored_share_reference.unwrap_or(Real::NAN),
            };
            logln!(
                log,
                "{scene} wrinkles {model}: surface {:.2} ms, length error {:.4}",
                p.ms,
                p.length_error
            );
            out.push(p);
        }
    }
    Ok(out)
}

#[derive(Clone, Debug)]
struct GuardPoint {
    label: &'static str,
    cloth_ms: Real,
    retries: u32,
    max_stretch: Real,
    mean_stretch: Real,
    /// Share of frames with some structural edge over 1.1 times its rest length.
    over: Real,
    max_mm: Real,
}

/// The stretch guard on the demo walk under P1's solver (the guard is its retry rule): what its
/// retries cost in the cloth stage, against the stretch they prevent.
fn guard_sweep(quick: bool, log: &mut String) -> Result<Vec<GuardPoint>, String> {
    let frames = if quick { Some(12) } else { None };
    let mut out = Vec::new();
    for (label, guard) in [("1.1 (default)", 1.1), ("1.2", 1.2), ("off", 0.0)] {
        let sets = vec![
            "cloth.solver=\"p1\"".to_string(),
            format!("cloth.p1.stretch_guard={guard}"),
        ];
        let (s, _) = run_scene("demo-dress-walk.toml", &sets, frames)?;
        let m = &s.metrics;
        let over = s.per_frame.iter().filter(|f| f.max_stretch > 1.1).count() as Real
            / s.per_frame.len().max(1) as Real;
        let p = GuardPoint {
            label,
            cloth_ms: stage_ms(&s, &["cloth"]),
            retries: m.substep_retries,
            max_stretch: m.max_stretch,
            mean_stretch: m.mean_stretch,
            over,
            max_mm: m.max_penetration_m * 1e3,
        };
        logln!(
            log,
            "guard {label}: cloth {:.2} ms/frame, {} retries, stretch max {:.3} mean {:.4}, frames over 1.1 {:.2}, penetration max {:.2} mm",
            p.cloth_ms,
            p.retries,
            p.max_stretch,
            p.mean_stretch,
            p.over,
            p.max_mm
        );
        out.push(p);
    }
    Ok(out)
}

#[derive(Clone, Debug)]
struct SpotPoint {
    label: &'static str,
    ms: Real,
    wall_ms: Real,
    max_mm: Real,
    p99_mm: Real,
    share: Real,
}

fn spot_sweep(quick: bool, log: &mut String) -> Result<Vec<SpotPoint>, String> {
    let frames = if quick { Some(8) } else { None };
    let runs: [(&'static str, &[&str]); 4] = [
        (
            "coarse only (no fine correction)",
            &["effects.fine_collision=false"],
        ),
        ("fine corrected by depth maps", &[]),
        (
            "fine corrected by exact referee",
            &["effects.fine_collider=\"exact\""],
        ),
        (
            "depth maps, pipelined (rayon::join)",
            &["scene.pipelined=true"],
        ),
    ];
    let mut out = Vec::new();
    for (label, sets) in runs {
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        let (s, _) = run_scene("cloth-on-spot.toml", &sets, frames)?;
        let m = &s.metrics;
        let p = SpotPoint {
            label,
            ms: frame_ms(&s),
            wall_ms: s.loop_s * 1e3 / s.frames.max(1) as Real
                - s.stages.get("referee").map_or(0.0, |t| t.ms_mean),
            max_mm: m.max_penetration_m * 1e3,
            p99_mm: m.p99_penetration_m * 1e3,
            share: m.share_over_1mm,
        };
        logln!(
            log,
            "spot: {label}: {:.2} ms/frame of stages, {:.2} ms/frame wall, fine penetration max {:.2} p99 {:.2} mm",
            p.ms,
            p.wall_ms,
            p.max_mm,
            p.p99_mm
        );
        out.push(p);
    }
    Ok(out)
}
