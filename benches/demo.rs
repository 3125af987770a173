//! Criterion benchmarks of whole frames, single thread. The demo scene (mannequin walking in the
//! dress, about 350 coarse particles; under P1's solver and the scene's own, VBD): motion, skinning (7.5k body vertices), following, collider
//! update and the cloth step (its surface stages are left out: see `surface`). And
//! makehuman-dress-walk as a user runs it (exact collider, refined surface with fine collision,
//! with and without `fine_pokes`; skipped when the shared assets are absent): every stage a frame
//! runs, so a cost the cloth-step benchmark cannot see (a collider starting cold after the fine
//! surface's queries) shows here. The referee (accuracy) is not timed; `tryon run` reports it.
//! Each timed iteration is one walking frame; the pipeline is rebuilt (untimed) when the clip ends.

use criterion::{Criterion, criterion_group, criterion_main};
use std::time::{Duration, Instant};
use tryon_pipeline::LoopState;
use tryon_pipeline::run::Timers;
use tryon_pipeline::scene::SolverName;
use tryon_pipeline::{Pipeline, Scene};

fn fresh(solver: SolverName) -> Run {
    // The coarse frame only (the surface stages have their own benchmark, `surface`).
    let mut scene = Scene::demo();
    scene.effects.refine = 0;
    scene.cloth.solver = solver;
    let mut p = Pipeline::new(scene).unwrap_or_else(|e| panic!("demo scene: {e}"));
    let mut st = p.start();
    let mut timers = Timers::default();
    // Untimed: settle and start walking.
    let first = 30;
    for k in 1..first {
        p.advance(&mut st, p.frame_time(k), &mut timers);
    }
    (p, st, first)
}

/// A pipeline, its loop state and the next frame to run.
type Run = (Pipeline, LoopState, usize);

/// The wall time of `iters` frames of `run`, each advanced inside `within` (a thread pool's
/// `install`, or directly); `restart` rebuilds the run (untimed) when its clip ends, and the
/// timing stops early when it cannot.
fn timed_frames(
    iters: u64,
    run: &mut Run,
    restart: &mut dyn FnMut() -> Option<Run>,
    within: &dyn Fn(&mut (dyn FnMut() + Send)),
) -> Duration {
    let mut total = Duration::ZERO;
    let mut timers = Timers::default();
    for _ in 0..iters {
        if run.2 >= run.0.frames {
            let Some(again) = restart() else {
                break;
            };
            *run = again;
        }
        let (p, st, k) = run;
        let t0 = Instant::now();
        within(&mut || {
            std::hint::black_box(p.advance(st, p.frame_time(*k), &mut timers));
        });
        total += t0.elapsed();
        *k += 1;
    }
    total
}

/// makehuman-dress-walk with `sets`, run untimed to frame 30 (`None` without the shared assets).
fn makehuman(sets: &[&str]) -> Option<Run> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../data/scenes/makehuman-dress-walk.toml");
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let scene = Scene::load_with_overrides(&path, &sets)
        .map_err(|e| eprintln!("skipped makehuman-dress-walk: {e}"))
        .ok()?;
    let mut p = Pipeline::new(scene)
        .map_err(|e| eprintln!("skipped makehuman-dress-walk: {e}"))
        .ok()?;
    let mut st = p.start();
    let mut timers = Timers::default();
    let first = 30;
    for k in 1..first {
        p.advance(&mut st, p.frame_time(k), &mut timers);
    }
    Some((p, st, first))
}

fn makehuman_frame(c: &mut Criterion) {
    let mut group = c.benchmark_group("makehuman_frame");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(1).build() else {
        return;
    };
    let cases: [(&str, &[&str]); 2] = [
        ("walk_dress_exact_refine1", &[]),
        (
            "walk_dress_exact_refine1_no_pokes",
            &["effects.fine_pokes=false"],
        ),
    ];
    for (name, sets) in cases {
        let Some(mut run) = pool.install(|| makehuman(sets)) else {
            continue;
        };
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let restart = &mut || pool.install(|| makehuman(sets));
                timed_frames(iters, &mut run, restart, &|f| pool.install(f))
            })
        });
    }
    group.finish();
}

fn demo_frame(c: &mut Criterion) {
    let mut group = c.benchmark_group("demo_frame");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    // P1's solver (the paper's) and the demo's own, VBD.
    for (name, solver) in [
        ("walk_dress_rk4", SolverName::P1),
        ("walk_dress_vbd", SolverName::Vbd),
    ] {
        let mut run = fresh(solver);
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let restart = &mut || Some(fresh(solver));
                timed_frames(iters, &mut run, restart, &|f| f())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, demo_frame, makehuman_frame);
criterion_main!(benches);
