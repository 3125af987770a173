//! Budgets checked before a run starts: frames, particles, fine vertices, substeps per frame,
//! memory and time are estimated from the scene as assembled so far and held against limits, so
//! that no accepted scene runs for hours or exhausts memory by accident. Each limit can be raised
//! (`tryon run --limit KEY=VALUE`); the error names the scene key that drives the estimate.
//!
//! The memory and time models are rough, fitted on this project's release build on a 2-core
//! machine (docs/decisions, *budgets*): a run's peak memory is about 50 MB plus 4 kB per
//! particle, 1.2 kB per fine vertex, 22 B per signed-distance cell and 58 B per depth-map pixel;
//! a frame costs about 1 us per particle, substep and solver iteration plus 8 us per fine vertex
//! (the surface stages and the exact referee).

use crate::scene::{CollisionMethod, Scene, SolverName};
use thiserror::Error;
use tryon_core::math::Real;
use tryon_core::mesh::PolyMesh;

/// The limits a scene's estimate is held against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    pub frames: usize,
    pub particles: usize,
    pub fine_vertices: usize,
    pub substeps: usize,
    pub memory_gb: Real,
    pub hours: Real,
    /// scene.glb's size (GB); GLB itself ends at 4 GiB.
    pub glb_gb: Real,
}

impl Default for Limits {
    /// Sized for a workstation like this project's (2 cores, 23 GB): the largest shipped scene
    /// estimates under a tenth of each.
    fn default() -> Self {
        Limits {
            frames: 200_000,
            particles: 150_000,
            fine_vertices: 4_000_000,
            substeps: 2_000,
            memory_gb: 8.0,
            hours: 4.0,
            glb_gb: GLB_MAX_GB,
        }
    }
}

/// The keys `--limit` takes, with what each bounds.
pub const LIMIT_KEYS: &str =
    "frames, particles, fine_vertices, substeps (a frame), memory_gb, hours, glb_gb";

/// GLB's own limit, 4 GiB, in GB.
pub const GLB_MAX_GB: Real = 4.294_967_295;

impl Limits {
    /// Applies one `KEY=VALUE` (the command line's `--limit`).
    pub fn set(&mut self, assignment: &str) -> Result<(), String> {
        let (key, value) = assignment.split_once('=').ok_or_else(|| {
            format!("`{assignment}`: expected KEY=VALUE, KEY one of {LIMIT_KEYS}")
        })?;
        let number: Real = value
            .trim()
            .parse()
            .ok()
            .filter(|v: &Real| v.is_finite() && *v > 0.0)
            .ok_or_else(|| format!("`{assignment}`: {value} is not a positive number"))?;
        let whole = || number.min(usize::MAX as Real).ceil() as usize;
        match key.trim() {
            "frames" => self.frames = whole(),
            "particles" => self.particles = whole(),
            "fine_vertices" => self.fine_vertices = whole(),
            "substeps" => self.substeps = whole(),
            "memory_gb" => self.memory_gb = number,
            "hours" => self.hours = number,
            "glb_gb" if number > GLB_MAX_GB => {
                return Err(format!(
                    "`{assignment}`: a GLB ends at 4 GiB ({GLB_MAX_GB} GB)"
                ));
            }
            "glb_gb" => self.glb_gb = number,
            other => return Err(format!("`{other}` is not a limit: one of {LIMIT_KEYS}")),
        }
        Ok(())
    }
}

/// What a scene is estimated to take.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Estimate {
    pub frames: usize,
    pub particles: usize,
    pub substeps: usize,
    /// Solver sweeps per substep (1 for P1's integrators).
    pub iterations: usize,
    pub fine_vertices: usize,
    pub memory_gb: Real,
    pub hours: Real,
    /// scene.glb's size (GB; 0 when the scene writes none).
    pub glb_gb: Real,
    pub solver: SolverName,
}

/// Why a scene is refused before it runs.
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "{what}: about {estimate}, over the limit of {limit}; {change}, or raise it with `--limit {key}=N`"
)]
pub struct BudgetError {
    pub what: &'static str,
    pub key: &'static str,
    pub estimate: String,
    pub limit: String,
    pub change: String,
}

/// The estimate for `scene` with `garment` (the joined cloth) on a body of `body_vertices`,
/// simulated at `substep` seconds, over `frames` frames.
pub fn estimate(
    scene: &Scene,
    garment: &PolyMesh,
    body_vertices: usize,
    substep: Real,
    frames: usize,
) -> Estimate {
    let c = &scene.cloth;
    let fx = &scene.effects;
    let particles = garment.positions.len();
    let per_frame = 1.0 / (scene.scene.fps * substep.max(1e-12));
    let substeps = (per_frame - 1e-9).ceil().clamp(1.0, 1e15) as usize;
    let iterations = c.solver.iterations(c);
    let fine_vertices = match fx.refine {
        0 => 0,
        level => fine_vertex_count(garment, level),
    };
    let grid = |m: Option<CollisionMethod>| match m {
        Some(CollisionMethod::Sdf) => 22.0 * (fx.sdf.resolution as Real).powi(3),
        Some(CollisionMethod::DepthMaps) => 58.0 * 6.0 * (fx.depth_maps.resolution as Real).powi(2),
        _ => 0.0,
    };
    let fine_collider =
        (fx.refine > 0 && fx.fine_collision).then(|| fx.fine_collider.unwrap_or(fx.body_collision));
    let bytes = 50e6
        + 4e3 * particles as Real
        + 1.2e3 * fine_vertices as Real
        + grid(Some(fx.body_collision))
        + grid(fine_collider);
    let frame_us =
        particles as Real * substeps as Real * iterations as Real + 8.0 * fine_vertices as Real;
    // A frame of scene.glb: each output garment vertex's position and normal (f32), and the
    // body's sparse offsets (the demo's 10,000 frames: 211 kB a frame, 5,314 fine and 7,506 body
    // vertices).
    let shown = if fine_vertices > 0 {
        fine_vertices
    } else {
        particles
    };
    let glb_frame = 24.0 * shown as Real + 12.0 * body_vertices as Real;
    let glb_gb = match scene.output.glb {
        true => frames as Real * glb_frame / 1e9,
        false => 0.0,
    };
    Estimate {
        glb_gb,
        frames,
        particles,
        substeps,
        iterations,
        fine_vertices,
        memory_gb: bytes / 1e9,
        hours: frames as Real * frame_us / 1e6 / 3600.0,
        solver: c.solver,
    }
}

/// Microseconds a frame's stages take and one judged frame of the referee takes, from the run's
/// counts: `output_vertices` (the refined surface, or the cloth), `body` (vertices, triangles).
/// A fit on this project's release build, one thread of a 2-core machine, over the shipped scenes
/// (docs/decisions, *referee stride*): low for the frame (the solver's sweeps, the surface, the
/// skinning) and high for the referee (an exact body query and a crossing test per output vertex),
/// so that the share it sets is rather undershot than passed.
pub fn frame_and_referee_us(
    e: &Estimate,
    output_vertices: usize,
    body: (usize, usize),
) -> (Real, Real) {
    let per_sweep = match e.solver {
        SolverName::Vbd => 0.25,
        SolverName::Xpbd => 0.2,
        SolverName::P1 => 0.5,
    };
    let sweeps = (e.particles * e.substeps * e.iterations) as Real;
    let frame = per_sweep * sweeps + 0.5 * e.fine_vertices as Real + 0.05 * body.0 as Real;
    let referee = 5.0 * output_vertices as Real + 0.05 * body.1 as Real;
    (frame, referee)
}

/// Every how many frames the referee judges so that it takes about `share` of a run's time (1:
/// every frame), from [`frame_and_referee_us`]: judged one frame in `n`, it takes
/// `r / n / (f + r / n)` of the time, at most `share` when `n >= r (1 - share) / (share f)`.
pub fn referee_stride(
    e: &Estimate,
    output_vertices: usize,
    body: (usize, usize),
    share: Real,
) -> usize {
    if !(share < 1.0) {
        return 1;
    }
    let (f, r) = frame_and_referee_us(e, output_vertices, body);
    let n = r * (1.0 - share) / (share.max(1e-3) * f.max(1.0));
    (n.ceil() as usize).clamp(1, 1000)
}

/// Fine vertices of `coarse` refined at `level` (as `pnt_surface::PnRefiner` builds them).
pub fn fine_vertex_count(coarse: &PolyMesh, level: u8) -> usize {
    let (tris, _) = coarse.triangulate();
    let mut edges: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    pnt_surface::fine_vertex_count(coarse.positions.len(), edges.len(), tris.len(), level)
}

/// `e` against `limits`: the first limit it passes, naming what to change in the scene.
pub fn check(e: &Estimate, limits: &Limits) -> Result<(), BudgetError> {
    let substeps_change = e.solver.substep_hint();
    let count = |n: usize| n.to_string();
    // (over, what, key, estimate, limit, what to change), in the order they are judged.
    let rows = [
        (
            e.frames > limits.frames,
            "frames",
            "frames",
            count(e.frames),
            count(limits.frames),
            "lower scene.duration or scene.fps, or run fewer with --frames",
        ),
        (
            e.particles > limits.particles,
            "garment particles",
            "particles",
            count(e.particles),
            count(limits.particles),
            "make the garment coarser ([garment] particles, columns or row_spacing)",
        ),
        (
            e.substeps > limits.substeps,
            "substeps a frame",
            "substeps",
            count(e.substeps),
            count(limits.substeps),
            substeps_change,
        ),
        (
            e.fine_vertices > limits.fine_vertices,
            "fine vertices",
            "fine_vertices",
            count(e.fine_vertices),
            count(limits.fine_vertices),
            "lower effects.refine",
        ),
        (
            e.memory_gb > limits.memory_gb,
            "peak memory",
            "memory_gb",
            format!("{:.1} GB", e.memory_gb),
            format!("{} GB", limits.memory_gb),
            "lower effects.refine, effects.sdf.resolution or effects.depth_maps.resolution, or make the garment coarser",
        ),
        (
            e.hours > limits.hours,
            "run time",
            "hours",
            format!("{:.1} h", e.hours),
            format!("{} h", limits.hours),
            "shorten the run (scene.duration, --frames), lower effects.refine or the solver's iterations, or make the garment coarser",
        ),
        (
            e.glb_gb > limits.glb_gb,
            "scene.glb",
            "glb_gb",
            format!("{:.2} GB", e.glb_gb),
            format!("{} GB", limits.glb_gb),
            "export fewer frames (scene.duration, --frames), a coarser surface (effects.refine), or none (output.glb = false)",
        ),
    ];
    match rows.into_iter().find(|r| r.0) {
        Some((_, what, key, estimate, limit, change)) => Err(BudgetError {
            what,
            key,
            estimate,
            limit,
            change: change.to_string(),
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn the_referee_stride_grows_with_what_judging_costs_against_a_frame() {
        let e = Estimate {
            particles: 2000,
            substeps: 4,
            iterations: 10,
            fine_vertices: 8000,
            solver: SolverName::Vbd,
            ..Estimate::default()
        };
        let body = (13000, 26000);
        // A frame of about 20 + 4 + 0.65 ms against a referee of about 40 + 1.3 ms: at a quarter,
        // one frame in ceil(3 x 41.3 / 24.65) = 6.
        assert_eq!(referee_stride(&e, 8000, body, 0.25), 6);
        assert_eq!(referee_stride(&e, 8000, body, 1.0), 1);
        // The same cloth unrefined: a frame of 20.65 ms against 10 + 1.3 ms judged, one in
        // ceil(3 x 11.3 / 20.65) = 2.
        let coarse = Estimate {
            fine_vertices: 0,
            ..e
        };
        assert_eq!(referee_stride(&coarse, 2000, body, 0.25), 2);
        // Nothing to judge against nothing to do stays finite.
        assert_eq!(referee_stride(&Estimate::default(), 0, (0, 0), 0.25), 1);
    }

    #[test]
    fn the_fine_vertex_count_is_the_refiners() {
        // A 3 x 2 grid of quads: 12 vertices, 12 triangles, 23 edges. At level 2 (4 segments an
        // edge): 12 + 23 * 3 + 12 * 3 = 117.
        let g = grid_xz(3, 2, 1.0, 1.0, 0.0);
        assert_eq!(fine_vertex_count(&g, 2), 117);
        for level in 1..=3 {
            let built = pnt_surface::PnRefiner::new(&g, level).unwrap();
            assert_eq!(
                fine_vertex_count(&g, level),
                built.sources.len(),
                "level {level}"
            );
        }
    }

    #[test]
    fn limits_take_known_keys_and_positive_numbers() {
        let mut l = Limits::default();
        l.set("hours=12").unwrap();
        l.set(" frames = 5e5 ").unwrap();
        assert_eq!((l.hours, l.frames), (12.0, 500_000));
        for bad in [
            "hours",
            "hours=0",
            "hours=-1",
            "hours=nan",
            "hours=inf",
            "speed=2",
        ] {
            let e = l.set(bad).unwrap_err();
            assert!(
                e.contains(bad.split('=').next().unwrap_or(bad)),
                "{bad}: {e}"
            );
        }
        assert!(l.set("speed=2").unwrap_err().contains("frames, particles"));
    }

    #[test]
    fn the_first_limit_passed_names_its_key_and_what_to_change() {
        let fine = Estimate {
            frames: 100,
            particles: 1000,
            substeps: 5,
            iterations: 10,
            fine_vertices: 10_000,
            memory_gb: 0.1,
            hours: 0.01,
            glb_gb: 0.5,
            solver: SolverName::Vbd,
        };
        let l = Limits::default();
        assert!(check(&fine, &l).is_ok());
        let cases = [
            (
                Estimate {
                    frames: 300_000,
                    ..fine
                },
                "--limit frames=N",
                "scene.duration",
            ),
            (
                Estimate {
                    particles: 200_000,
                    ..fine
                },
                "--limit particles=N",
                "[garment]",
            ),
            (
                Estimate {
                    substeps: 3000,
                    ..fine
                },
                "--limit substeps=N",
                "cloth.vbd.substep",
            ),
            (
                Estimate {
                    substeps: 3000,
                    solver: SolverName::P1,
                    ..fine
                },
                "--limit substeps=N",
                "cloth.spring_damping",
            ),
            (
                Estimate {
                    fine_vertices: 5_000_000,
                    ..fine
                },
                "fine_vertices=N",
                "effects.refine",
            ),
            (
                Estimate {
                    memory_gb: 9.0,
                    ..fine
                },
                "memory_gb=N",
                "about 9.0 GB",
            ),
            (Estimate { hours: 5.0, ..fine }, "hours=N", "about 5.0 h"),
            (
                Estimate {
                    glb_gb: 4.5,
                    ..fine
                },
                "glb_gb=N",
                "output.glb = false",
            ),
        ];
        for (e, flag, says) in cases {
            let text = check(&e, &l).unwrap_err().to_string();
            assert!(text.contains(flag) && text.contains(says), "{text}");
        }
    }
}
