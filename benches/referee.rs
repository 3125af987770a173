//! The referee's parts on a real frame (issue 67 item 5): the dress of makehuman-dress-walk after
//! 30 frames of its walk, refined as the scene refines it (skipped without the shared assets).
//! The cases: the crossing pairs of the output surface with the smallest layer gap
//! (`crossings::judge`), the crossing pairs alone, and the exact signed distance of every output
//! vertex to the body (`metrics::distances`, the referee collider as the run keeps it).

mod dressed;

use body_collide::{ExactCollider, crossings, metrics};
use criterion::{Criterion, criterion_group, criterion_main};
use std::time::Duration;
use tryon_core::stages::Collider;

/// Frames run before the surface is taken.
const WARM: usize = 30;

fn bench(c: &mut Criterion) {
    let Some((p, st)) = dressed::dressed("referee", WARM) else {
        return;
    };
    let x = p.surface.positions.clone();
    let tris = p.surface.triangles.clone();
    let mut referee = ExactCollider::new(&p.body_mesh, 0.003).expect("body");
    referee.update(&st.body_frame);
    let mut g = c.benchmark_group("referee");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    g.bench_function("crossings and gap", |b| {
        b.iter(|| crossings::judge(&x, &tris))
    });
    g.bench_function("crossing pairs", |b| {
        b.iter(|| crossings::crossings(&x, &tris).len())
    });
    g.bench_function("distances", |b| {
        b.iter(|| metrics::distances(&mut referee, &x).len())
    });
    g.finish();
    println!(
        "referee: {} output vertices, {} triangles, {} crossing pairs",
        x.len(),
        tris.len(),
        crossings::crossings(&x, &tris).len()
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
