//! `cargo xtask bench --realtime`: the product's speed benchmark (benches/realtime.rs) built, then
//! run pinned to one core (`taskset -c 1` where it exists, one rayon thread), and its table
//! written into docs/speed.md beside the previous one, with each scene's ratio to it. The figures
//! are kept in docs/speed/realtime.json (the previous run's are read from there first).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

const BEGIN: &str = "<!-- realtime:begin: written by `cargo xtask bench --realtime` -->";
const END: &str = "<!-- realtime:end -->";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

pub fn run(args: &[String]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let bench = ["bench", "-p", "tryon-benches", "--bench", "realtime"];
    let built = Command::new(&cargo)
        .args(bench)
        .arg("--no-run")
        .current_dir(root())
        .status()
        .map_err(|e| format!("cannot run {cargo}: {e}"))?;
    if !built.success() {
        return Err(format!("building the realtime benchmark failed ({built})"));
    }
    let pinned = Command::new("taskset").arg("-V").output().is_ok();
    let mut cmd = match pinned {
        true => {
            let mut c = Command::new("taskset");
            c.args(["-c", "1", &cargo]);
            c
        }
        false => Command::new(&cargo),
    };
    let status = cmd
        .args(bench)
        .arg("--")
        .args(args)
        .env("RAYON_NUM_THREADS", "1")
        .current_dir(root())
        .status()
        .map_err(|e| format!("cannot run the realtime benchmark: {e}"))?;
    if !status.success() {
        return Err(format!("the realtime benchmark failed ({status})"));
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root().join("target"));
    let now = read_json(&target.join("realtime.json"))?;
    let kept = root().join("docs/speed/realtime.json");
    let previous = read_json(&kept).ok();
    let now = stamped(now, pinned);
    write_section(&now, previous.as_ref())?;
    let text = serde_json::to_string_pretty(&now).map_err(|e| e.to_string())?;
    tryon_io::write_atomic(&kept, text.as_bytes()).map_err(|e| format!("{}: {e}", kept.display()))
}

fn read_json(path: &Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

/// The bench's figures with when and where they were measured.
fn stamped(scenes: Value, pinned: bool) -> Value {
    let pin = match pinned {
        true => "one thread pinned to core 1",
        false => "one thread (taskset missing: not pinned)",
    };
    serde_json::json!({
        "date": tryon_io::machine::today(),
        "machine": format!("{}; {pin}; release build", tryon_io::machine::description()),
        "scenes": scenes,
    })
}

fn ms(v: &Value, key: &str) -> Option<f64> {
    v["stages_ms"][key].as_f64()
}

/// The section of docs/speed.md: the new table, with ratios to `previous`, and the previous one.
fn table(now: &Value, previous: Option<&Value>) -> String {
    let mut s = format!(
        "{BEGIN}\n\n## Real-time frames (issue 67)\n\n`cargo xtask bench --realtime` \
         (benches/realtime.rs): whole frames, every stage but the referee, ms per frame.\n\
         Measured {} on {}.\n\n\
         | scene | particles | frame ms | frames/s | vs previous | cloth ms | surface ms | other stages (ms) |\n\
         |---|---|---|---|---|---|---|---|\n",
        now["date"].as_str().unwrap_or("?"),
        now["machine"].as_str().unwrap_or("?"),
    );
    let surface = [
        "refine",
        "wrinkle",
        "fine_collision",
        "normals",
        "fine_layers",
    ];
    let empty = serde_json::Map::new();
    for (name, v) in now["scenes"].as_object().unwrap_or(&empty) {
        let frame = v["frame_ms"].as_f64().unwrap_or(f64::NAN);
        let before = previous.and_then(|p| p["scenes"][name]["frame_ms"].as_f64());
        let ratio = before.map_or("-".into(), |b| format!("{:.2}x", frame / b));
        let parts: Vec<f64> = surface.iter().filter_map(|k| ms(v, k)).collect();
        let surf = match parts.is_empty() {
            true => "-".to_string(),
            false => format!("{:.2}", parts.iter().sum::<f64>()),
        };
        let others: Vec<String> = v["stages_ms"]
            .as_object()
            .unwrap_or(&empty)
            .iter()
            .filter(|(k, _)| *k != "cloth" && !surface.contains(&k.as_str()))
            .map(|(k, x)| format!("{k} {:.2}", x.as_f64().unwrap_or(f64::NAN)))
            .collect();
        s += &format!(
            "| {name} | {} | {frame:.2} | {:.1} | {ratio} | {:.2} | {surf} | {} |\n",
            v["particles"],
            1e3 / frame,
            ms(v, "cloth").unwrap_or(0.0),
            others.join(", ")
        );
    }
    if let Some(p) = previous {
        if p["machine"] != now["machine"] {
            s += "\nThe previous run was on another machine: the ratios compare the machines as well \
                  as the code.\n";
        }
        s += &format!(
            "\nThe previous run, {} on {}:\n\n| scene | frame ms | cloth ms |\n|---|---|---|\n",
            p["date"].as_str().unwrap_or("?"),
            p["machine"].as_str().unwrap_or("?")
        );
        for (name, v) in p["scenes"].as_object().unwrap_or(&empty) {
            s += &format!(
                "| {name} | {:.2} | {:.2} |\n",
                v["frame_ms"].as_f64().unwrap_or(f64::NAN),
                ms(v, "cloth").unwrap_or(0.0)
            );
        }
    }
    s + "\n" + END
}

/// Replaces the section in docs/speed.md (or puts it after the title).
fn write_section(now: &Value, previous: Option<&Value>) -> Result<(), String> {
    let path = root().join("docs/speed.md");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let section = table(now, previous);
    let out = match (text.find(BEGIN), text.find(END)) {
        (Some(a), Some(b)) if a < b => format!("{}{section}{}", &text[..a], &text[b + END.len()..]),
        _ => match text.find('\n') {
            Some(i) => format!("{}\n\n{section}\n{}", &text[..i], &text[i..]),
            None => format!("{text}\n\n{section}\n"),
        },
    };
    tryon_io::write_atomic(&path, out.as_bytes())
        .map_err(|e| format!("{}: {e}", path.display()))?;
    eprintln!("xtask: wrote {}", path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_gives_each_scene_its_ratio_to_the_previous_run() {
        let scene = |frame: f64, cloth: f64| {
            serde_json::json!({"particles": 10, "frames": 5, "frame_ms": frame,
                "stages_ms": {"cloth": cloth, "refine": 1.0, "fine_collision": 2.0, "skinning": 0.5}})
        };
        let old =
            serde_json::json!({"date": "d0", "machine": "m", "scenes": {"a": scene(20.0, 10.0)}});
        let new = serde_json::json!({"date": "d1", "machine": "m", "scenes": {"a": scene(10.0, 4.0), "b": scene(5.0, 1.0)}});
        let t = table(&new, Some(&old));
        assert!(
            t.contains("| a | 10 | 10.00 | 100.0 | 0.50x | 4.00 | 3.00 | skinning 0.50 |"),
            "{t}"
        );
        assert!(t.contains("| b | 10 | 5.00 | 200.0 | - |"), "{t}");
        assert!(t.contains("| a | 20.00 | 10.00 |"), "{t}");
        assert!(t.starts_with(BEGIN) && t.ends_with(END));
        assert!(!t.contains("another machine"), "{t}");
        let elsewhere = serde_json::json!({"date": "d0", "machine": "m2", "scenes": {}});
        assert!(table(&new, Some(&elsewhere)).contains("another machine"));
    }
}
