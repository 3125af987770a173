//! (g) The garment solvers on every scene: P1's particle cloth against XPBD and VBD, each scene's own
//! settings otherwise (`[cloth] solver`).

use super::*;
use tryon_pipeline::scene::SolverName;

/// One solver on one scene.
#[derive(Clone, Debug)]
pub(super) struct SolverPoint {
    pub scene: &'static str,
    pub solver: &'static str,
    pub max_mm: Real,
    pub p99_mm: Real,
    pub max_stretch: Real,
    pub mean_stretch: Real,
    pub retries: u32,
    pub rollbacks: u32,
    pub cloth_ms: Real,
}

/// The scenes compared, with the frames of a quick run (`None`: the scene's own length).
const SCENES: [(&str, Option<usize>); 7] = [
    ("drape-sphere.toml", Some(30)),
    ("demo-dress-walk.toml", Some(12)),
    ("skirt-walk.toml", Some(12)),
    ("dress-arm-raise.toml", Some(12)),
    ("cloth-on-spot.toml", Some(12)),
    ("makehuman-dress-walk.toml", Some(4)),
    ("makehuman-casual-131.toml", Some(4)),
];

/// The solvers compared: every one the schema has.
const SOLVERS: [SolverName; 3] = SolverName::ALL;
/// Variants run on one scene only: (scene, label, overrides). VBD's strain limit is for
/// free-hanging sheets (garments do worse with it).
const VARIANTS: [(&str, &str, &[&str]); 1] = [(
    "drape-sphere.toml",
    "vbd, limit 1.0",
    &["cloth.solver=\"vbd\"", "cloth.vbd.limit=1.0"],
)];
/// Points a complete sweep makes.
pub(super) const POINTS: usize = SCENES.len() * SOLVERS.len() + VARIANTS.len();

pub(super) fn solver_sweep(quick: bool, log: &mut String) -> Result<Vec<SolverPoint>, String> {
    let mut out = Vec::new();
    for (file, quick_frames) in SCENES {
        let runs = SOLVERS
            .iter()
            .map(|s| (s.as_str(), vec![format!("cloth.solver=\"{}\"", s.as_str())]))
            .chain(
                VARIANTS
                    .iter()
                    .filter(|v| v.0 == file)
                    .map(|&(_, label, sets)| (label, sets.iter().map(|s| s.to_string()).collect())),
            );
        for (solver, sets) in runs {
            let frames = if quick { quick_frames } else { None };
            let (s, _) = run_scene(file, &sets, frames)?;
            let m = &s.metrics;
            let p = SolverPoint {
                scene: file.trim_end_matches(".toml"),
                solver,
                max_mm: m.max_penetration_m * 1e3,
                p99_mm: m.p99_penetration_m * 1e3,
                max_stretch: m.max_stretch,
                mean_stretch: m.mean_stretch,
                retries: m.substep_retries,
                rollbacks: m.rollbacks,
                cloth_ms: stage_ms(&s, &["cloth"]),
            };
            logln!(
                log,
                "solver {} {solver}: penetration {:.2} mm, stretch {:.3}, {} retries, {} rollbacks, cloth {:.2} ms",
                p.scene,
                p.max_mm,
                p.max_stretch,
                p.retries,
                p.rollbacks,
                p.cloth_ms
            );
            out.push(p);
        }
    }
    Ok(out)
}

/// The report's section (g).
pub(super) fn section(r: &mut String, points: &[SolverPoint]) {
    let _ = writeln!(r, "\n## (g) Garment solvers on every scene\n");
    let _ = writeln!(
        r,
        "`[cloth] solver`: P1's particle cloth (RK4, strain limit) against XPBD (small substeps, contact and friction inside each) and VBD (vertex block descent of the implicit step's energy, contact and friction as energies). Penetration by the exact referee over the output surface, stretch over the coarse structural edges.\n"
    );
    let _ = writeln!(
        r,
        "| scene | solver | penetration max / p99 mm | stretch max / mean | retries / rollbacks | cloth ms/frame |\n|---|---|---|---|---|---|"
    );
    for p in points {
        let _ = writeln!(
            r,
            "| {} | {} | {:.2} / {:.2} | {:.3} / {:.4} | {} / {} | {:.2} |",
            p.scene,
            p.solver,
            p.max_mm,
            p.p99_mm,
            p.max_stretch,
            p.mean_stretch,
            p.retries,
            p.rollbacks,
            p.cloth_ms
        );
    }
}
