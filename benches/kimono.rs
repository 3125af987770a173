//! Criterion benchmarks of P2's kimono on one thread (issue 23's target: the fit, eq. (1), plus the
//! print correction, at most 50 ms for the whole kimono): `kimono_fit` (the blend weights per
//! sub-mesh and the sub-meshes meeting), `kimono_print` (the print correction), `kimono_both`, for
//! a wearer who is not among the family's targets; on the flat targets, and `both_worn` on the worn
//! ones (data/kimono, built into tryon-pipeline).

use criterion::{Criterion, criterion_group, criterion_main};
use kimono::family::flat_family;
use kimono::{FitParams, PrintParams, Wearer, correct_print, fit, tailor};
use std::time::Duration;

fn kimono(c: &mut Criterion) {
    let fam = flat_family().unwrap_or_else(|e| panic!("{e}"));
    let d = tailor(&Wearer::new(1.68, 0.94, 0.76, 1.02)).unwrap_or_else(|e| panic!("{e}"));
    let base = &fam.base;
    let p = FitParams::default();
    let fitted = fit(base, &base.positions, &fam.targets, &d, &p).unwrap_or_else(|e| panic!("{e}"));
    let mut group = c.benchmark_group("kimono");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    group.bench_function("fit", |b| {
        b.iter(|| std::hint::black_box(fit(base, &base.positions, &fam.targets, &d, &p)))
    });
    group.bench_function("print", |b| {
        b.iter(|| {
            std::hint::black_box(
                correct_print(
                    base,
                    &base.positions,
                    &fitted.positions,
                    &PrintParams::default(),
                )
                .expect("shapes of the mesh"),
            )
        })
    });
    group.bench_function("both", |b| {
        b.iter(|| {
            let f =
                fit(base, &base.positions, &fam.targets, &d, &p).unwrap_or_else(|e| panic!("{e}"));
            std::hint::black_box(
                correct_print(base, &base.positions, &f.positions, &PrintParams::default())
                    .expect("shapes of the mesh"),
            )
        })
    });
    let worn =
        tryon_pipeline::kimono::Targets::Worn(&tryon_pipeline::kimono_wear::embedded::shape_text)
            .family()
            .unwrap_or_else(|e| panic!("{e}"));
    let wb = &worn.base;
    group.bench_function("both_worn", |b| {
        b.iter(|| {
            let f = fit(wb, &wb.positions, &worn.targets, &d, &p).unwrap_or_else(|e| panic!("{e}"));
            std::hint::black_box(
                correct_print(wb, &wb.positions, &f.positions, &PrintParams::default())
                    .expect("shapes of the mesh"),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, kimono);
criterion_main!(benches);
