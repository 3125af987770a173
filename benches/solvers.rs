//! Criterion benchmarks of the garment solvers' cloth step alone (`ClothSolver::step_frame`), on one
//! thread and on two: VBD on the drape at N = 64 and 128 (plain, with its strain limit at rest
//! length, and with the cloth's contact with itself), and on the MakeHuman walk (plain, with
//! the nearest-vertex collider instead of the scene's exact one, with hinges or
//! self-contact; skipped when
//! the shared assets are absent). Each scene is run untimed to a frame in contact (the drape after
//! 1 s, the walk at frame 30); every timed iteration then steps that same frame from the same cloth
//! and solver state against the same body, so one and two threads do the same work. The VBD sweep gives the
//! same result for any thread count (tests: `vbd_is_the_same_on_any_thread_count`).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::path::Path;
use std::time::{Duration, Instant};
use tryon_core::stages::Collider;
use tryon_pipeline::run::Timers;
use tryon_pipeline::{Pipeline, Scene};

/// A scene of data/scenes with overrides, run untimed for `frames` frames.
fn ready(file: &str, sets: &[&str], frames: usize) -> Option<Pipeline> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/scenes")
        .join(file);
    let mut sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    sets.push("effects.refine=0".into());
    let scene = match Scene::load_with_overrides(&path, &sets) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("skipped {file}: {e}");
            return None;
        }
    };
    let mut p = match Pipeline::new(scene) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("skipped {file}: {e}");
            return None;
        }
    };
    let mut st = p.start();
    let mut timers = Timers::default();
    for k in 1..=frames {
        p.advance(&mut st, p.frame_time(k), &mut timers);
    }
    Some(p)
}

fn cloth_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("cloth_step");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let cases: [(&str, &str, &[&str], usize); 14] = [
        (
            "vbd_drape_64",
            "drape-sphere.toml",
            &["cloth.solver=\"vbd\"", "garment.particles=64"],
            60,
        ),
        (
            "vbd_drape_128",
            "drape-sphere.toml",
            &["cloth.solver=\"vbd\"", "garment.particles=128"],
            60,
        ),
        (
            "vbd_limit_drape_64",
            "drape-sphere.toml",
            &[
                "cloth.solver=\"vbd\"",
                "garment.particles=64",
                "cloth.vbd.limit=1.0",
            ],
            60,
        ),
        (
            "vbd_limit_drape_128",
            "drape-sphere.toml",
            &[
                "cloth.solver=\"vbd\"",
                "garment.particles=128",
                "cloth.vbd.limit=1.0",
            ],
            60,
        ),
        // The scene's own collider (exact, with the swept test) and P1's nearest-vertex one.
        ("vbd_makehuman_walk", "makehuman-dress-walk.toml", &[], 30),
        (
            "vbd_makehuman_walk_tracker",
            "makehuman-dress-walk.toml",
            &["effects.body_collision=\"nearest_vertex\""],
            30,
        ),
        (
            "vbd_makehuman_walk_dihedral",
            "makehuman-dress-walk.toml",
            &["cloth.vbd.dihedral=1e-4", "cloth.vbd.flexion=0"],
            30,
        ),
        (
            "vbd_self_drape_64",
            "drape-sphere.toml",
            &[
                "cloth.solver=\"vbd\"",
                "garment.particles=64",
                "effects.self_collision=true",
            ],
            60,
        ),
        (
            "vbd_self_drape_128",
            "drape-sphere.toml",
            &[
                "cloth.solver=\"vbd\"",
                "garment.particles=128",
                "effects.self_collision=true",
            ],
            60,
        ),
        (
            "vbd_self_hash_drape_64",
            "drape-sphere.toml",
            &[
                "cloth.solver=\"vbd\"",
                "garment.particles=64",
                "effects.self_collision=true",
                "cloth.self_broad_phase=\"hash\"",
            ],
            60,
        ),
        (
            "vbd_self_hash_drape_128",
            "drape-sphere.toml",
            &[
                "cloth.solver=\"vbd\"",
                "garment.particles=128",
                "effects.self_collision=true",
                "cloth.self_broad_phase=\"hash\"",
            ],
            60,
        ),
        (
            "vbd_self_makehuman_walk",
            "makehuman-dress-walk.toml",
            &["effects.self_collision=true"],
            30,
        ),
        // Two garments (a slip under the dress) with and without contact between them.
        ("vbd_layered_walk", "layered-walk.toml", &[], 60),
        (
            "vbd_layered_walk_no_contact",
            "layered-walk.toml",
            &["effects.cloth_collision=false"],
            60,
        ),
    ];
    for (name, file, sets, frames) in cases {
        let Some(mut p) = ready(file, sets, frames) else {
            continue;
        };
        let dt = 1.0 / p.fps;
        let start = p.cloth.clone();
        // The solver's state between frames too (VBD's self-contact remembers the last frame's
        // end): without it every iteration after the first reopened a whole frame's motion.
        let solver0 = p.solver.boxed_clone();
        for threads in [1usize, 2] {
            let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(threads).build() else {
                continue;
            };
            group.bench_with_input(BenchmarkId::new(name, threads), &threads, |b, _| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        p.cloth.clone_from(&start);
                        if let Some(s) = solver0.as_ref().and_then(|s| s.boxed_clone()) {
                            p.solver = s;
                        }
                        let (solver, cloth) = (&mut p.solver, &mut p.cloth);
                        let collider: Option<&mut dyn Collider> = p.collider.as_deref_mut();
                        let Some(collider) = collider else {
                            continue;
                        };
                        let t = Instant::now();
                        pool.install(|| {
                            std::hint::black_box(solver.step_frame(cloth, dt, collider))
                        });
                        total += t.elapsed();
                    }
                    total
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, cloth_step);
criterion_main!(benches);
