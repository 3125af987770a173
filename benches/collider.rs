//! Body queries per point (issue 67 item 3): nanoseconds per probe of the cloth's particles
//! against the MakeHuman body, for the exact collider and the nearest-vertex tracker. The body
//! and the dress are taken from makehuman-dress-walk after 30 frames of its walk (skipped without
//! the shared assets); each iteration probes every particle, moved by up to a millimetre from
//! where the previous iteration asked (a substep's motion on the frame's body shape), so no answer
//! is reused. The cases: `probe_near` within the VBD solver's reach (thickness + 3 cm), the whole
//! search (`probe`), and the fail-safe (`resolve`, within the thickness).

mod dressed;

use body_collide::{ExactCollider, NearestVertexCollider};
use criterion::{Criterion, criterion_group, criterion_main};
use std::time::Duration;
use tryon_core::math::{Real, Vec3};
use tryon_core::stages::{Collider, Probe};

/// Frames run before the body and the cloth are taken.
const WARM: usize = 30;
/// Jittered copies of the particles, asked in turn.
const COPIES: usize = 8;

/// The dress's particles and the body mesh and shape after [`WARM`] frames.
fn dressed() -> Option<(
    tryon_core::mesh::PolyMesh,
    tryon_core::frames::BodyFrame,
    Vec<Vec3>,
)> {
    let (p, st) = dressed::dressed("collider", WARM)?;
    Some((
        p.body_mesh.clone(),
        st.body_frame.clone(),
        p.cloth.positions.clone(),
    ))
}

/// `x` moved by up to `r` per axis, differently for each copy (a fixed sequence).
fn jittered(x: &[Vec3], copy: usize, r: Real) -> Vec<Vec3> {
    let mut s = 0x9e37_79b9_7f4a_7c15_u64 ^ copy as u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as Real / (1u64 << 53) as Real * 2.0 - 1.0
    };
    x.iter()
        .map(|p| p + Vec3::new(next(), next(), next()) * r)
        .collect()
}

fn bench(c: &mut Criterion) {
    let Some((mesh, body, cloth)) = dressed() else {
        return;
    };
    let thickness = 0.003;
    let reach = thickness + 0.03;
    let copies: Vec<Vec<Vec3>> = (0..COPIES).map(|k| jittered(&cloth, k, 1e-3)).collect();
    let all: Vec<u32> = (0..cloth.len() as u32).collect();
    let n = cloth.len() as f64;
    let mut g = c.benchmark_group("collider");
    g.sample_size(20).measurement_time(Duration::from_secs(3));
    let mut exact = ExactCollider::new(&mesh, thickness).expect("body");
    exact.update(&body);
    let mut tracker = NearestVertexCollider::new(&mesh, thickness).expect("body");
    tracker.update(&body);
    let mut out: Vec<Probe> = Vec::new();
    let mut k = 0;
    let mut per_query = Vec::new();
    let cases: [(&str, usize, usize); 4] = [
        ("exact probe_near", 0, 0),
        ("tracker probe_near", 1, 0),
        ("exact probe", 0, 1),
        ("exact resolve", 0, 2),
    ];
    for (name, which, how) in cases {
        let coll: &mut dyn Collider = if which == 0 { &mut exact } else { &mut tracker };
        let start = std::time::Instant::now();
        let mut calls = 0u64;
        g.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) % COPIES;
                calls += 1;
                match how {
                    0 => coll.probe_near(&copies[k], &all, reach, &mut out),
                    1 => coll.probe(&copies[k], &all, &mut out),
                    _ => {
                        let mut x = copies[k].clone();
                        let mut contacts = Vec::new();
                        coll.resolve(&mut x, &mut contacts);
                    }
                }
            })
        });
        per_query.push((
            name,
            start.elapsed().as_secs_f64() / calls.max(1) as f64 / n * 1e9,
        ));
    }
    g.finish();
    println!(
        "collider: {} particles, {} body triangles",
        cloth.len(),
        mesh.faces.len()
    );
    for (name, ns) in per_query {
        println!("collider: {name}: about {ns:.0} ns per point (wall time over every call)");
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
