//! Criterion benchmark of `tryon batch` (issue 25's target: N scenes on 2 cores in at most 0.6x
//! the time of running them one after another). Eight jobs, two each of four scenes with their
//! files in the repository (the embedded demo, the layered walk, the skirt walk, the drape), run
//! by the `tryon` binary itself: `one_after_another` is `--jobs 1` (each run with every core, as
//! `tryon run` is), `parallel` the default (one job a core). Read the ratio of the two from one
//! run.

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

fn manifest(dir: &Path) -> PathBuf {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/scenes");
    // Two of each scene (two friction values), each about a second and a half on one core here,
    // so that no one job outlasts the others (a batch ends no sooner than its longest job).
    let cross = |scene: String, frames: usize| {
        format!(
            "[[cross]]\nscene = {scene:?}\nframes = {frames}\n\
             [cross.vary]\n\"effects.friction\" = [0.4, 0.5]\n"
        )
    };
    let file = |name: &str| scenes.join(name).display().to_string();
    let text = [
        "out = \"runs\"\n".to_string(),
        cross("embedded:demo".into(), 40),
        cross(file("layered-walk.toml"), 30),
        cross(file("skirt-walk.toml"), 120),
        cross(file("drape-sphere.toml"), 120),
    ]
    .concat();
    let path = dir.join("bench.toml");
    std::fs::write(&path, text).unwrap_or_else(|e| panic!("{e}"));
    path
}

fn batch(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("tryon-bench-batch-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap_or_else(|e| panic!("{e}"));
    let m = manifest(&dir);
    let mut group = c.benchmark_group("batch_8_jobs");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(30));
    for (name, jobs) in [("one_after_another", Some("1")), ("parallel", None)] {
        group.bench_function(name, |b| {
            b.iter_batched(
                || {
                    let _ = std::fs::remove_dir_all(dir.join("runs"));
                },
                |()| {
                    let mut cmd = Command::new(env!("CARGO_BIN_EXE_tryon"));
                    cmd.arg("batch").arg(&m).arg("--quiet");
                    if let Some(j) = jobs {
                        cmd.args(["--jobs", j]);
                    }
                    let status = cmd.status().unwrap_or_else(|e| panic!("{e}"));
                    assert!(status.success(), "tryon batch failed");
                },
                BatchSize::PerIteration,
            );
        });
    }
    group.finish();
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, batch);
criterion_main!(benches);
