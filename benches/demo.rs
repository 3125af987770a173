//! Criterion benchmark of one frame of the demo scene (mannequin walking in the dress, about 350
//! coarse particles): motion, skinning (7.5k body vertices), following, collider update and the
//! cloth step, single thread (the demo's surface stages are left out: see `surface`). The referee (accuracy) is not timed; `tryon demo` reports it.
//! Each timed iteration is one walking frame; the pipeline is rebuilt (untimed) when the clip ends.

use criterion::{Criterion, criterion_group, criterion_main};
use std::time::{Duration, Instant};
use tryon_pipeline::LoopState;
use tryon_pipeline::run::Timers;
use tryon_pipeline::{Pipeline, Scene};

fn fresh() -> (Pipeline, LoopState, usize) {
    // The coarse frame only (the surface stages have their own benchmark, `surface`).
    let mut scene = Scene::demo();
    scene.effects.refine = 0;
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

fn demo_frame(c: &mut Criterion) {
    let mut group = c.benchmark_group("demo_frame");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let (mut p, mut st, mut k) = fresh();
    group.bench_function("walk_dress_rk4", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            let mut timers = Timers::default();
            for _ in 0..iters {
                if k >= p.frames {
                    (p, st, k) = fresh();
                }
                let t0 = Instant::now();
                std::hint::black_box(p.advance(&mut st, p.frame_time(k), &mut timers));
                total += t0.elapsed();
                k += 1;
            }
            total
        })
    });
    group.finish();
}

criterion_group!(benches, demo_frame);
criterion_main!(benches);
