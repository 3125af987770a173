//! Criterion benchmark of building P3's folds (issue 22's target: at most 20 ms for the shirt's
//! about 14,000 triangles): the garment of `data/scenes/fold-bust-walk.toml` (the dress pattern at
//! 96 columns and 8.5 mm rows, 5,757 vertices, about 11,500 triangles) and its four lines, subdivided, raised, smoothed
//! and the bend changes found; and the bloomer skirt's six lines. Single thread (the stage is
//! serial).

use criterion::{Criterion, criterion_group, criterion_main};
use std::path::Path;
use std::time::Duration;
use tryon_pipeline::Scene;
use tryon_pipeline::build::garment_of;

fn fold_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("fold_build");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for name in ["fold-bust-walk", "fold-bloomer"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../data/scenes")
            .join(format!("{name}.toml"));
        let scene =
            Scene::load_with_overrides(&path, &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
        let mesh = garment_of(&scene, &scene.garment, None).unwrap_or_else(|e| panic!("{e}"));
        let lines: Vec<fold::FoldLine> = scene.fold.iter().map(|f| f.line()).collect();
        let p = scene.folding.params();
        group.bench_function(name, |b| {
            b.iter(|| {
                let f = fold::build(&mesh, &lines, &p).unwrap_or_else(|e| panic!("{e}"));
                std::hint::black_box(fold::bend_edits(&f, &p))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, fold_build);
criterion_main!(benches);
