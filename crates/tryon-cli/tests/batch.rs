//! `tryon batch` (issue 25, item 5) through the real binary: shards split a manifest into
//! disjoint parts whose union is the batch, a finished job is skipped, a failed one fails the
//! batch (exit 4) without stopping the others, an interrupted one (the batch and its jobs
//! SIGKILLed) goes on from its checkpoint, and a bad manifest is refused with its line.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant, SystemTime};

const TRYON: &str = env!("CARGO_BIN_EXE_tryon");

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tryon-batch-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn batch(manifest: &Path, extra: &[&str]) -> Output {
    Command::new(TRYON)
        .arg("batch")
        .arg(manifest)
        .args(extra)
        .output()
        .unwrap()
}

fn record(dir: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("job.json")).ok()?;
    Some(serde_json::from_str(&text).unwrap())
}

fn modified(path: &Path) -> SystemTime {
    std::fs::metadata(path).unwrap().modified().unwrap()
}

/// The summary's rows: (job, status).
fn summary(out: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let mut lines = text.lines();
    assert!(
        lines
            .next()
            .unwrap()
            .starts_with("job,status,wall s,frames")
    );
    let row = |l: &str| {
        let c: Vec<&str> = l.split(',').collect();
        (c[0].to_string(), c[1].to_string())
    };
    lines.map(row).collect()
}

#[test]
fn shards_split_the_manifest_and_a_finished_job_is_skipped() {
    let root = scratch("shards");
    let skirt = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/scenes/skirt-walk.toml");
    let text = format!(
        "out = \"runs\"\n\
         [[job]]\nscene = \"embedded:demo\"\nframes = 3\n\
         [[job]]\nscene = {:?}\nframes = 4\nname = \"skirt\"\n\
         [[cross]]\nscene = \"embedded:demo\"\nframes = 2\n\
         [cross.vary]\n\"cloth.density\" = [0.18, 0.22]\n",
        skirt.display().to_string()
    );
    let m = root.join("m.toml");
    std::fs::write(&m, text).unwrap();
    let out = root.join("runs");
    let names = ["demo", "skirt", "demo_0.18", "demo_0.22"];

    let first = batch(&m, &["--shard", "0/2"]);
    assert!(first.status.success(), "{first:?}");
    let ran: Vec<bool> = names
        .iter()
        .map(|n| record(&out.join(n)).is_some())
        .collect();
    assert_eq!(
        ran,
        [true, false, true, false],
        "part 0 of 2 is jobs 0 and 2"
    );
    let rows = summary(&out);
    let status: Vec<&str> = rows.iter().map(|r| r.1.as_str()).collect();
    assert_eq!(status, ["done", "not run", "done", "not run"]);

    let second = batch(&m, &["--shard", "1/2", "--jobs", "2"]);
    assert!(second.status.success(), "{second:?}");
    let rows = summary(&out);
    assert_eq!(rows.iter().map(|r| r.0.as_str()).collect::<Vec<_>>(), names);
    assert!(rows.iter().all(|r| r.1 == "done"), "{rows:?}");
    // Each job's outputs and its record; the frames it was asked for.
    for (n, frames) in names.iter().zip([3, 4, 2, 2]) {
        let stats = std::fs::read_to_string(out.join(n).join("stats.json")).unwrap();
        let stats: serde_json::Value = serde_json::from_str(&stats).unwrap();
        assert_eq!(stats["frames"], frames, "{n}");
        assert!(out.join(n).join("scene.glb").exists());
        assert_eq!(record(&out.join(n)).unwrap()["status"], "done");
    }
    let d = record(&out.join("demo_0.22")).unwrap();
    assert_eq!(d["sets"], serde_json::json!(["cloth.density=0.22"]));

    // Run again: every job is done and none runs.
    let before = modified(&out.join("skirt/stats.json"));
    let again = batch(&m, &[]);
    assert!(again.status.success());
    let err = String::from_utf8_lossy(&again.stderr);
    assert!(err.contains("0 done, 0 failed, 4 done before"), "{err}");
    assert_eq!(modified(&out.join("skirt/stats.json")), before);
    let list = String::from_utf8_lossy(&batch(&m, &["--list"]).stdout).to_string();
    assert_eq!(list.matches(" done\n").count(), 4, "{list}");

    // A changed job runs again; the others stay.
    let changed = std::fs::read_to_string(&m)
        .unwrap()
        .replace("frames = 4", "frames = 5");
    std::fs::write(&m, changed).unwrap();
    let list = String::from_utf8_lossy(&batch(&m, &["--list"]).stdout).to_string();
    assert!(list.contains("skirt") && list.contains("to run"), "{list}");
    assert_eq!(list.matches(" done\n").count(), 3, "{list}");
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_failed_job_fails_the_batch_but_not_the_others() {
    let root = scratch("failed");
    // Parses, and fails when it is built: its body's file is missing.
    let lost = "[scene]\nduration = 0.2\n[body]\nkind = \"object\"\nfile = \"nowhere.obj\"\n\
                [garment]\nkind = \"square\"\n";
    std::fs::write(root.join("lost.toml"), lost).unwrap();
    let text = "[[job]]\nscene = \"embedded:demo\"\nframes = 2\n\
                [[job]]\nscene = \"lost.toml\"\n";
    let m = root.join("m.toml");
    std::fs::write(&m, format!("out = \"o\"\n{text}")).unwrap();
    let run = batch(&m, &["--quiet"]);
    assert_eq!(run.status.code(), Some(4), "{run:?}");
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("1 job(s) failed"), "{err}");
    let lost = record(&root.join("o/lost")).unwrap();
    assert_eq!(
        (lost["status"].as_str(), lost["exit_code"].as_i64()),
        (Some("failed"), Some(2))
    );
    assert!(
        lost["error"].as_str().unwrap().contains("nowhere.obj"),
        "{lost}"
    );
    assert_eq!(record(&root.join("o/demo")).unwrap()["status"], "done");
    let rows = summary(&root.join("o"));
    assert_eq!(rows[1], ("lost".into(), "failed".into()));
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn an_interrupted_job_goes_on_from_its_checkpoint() {
    let root = scratch("killed");
    let m = root.join("m.toml");
    // A job long enough to write its first checkpoint (every 100 frames) well before its end.
    let text = "out = \"o\"\n[[job]]\nscene = \"embedded:demo\"\nframes = 170\n\
                set = [\"output.referee_every=0\"]\n";
    std::fs::write(&m, text).unwrap();
    let mut cmd = Command::new(TRYON);
    cmd.arg("batch").arg(&m).arg("--quiet");
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let job = root.join("o/demo");
    let start = Instant::now();
    while !job.join("checkpoint.tryon").exists() {
        assert!(
            child.try_wait().unwrap().is_none(),
            "ended before a checkpoint"
        );
        assert!(start.elapsed() < Duration::from_secs(300), "no checkpoint");
        std::thread::sleep(Duration::from_millis(5));
    }
    // The batch and its job, as a cluster's preemption or a lost machine would.
    let group = format!("-{}", child.id());
    let killed = Command::new("kill").args(["-KILL", "--", &group]).status();
    assert!(killed.unwrap().success());
    child.wait().unwrap();
    assert_eq!(record(&job).unwrap()["status"], "running");
    assert!(!job.join("stats.json").exists(), "killed before its end");
    let list = String::from_utf8_lossy(&batch(&m, &["--list"]).stdout).to_string();
    assert!(list.contains("interrupted (resumes)"), "{list}");

    let again = batch(&m, &["--quiet"]);
    assert!(again.status.success(), "{again:?}");
    assert_eq!(record(&job).unwrap()["status"], "done");
    let stats = std::fs::read_to_string(job.join("stats.json")).unwrap();
    let stats: serde_json::Value = serde_json::from_str(&stats).unwrap();
    assert_eq!(stats["frames"], 170);
    assert!(!job.join("checkpoint.tryon").exists());
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn a_bad_manifest_is_refused_with_its_line() {
    let root = scratch("bad");
    let m = root.join("m.toml");
    std::fs::write(&m, "[[job]]\nscene = \"embedded:demo\"\nframez = 3\n").unwrap();
    let run = batch(&m, &[]);
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("m.toml:3:1: unknown field `framez`"), "{err}");
    // A value a job's scene refuses is named before anything runs.
    std::fs::write(
        &m,
        "[[job]]\nscene = \"embedded:demo\"\nset = [\"effects.refine=9\"]\n",
    )
    .unwrap();
    let run = batch(&m, &[]);
    assert_eq!(run.status.code(), Some(2));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("job `demo`") && err.contains("effects.refine"),
        "{err}"
    );
    let run = batch(&root.join("none.toml"), &[]);
    assert_eq!(run.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(&root);
}

#[test]
fn the_examples_of_docs_scale_hold_together() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let data = tryon_io::data_root_from(&root).expect("the shared asset folder (TRYON_DATA)");
    // Every example manifest parses, its scenes and values check, and it lists its jobs.
    let lists = |name: &str, parts: &str| {
        let out = Command::new(TRYON)
            .args(["batch", "--list", "--shard", parts])
            .arg(root.join("data/batch").join(name))
            .env("TRYON_DATA", &data)
            .output()
            .unwrap();
        assert!(out.status.success(), "{name}: {out:?}");
        String::from_utf8_lossy(&out.stdout).lines().count()
    };
    assert_eq!(lists("demo-sweep.toml", "0/1"), 7);
    let parts: Vec<usize> = (0..4)
        .map(|i| lists("makehuman-cross.toml", &format!("{i}/4")))
        .collect();
    assert_eq!(parts, [2, 2, 2, 2], "8 jobs in 4 parts");

    // The Slurm script: valid bash, an array of as many tasks as it has parts.
    let slurm = root.join("data/batch/slurm.sh");
    assert!(
        Command::new("bash")
            .arg("-n")
            .arg(&slurm)
            .status()
            .unwrap()
            .success()
    );
    let text = std::fs::read_to_string(&slurm).unwrap();
    assert!(text.contains("#SBATCH --array=0-3"));
    assert!(text.contains("--shard \"${SLURM_ARRAY_TASK_ID}/${SLURM_ARRAY_TASK_COUNT}\""));

    // The Kubernetes Indexed Job: read as YAML, its completions equal the N of its --shard.
    let yaml = root.join("data/batch/k8s-indexed-job.yaml");
    let script = "import json, sys, yaml; print(json.dumps(yaml.safe_load(open(sys.argv[1]))))";
    let out = Command::new("python3")
        .args(["-c", script])
        .arg(&yaml)
        .output();
    let required = std::env::var_os("TRYON_REQUIRE_PYTHON").is_some();
    let Some(out) = out.ok().filter(|o| o.status.success()) else {
        assert!(
            !required,
            "TRYON_REQUIRE_PYTHON is set and python3 cannot read YAML"
        );
        eprintln!("skipping the YAML check: no PyYAML on this machine");
        return;
    };
    let job: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (job["kind"].as_str(), job["apiVersion"].as_str()),
        (Some("Job"), Some("batch/v1"))
    );
    let spec = &job["spec"];
    assert_eq!(spec["completionMode"], "Indexed");
    let n = spec["completions"].as_u64().unwrap();
    let args = spec["template"]["spec"]["containers"][0]["args"][0]
        .as_str()
        .unwrap();
    assert!(
        args.contains(&format!("--shard \"${{JOB_COMPLETION_INDEX}}/{n}\"")),
        "{args}"
    );
    assert_eq!(spec["template"]["spec"]["restartPolicy"], "Never");
}
