//! The product's speed (issue 67) as one benchmark: whole frames of the scenes users run, every
//! stage the scene runs but the referee, on a one-thread rayon pool. The cases: the MakeHuman
//! dress and casual suit on their clips (skipped without the shared assets), the demo, and the
//! drape (drape-sphere.toml, the scene's own solver, at 60 frames a second as issue 67 measures
//! it) at N = 64 and 128. Each case is run untimed into motion (30 frames), then every timed
//! iteration is the next frame, the pipeline rebuilt (untimed) when its run ends.
//!
//! Besides criterion's figures, a bench run (`cargo bench --bench realtime`) writes each case's
//! mean ms per frame and per stage, over every frame it timed, to target/realtime.json and prints
//! them as a table; `cargo xtask bench --realtime` writes that table into docs/speed.md beside
//! the previous one. Run as a test (`cargo test --benches`) each case steps a frame or two and
//! nothing is written.

use criterion::{Criterion, criterion_group, criterion_main};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use tryon_pipeline::run::Timers;
use tryon_pipeline::{LoopState, Pipeline, Scene};

/// Frames run untimed before timing: the body in motion, the drape in contact.
const WARM: usize = 30;

/// A case: its name and how its scene is made (`None`: skipped, with the reason printed).
type Case = (&'static str, fn() -> Option<Scene>);

fn scene_file(name: &str, sets: &[&str]) -> Option<Scene> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../data/scenes/{name}.toml"));
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    Scene::load_with_overrides(&path, &sets)
        .map_err(|e| eprintln!("realtime: skipped {name}: {e}"))
        .ok()
}

const CASES: [Case; 5] = [
    ("makehuman-dress-walk", || {
        scene_file("makehuman-dress-walk", &[])
    }),
    ("makehuman-casual-131", || {
        scene_file("makehuman-casual-131", &[])
    }),
    ("demo", || Some(Scene::demo())),
    ("drape-64", || {
        scene_file("drape-sphere", &["garment.particles=64", "scene.fps=60"])
    }),
    ("drape-128", || {
        scene_file("drape-sphere", &["garment.particles=128", "scene.fps=60"])
    }),
];

/// A pipeline, its loop state and the next frame to run.
struct Run {
    p: Pipeline,
    st: LoopState,
    next: usize,
}

/// The case's pipeline run untimed to frame `warm`.
fn start(scene: Scene, warm: usize) -> Option<Run> {
    let mut p = Pipeline::new(scene)
        .map_err(|e| eprintln!("realtime: {e}"))
        .ok()?;
    let mut st = p.start();
    let mut timers = Timers::default();
    let warm = warm.min(p.frames.saturating_sub(1)).max(1);
    for k in 1..warm {
        p.advance(&mut st, p.frame_time(k), &mut timers);
    }
    Some(Run { p, st, next: warm })
}

/// What a case measured: frames timed, their summed wall time, and the stages' timers.
#[derive(Default)]
struct Measured {
    frames: usize,
    total: Duration,
    timers: Timers,
    particles: usize,
}

fn realtime(c: &mut Criterion) {
    let bench = std::env::args().any(|a| a == "--bench");
    let warm = if bench { WARM } else { 2 };
    let mut group = c.benchmark_group("realtime");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(6));
    let Ok(pool) = rayon::ThreadPoolBuilder::new().num_threads(1).build() else {
        return;
    };
    let mut results: BTreeMap<&str, Measured> = BTreeMap::new();
    for (name, make) in CASES {
        let Some(scene) = make() else {
            continue;
        };
        let Some(mut run) = pool.install(|| start(scene.clone(), warm)) else {
            continue;
        };
        let m = results.entry(name).or_default();
        m.particles = run.p.cloth.positions.len();
        group.bench_function(name, |b| {
            b.iter_custom(|iters| {
                let mut spent = Duration::ZERO;
                for _ in 0..iters {
                    if run.next >= run.p.frames {
                        match pool.install(|| start(scene.clone(), warm)) {
                            Some(again) => run = again,
                            None => break,
                        }
                    }
                    let Run { p, st, next } = &mut run;
                    let t0 = Instant::now();
                    pool.install(|| {
                        std::hint::black_box(p.advance(st, p.frame_time(*next), &mut m.timers));
                    });
                    let dt = t0.elapsed();
                    m.timers.end_frame();
                    spent += dt;
                    m.frames += 1;
                    m.total += dt;
                    *next += 1;
                }
                spent
            })
        });
    }
    group.finish();
    if bench {
        report(results);
    }
}

/// Where the table goes: the workspace's target folder.
fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../target"))
}

/// Prints the table and writes target/realtime.json.
fn report(results: BTreeMap<&str, Measured>) {
    let mut json = serde_json::Map::new();
    println!("\n| scene | particles | frame ms | frames/s | stages (ms per frame) |");
    println!("|---|---|---|---|---|");
    for (name, m) in results {
        let frame = m.total.as_secs_f64() * 1e3 / m.frames.max(1) as f64;
        let stages = m.timers.finish();
        let list: Vec<String> = stages
            .iter()
            .map(|(s, t)| format!("{s} {:.2}", t.ms_mean))
            .collect();
        println!(
            "| {name} | {} | {frame:.2} | {:.1} | {} |",
            m.particles,
            1e3 / frame,
            list.join(", ")
        );
        let stage_ms: serde_json::Map<String, serde_json::Value> = stages
            .iter()
            .map(|(s, t)| (s.clone(), serde_json::json!(t.ms_mean)))
            .collect();
        json.insert(
            name.to_string(),
            serde_json::json!({
                "particles": m.particles,
                "frames": m.frames,
                "frame_ms": frame,
                "stages_ms": stage_ms,
            }),
        );
    }
    let path = target_dir().join("realtime.json");
    let text = serde_json::to_string_pretty(&serde_json::Value::Object(json)).unwrap_or_default();
    match std::fs::write(&path, text) {
        Ok(()) => eprintln!("realtime: wrote {}", path.display()),
        Err(e) => eprintln!("realtime: cannot write {}: {e}", path.display()),
    }
}

criterion_group!(benches, realtime);
criterion_main!(benches);
