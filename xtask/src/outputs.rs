//! `cargo xtask outputs save DIR` runs every scene in data/scenes (and a few variants that reach the
//! other stages) and writes their outputs under DIR; `cargo xtask outputs compare OLD NEW` says
//! whether two such directories hold the same outputs: scene.glb and preview.png byte for byte,
//! stats.json but for its timings. A refactor that must not change results is checked this way.

use std::path::{Path, PathBuf};
use tryon_pipeline::{Pipeline, Scene};

/// Variants run for 40 frames: (scene, label, overrides).
const VARIANTS: [(&str, &str, &[&str]); 6] = [
    ("demo-dress-walk", "wrinkles", &["effects.wrinkles=true"]),
    ("demo-dress-walk", "pipelined", &["scene.pipelined=true"]),
    ("skirt-walk", "sdf", &["effects.body_collision=\"sdf\""]),
    (
        "drape-sphere",
        "depth",
        &["effects.body_collision=\"depth_maps\""],
    ),
    // P1's solver, which the demo keeps as an option, with two of its integrators.
    ("demo-dress-walk", "p1", &["cloth.solver=\"p1\""]),
    (
        "demo-dress-walk",
        "implicit",
        &[
            "cloth.solver=\"p1\"",
            "cloth.p1.integrator=\"implicit_euler\"",
        ],
    ),
];

pub fn run(args: &[String]) -> Result<(), String> {
    match args {
        [cmd, dir] if cmd == "save" => save(Path::new(dir)),
        [cmd, a, b] if cmd == "compare" => compare(Path::new(a), Path::new(b)),
        _ => Err("usage: cargo xtask outputs save DIR | compare OLD NEW".into()),
    }
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../data/scenes")
}

fn run_one(file: &Path, sets: &[String], frames: Option<usize>, out: &Path) -> Result<(), String> {
    let scene = Scene::load_with_overrides(file, sets).map_err(|e| e.to_string())?;
    let mut p = Pipeline::new(scene).map_err(|e| format!("{}: {e}", file.display()))?;
    p.run_to(out, frames, |_, _| {})
        .map_err(|e| e.to_string())?;
    Ok(())
}

fn save(dir: &Path) -> Result<(), String> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .map_err(|e| e.to_string())?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    for f in &files {
        let name = f.file_stem().unwrap_or_default().to_string_lossy();
        eprintln!("xtask: outputs: {name}");
        run_one(f, &[], None, &dir.join(&*name))?;
    }
    for (scene, label, sets) in VARIANTS {
        eprintln!("xtask: outputs: {scene} {label}");
        let f = scenes_dir().join(format!("{scene}.toml"));
        let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
        run_one(&f, &sets, Some(40), &dir.join(format!("{scene}-{label}")))?;
    }
    Ok(())
}

/// stats.json without its timings.
fn stats_without_timings(path: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    if let Some(o) = v.as_object_mut() {
        o.remove("stages");
        o.remove("loop_s");
        o.remove("frame_ms");
    }
    Ok(v)
}

fn compare(a: &Path, b: &Path) -> Result<(), String> {
    let mut runs: Vec<PathBuf> = std::fs::read_dir(a)
        .map_err(|e| format!("{}: {e}", a.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    runs.sort();
    let mut differ = Vec::new();
    for run in &runs {
        let name = run.file_name().unwrap_or_default();
        let other = b.join(name);
        for file in ["scene.glb", "preview.png"] {
            let (x, y) = (
                std::fs::read(run.join(file)),
                std::fs::read(other.join(file)),
            );
            if x.map_err(|e| e.to_string()) != y.map_err(|e| e.to_string()) {
                differ.push(format!("{}/{file}", name.to_string_lossy()));
            }
        }
        let (x, y) = (
            stats_without_timings(&run.join("stats.json")),
            stats_without_timings(&other.join("stats.json")),
        );
        if x != y {
            differ.push(format!("{}/stats.json", name.to_string_lossy()));
        }
    }
    println!(
        "{} runs compared, {} files differ",
        runs.len(),
        differ.len()
    );
    if differ.is_empty() {
        Ok(())
    } else {
        Err(format!("outputs differ: {}", differ.join(", ")))
    }
}
