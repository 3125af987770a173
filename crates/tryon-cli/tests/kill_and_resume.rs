//! Issue 24's test of checkpoints: a `tryon demo` run is killed (SIGKILL) once it has written a
//! checkpoint, `tryon run --resume DIR` finishes it, and its outputs are byte for byte those of
//! a run that was never interrupted (stats.json but for its wall times).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const TRYON: &str = env!("CARGO_BIN_EXE_tryon");

fn demo(out: &Path) -> Command {
    let mut c = Command::new(TRYON);
    c.args([
        "demo",
        "--quiet",
        "--frames",
        "90",
        "--checkpoint-every",
        "10",
    ])
    .args(["--set", "effects.refine=1", "--out"])
    .arg(out)
    .stdout(Stdio::null())
    .stderr(Stdio::null());
    c
}

fn stats_without_times(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("stats.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let o = v.as_object_mut().unwrap();
    o.remove("stages");
    o.remove("loop_s");
    o.remove("frame_ms");
    v
}

#[test]
fn a_killed_run_resumes_to_the_bytes_of_an_uninterrupted_one() {
    let root: PathBuf =
        std::env::temp_dir().join(format!("tryon-kill-resume-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    let (whole, cut) = (root.join("whole"), root.join("cut"));
    assert!(demo(&whole).status().unwrap().success());
    assert!(!whole.join("checkpoint.tryon").exists());

    let mut child = demo(&cut).spawn().unwrap();
    let start = Instant::now();
    let checkpoint = cut.join("checkpoint.tryon");
    while !checkpoint.exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the run ended before its first checkpoint"
        );
        assert!(start.elapsed() < Duration::from_secs(300), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
    // Let it spool a little past the checkpoint, then kill it.
    std::thread::sleep(Duration::from_millis(150));
    child.kill().unwrap();
    let status = child.wait().unwrap();
    assert!(
        !status.success(),
        "the run must have been killed, not finished"
    );
    assert!(!cut.join("scene.glb").exists() && checkpoint.exists());

    let resumed = Command::new(TRYON)
        .args(["run", "--quiet", "--resume"])
        .arg(&cut)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&resumed.stderr);
    assert!(resumed.status.success(), "{err}");
    for f in ["scene.glb", "preview.png", "frames.jsonl"] {
        let (a, b) = (
            std::fs::read(whole.join(f)).unwrap(),
            std::fs::read(cut.join(f)),
        );
        let b = b.unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(a == b, "{f} differs: {} and {} bytes", a.len(), b.len());
    }
    assert_eq!(stats_without_times(&whole), stats_without_times(&cut));
    let left: Vec<String> = std::fs::read_dir(&cut)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') || n == "checkpoint.tryon")
        .collect();
    assert!(left.is_empty(), "left behind: {left:?}");

    // A finished run has nothing to resume; the message says so.
    let again = Command::new(TRYON)
        .args(["run", "--resume"])
        .arg(&cut)
        .output()
        .unwrap();
    assert_eq!(again.status.code(), Some(2));
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("no checkpoint"), "{err}");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn resume_takes_no_scene_or_overrides() {
    let out = Command::new(TRYON)
        .args(["run", "--resume", "x", "--set", "effects.refine=1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("cannot be used with"), "{err}");
}
