//! Criterion benchmarks of the drape scene: one output frame (1/60 s) at N = 32, 64, 128 particles
//! per side with each integrator. Every timed iteration steps from the same state, the cloth after 60
//! frames (1 s, draped on the sphere), restored untimed before each step, so the benchmark measures the
//! scene in contact rather than wherever thousands of iterations would carry it. Accuracy of the same
//! fixture is printed by `cargo xtask drape`.

use cloth_dyn::IntegratorKind;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::time::{Duration, Instant};
use tryon_pipeline::{DrapeConfig, DrapeScene};

fn drape_frame(c: &mut Criterion) {
    let mut group = c.benchmark_group("drape_frame");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for n in [32usize, 64, 128] {
        for kind in [
            IntegratorKind::Rk4,
            IntegratorKind::SymplecticEuler,
            IntegratorKind::ImplicitEuler,
        ] {
            let mut cfg = DrapeConfig::new(n, kind);
            cfg.measure_penetration = false;
            let Ok(mut scene) = DrapeScene::new(cfg) else {
                continue;
            };
            for _ in 0..60 {
                scene.step();
            }
            let settled = scene.pipeline.cloth.clone();
            group.bench_with_input(BenchmarkId::new(kind.as_str(), n), &n, |b, _| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        scene.pipeline.cloth.clone_from(&settled);
                        let t = Instant::now();
                        std::hint::black_box(scene.step());
                        total += t.elapsed();
                    }
                    total
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, drape_frame);
criterion_main!(benches);
