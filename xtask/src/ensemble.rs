//! `cargo xtask ensemble`: how a solver change is judged (docs/decisions, *judging solver
//! changes*). One run's maximum stretch or penetration moves with rounding alone, so the release
//! build runs the dress and the casual suit on the two shared clips, each three times with the
//! velocity damping changed by 1e-7 of itself, every frame judged; the figures go to
//! target/ensemble/NAME.json and a table per case (the three runs side by side) to NAME.md,
//! beside another saved build's (`--against OTHER`).

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENES: [&str; 2] = ["makehuman-dress-walk", "makehuman-casual-131"];
const CLIPS: [&str; 2] = ["10_04", "131_01"];
const DAMPING: [&str; 3] = ["0.2", "0.2000001", "0.2000002"];
/// The figures kept per run, from stats.json's metrics, and how each is shown.
const FIGURES: [(&str, &str, f64); 4] = [
    ("max_stretch", "max stretch", 1.0),
    ("p99_stretch", "p99 stretch", 1.0),
    ("max_penetration_m", "max penetration (mm)", 1e3),
    ("detached_share", "detached", 1.0),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub fn run(args: &[String]) -> Result<(), String> {
    let (mut name, mut against, mut frames) = ("current".to_string(), None, 120u32);
    let mut it = args.iter();
    while let Some(a) = it.next() {
        let mut value = || it.next().cloned().ok_or(format!("`{a}` needs a value"));
        match a.as_str() {
            "--save" => name = value()?,
            "--against" => against = Some(value()?),
            "--frames" => {
                frames = value()?
                    .parse()
                    .map_err(|_| "--frames: a whole number".to_string())?
            }
            other => return Err(format!("ensemble: unknown argument `{other}`")),
        }
    }
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(format!("--save `{name}`: letters, digits, - and _ only"));
    }
    crate::cargo(&["build", "--release", "-p", "tryon-cli"])?;
    let dir = root().join("target/ensemble");
    let cases: Vec<(&str, &str, &str)> = SCENES
        .iter()
        .flat_map(|s| {
            CLIPS
                .iter()
                .flat_map(move |c| DAMPING.iter().map(move |d| (*s, *c, *d)))
        })
        .collect();
    // Two runs at a time, one thread each.
    let results: Vec<Result<Value, String>> = std::thread::scope(|scope| {
        let chunks: Vec<_> = cases.chunks(cases.len().div_ceil(2)).collect();
        let handles: Vec<_> = chunks
            .into_iter()
            .map(|part| {
                let dir = &dir;
                let name = &name;
                scope.spawn(move || {
                    part.iter()
                        .map(|&case| one_run(dir, name, case, frames))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| {
                h.join()
                    .unwrap_or_else(|_| vec![Err("a run's thread panicked".into())])
            })
            .collect()
    });
    let runs = results
        .into_iter()
        .collect::<Result<Vec<Value>, String>>()?;
    let saved = json!({ "frames": frames, "runs": runs });
    write(
        &dir.join(format!("{name}.json")),
        &serde_json::to_string_pretty(&saved).map_err(|e| e.to_string())?,
    )?;
    let mut builds = vec![(name.clone(), saved)];
    if let Some(other) = against {
        let path = dir.join(format!("{other}.json"));
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let v = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        builds.insert(0, (other, v));
    }
    let table = table(&builds);
    println!("{table}");
    write(&dir.join(format!("{name}.md")), &table)
}

fn write(path: &Path, text: &str) -> Result<(), String> {
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
    }
    tryon_io::write_atomic(path, text.as_bytes()).map_err(|e| format!("{}: {e}", path.display()))
}

/// One run of the release build; its case and figures.
fn one_run(
    dir: &Path,
    name: &str,
    (scene, clip, damping): (&str, &str, &str),
    frames: u32,
) -> Result<Value, String> {
    let out = dir.join(name).join(format!("{scene}-{clip}-{damping}"));
    let exe = root().join("target/release/tryon");
    let status = Command::new(&exe)
        .arg("run")
        .arg(root().join(format!("data/scenes/{scene}.toml")))
        .args(["--frames", &frames.to_string(), "--quiet", "--out"])
        .arg(&out)
        .args(["--set", "output.referee_share=1"])
        .args([
            "--set",
            &format!("motion.file=\"cmu-mocap-bvh/{clip}.bvh\""),
        ])
        .args(["--set", &format!("effects.velocity_damping={damping}")])
        .env("RAYON_NUM_THREADS", "1")
        .status()
        .map_err(|e| format!("cannot run {}: {e}", exe.display()))?;
    if !status.success() {
        return Err(format!(
            "{scene} on {clip} (damping {damping}) failed ({status})"
        ));
    }
    let stats = out.join("stats.json");
    let text = std::fs::read_to_string(&stats).map_err(|e| format!("{}: {e}", stats.display()))?;
    let v: Value = serde_json::from_str(&text).map_err(|e| format!("{}: {e}", stats.display()))?;
    let figures: serde_json::Map<String, Value> = FIGURES
        .iter()
        .map(|(key, _, _)| (key.to_string(), v["metrics"][key].clone()))
        .collect();
    // The run's outputs (a GLB and caches) are not what is judged.
    let _ = std::fs::remove_dir_all(&out);
    Ok(json!({ "case": format!("{scene} / {clip}"), "damping": damping, "figures": figures }))
}

/// The table: per case and build, each figure's values over the perturbed runs.
fn table(builds: &[(String, Value)]) -> String {
    let mut head = "| case | build |".to_string();
    let mut rule = "|---|---|".to_string();
    for (_, title, _) in FIGURES {
        head += &format!(" {title} |");
        rule += "---|";
    }
    let mut lines = vec![head, rule];
    let mut cases: Vec<String> = Vec::new();
    for (_, b) in builds {
        for r in b["runs"].as_array().into_iter().flatten() {
            let c = r["case"].as_str().unwrap_or("?").to_string();
            if !cases.contains(&c) {
                cases.push(c);
            }
        }
    }
    for case in &cases {
        for (name, b) in builds {
            let runs: Vec<&Value> = b["runs"]
                .as_array()
                .into_iter()
                .flatten()
                .filter(|r| r["case"].as_str() == Some(case.as_str()))
                .collect();
            let mut line = format!("| {case} | {name} |");
            for (key, _, scale) in FIGURES {
                let values: Vec<String> = runs
                    .iter()
                    .map(|r| {
                        r["figures"][key]
                            .as_f64()
                            .map_or("-".into(), |x| format!("{:.4}", x * scale))
                    })
                    .collect();
                line += &format!(" {} |", values.join(", "));
            }
            lines.push(line);
        }
    }
    lines.join("\n") + "\n"
}

#[cfg(test)]
mod tests {
    use super::*;

    fn build(case: &str, maxima: &[f64]) -> Value {
        let runs: Vec<Value> = maxima
            .iter()
            .map(|m| json!({ "case": case, "figures": { "max_stretch": m, "max_penetration_m": 0.0021 } }))
            .collect();
        json!({ "runs": runs })
    }

    #[test]
    fn the_table_puts_each_builds_runs_side_by_side_under_their_case() {
        let t = table(&[
            ("base".into(), build("dress / 10_04", &[1.456, 1.585])),
            ("new".into(), build("dress / 10_04", &[1.5, 1.25])),
        ]);
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines.len(), 4, "{t}");
        assert!(
            lines[2].starts_with("| dress / 10_04 | base | 1.4560, 1.5850 |"),
            "{t}"
        );
        // Metres shown in millimetres; a figure a run lacks is a dash.
        assert!(
            lines[3].contains("| 1.5000, 1.2500 | -, - | 2.1000, 2.1000 | -, - |"),
            "{t}"
        );
    }
}
