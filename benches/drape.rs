//! Criterion benchmarks of the drape scene: one output frame (1/60 s) at N = 32, 64, 128 particles
//! per side with each integrator, after 30 frames of settling so the cloth is in contact. Accuracy of
//! the same runs is printed by `cargo xtask drape` (timing and accuracy come from the same fixture).

use cloth_dyn::IntegratorKind;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::time::Duration;
use tryon_pipeline::{DrapeConfig, DrapeScene};

fn drape_frame(c: &mut Criterion) {
    let mut group = c.benchmark_group("drape_frame");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for n in [32usize, 64, 128] {
        for kind in [IntegratorKind::Rk4, IntegratorKind::SymplecticEuler] {
            let mut cfg = DrapeConfig::new(n, kind);
            cfg.measure_penetration = false;
            let Ok(mut scene) = DrapeScene::new(cfg) else {
                continue;
            };
            for _ in 0..30 {
                scene.step();
            }
            group.bench_with_input(BenchmarkId::new(kind.as_str(), n), &n, |b, _| {
                b.iter(|| scene.step())
            });
        }
    }
    group.finish();
}

criterion_group!(benches, drape_frame);
criterion_main!(benches);
