//! Criterion benchmark of P1 section 4's surface stages for about 11k fine vertices, single thread:
//! a 27 x 27-particle square draped on a sphere (the drape scene's body), refined at level 2
//! ((4 x 26 + 1)^2 = 11,025 fine vertices). Timed per frame: PN refinement, the wrinkle model,
//! hierarchical fine collision (nearest-vertex tracking, including the fine collider's body update)
//! and normal blending; `refine_collide` leaves the wrinkle model out, `all_stages` has the default
//! (compression) wrinkles and `all_stages_force_model` P1's force-driven ones. Each is timed on
//! the global pool and, as `..._1thread`, in a one-thread pool (the target's condition). P1 measured 51.6 ms for its
//! 10,912 vertices; the target here is 0.5 ms.

use criterion::{Criterion, criterion_group, criterion_main};
use std::path::Path;
use std::time::Duration;
use tryon_core::frames::BodyFrame;
use tryon_core::stages::SurfaceInput;
use tryon_pipeline::pipeline::run_surface;
use tryon_pipeline::run::Timers;
use tryon_pipeline::{Pipeline, Scene};

fn scene(model: Option<&str>) -> Pipeline {
    let wrinkles = model.is_some();
    let model = model.unwrap_or("compression");
    let text = format!(
        "[scene]\nname = \"surface\"\nfps = 60\nduration = 1.0\nsettle = 0.0\n\
         [body]\nkind = \"sphere\"\nradius = 0.3\nsubdivisions = 4\n\
         [garment]\nkind = \"square\"\nparticles = 27\nsize = 1.0\ndrop_height = 0.4\n\
         [motion]\nkind = \"still\"\n[cloth]\nsolver = \"p1\"\n\
         [effects]\nfollow_body = false\nfriction = 0.3\nbody_collision = \"nearest_vertex\"\n\
         refine = 2\nwrinkles = {wrinkles}\n\
         wrinkle_model = \"{model}\"\n"
    );
    let s = Scene::parse(&text, Path::new("surface.toml")).unwrap_or_else(|e| panic!("{e}"));
    let mut p = Pipeline::new(s).unwrap_or_else(|e| panic!("{e}"));
    // Untimed: drape for 40 frames so that the cloth lies on the sphere, folded around it.
    let mut st = p.start();
    let mut timers = Timers::default();
    for k in 1..=40 {
        p.advance(&mut st, p.frame_time(k), &mut timers);
    }
    p
}

fn surface(c: &mut Criterion) {
    let mut group = c.benchmark_group("surface_11k");
    group
        .sample_size(30)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for (name, model) in [
        ("refine_collide", None),
        ("all_stages", Some("compression")),
        ("all_stages_force_model", Some("force")),
    ] {
        let mut p = scene(model);
        let body = BodyFrame {
            time: 0.0,
            positions: p.body_mesh.positions.clone(),
            velocities: Vec::new(),
        };
        assert_eq!(p.surface.positions.len(), 11_025);
        let coarse = p.cloth.clone();
        let input = SurfaceInput {
            coarse: &coarse,
            body: Some(&body),
        };
        let mut timers = Timers::default();
        group.bench_function(name, |b| {
            b.iter(|| run_surface(&mut p.surface_stages, &input, &mut p.surface, &mut timers));
        });
        // The target is single thread: the same inside a one-thread pool (the probes and pokes
        // of the fine collision run on rayon).
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .expect("a one-thread pool");
        group.bench_function(format!("{name}_1thread"), |b| {
            one.install(|| {
                b.iter(|| run_surface(&mut p.surface_stages, &input, &mut p.surface, &mut timers));
            });
        });
    }
    group.finish();
}

criterion_group!(benches, surface);
criterion_main!(benches);
