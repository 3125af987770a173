//! cargo xtask: project automation. `ci` (fmt, clippy, tests, tidy), `bench`, `drape`, `tidy`,
//! `tradeoff`, `ensemble`, `outputs`, `kimono-targets`, `fuzz`, `viewer`.

mod drape;
mod ensemble;
mod fuzz;
mod fuzz_mutate;
mod outputs;
mod realtime;
mod tidy;
mod viewer;

use std::process::{Command, ExitCode};

const USAGE: &str = "usage: cargo xtask <command>

commands:
  ci                 cargo fmt --check, clippy -D warnings, tidy, fuzz --quick, all tests,
                     tradeoff --quick
  bench [ARGS..]     criterion benchmarks (cargo bench -p tryon-benches -p tryon-cli -- ARGS)
  bench --realtime [ARGS..]
                     the product's speed (benches/realtime.rs) pinned to one core; its table
                     goes into docs/speed.md beside the previous one
  drape [N..] [--integrator rk4|symplectic_euler|all] [--frames F] [--trace] [--set KEY=VALUE] [--png FILE]
                     run the drape scene (release) and print ms/frame, stretch, penetration
  ensemble [--save NAME] [--against OTHER] [--frames F]
                     how a solver change is judged: the dress and the casual suit on both
                     shared clips, three runs each with the damping moved by 1e-7 (release,
                     every frame judged, two runs at a time); target/ensemble/NAME.{json,md}
  tradeoff [--quick] [--summary FILE]
                     what accuracy costs in time: collider, integrator, refinement and wrinkle
                     sweeps and P4's scene; report.md and SVG plots under target/tradeoff/
                     (release; --quick is a check at a few frames in the tools build, not
                     figures to quote)
  outputs save DIR | outputs compare OLD NEW
                     run every scene (and variants) into DIR; compare two such runs (GLB and
                     PNG bytes, stats.json but timings)
  kimono-targets [INDEX..]
                     put the kimono family on the mannequins of their sizes (release, about 70 s
                     each); writes data/kimono/*.obj and targets.json, pictures under
                     target/kimono-targets/
  fuzz [--quick | --cases N] [READER..]
                     structure-aware mutation of the data folder's files through every reader
                     (obj, bvh, mhskel, mhw, target, mhclo, scene with --set): 1,000,000 cases
                     each by default, --quick 3,000; a panic or a case over 60 s fails, its input
                     saved under target/fuzz/failures/; counts in target/fuzz/summary.md
  docs               regenerate docs/scenes.md (every scene key) from the schema
  viewer             rebuild tryon view's page bundle (three.js and tools/viewer/src, by esbuild)
                     into crates/tryon-view/assets/viewer.js
  tidy               check the architecture invariants and that docs/scenes.md is current";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("ci") => ci(),
        Some("bench") => bench(&args[1..]),
        Some("drape") => drape::run_in_release(&args[1..]),
        Some("ensemble") => ensemble::run(&args[1..]),
        Some("tidy") => tidy::run(),
        Some("fuzz") => fuzz::run(&args[1..]),
        Some("outputs") => outputs::run(&args[1..]),
        Some("docs") => tidy::write_scene_docs(),
        Some("viewer") => viewer::build(),
        Some("tradeoff") => tradeoff(&args[1..]),
        Some("kimono-targets") => kimono_targets(&args[1..]),
        Some("-h" | "--help" | "help") => {
            println!("{USAGE}");
            Ok(())
        }
        Some(other) => Err(format!("unknown command `{other}`\n\n{USAGE}")),
        None => Err(USAGE.to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Runs cargo with arguments, failing with the command line on a non-zero exit.
fn cargo(args: &[&str]) -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    eprintln!("xtask: cargo {}", args.join(" "));
    let status = Command::new(&cargo)
        .args(args)
        .status()
        .map_err(|e| format!("cannot run {cargo}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("`cargo {}` failed ({status})", args.join(" ")))
    }
}

/// Installs the Khronos glTF validator (npm, pinned by tools/gltf-validate/package-lock.json) that
/// the end-to-end test runs on the written GLB, unless it is already there.
fn install_gltf_validator() -> Result<(), String> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/gltf-validate");
    if dir.join("node_modules/gltf-validator").exists() {
        return Ok(());
    }
    eprintln!("xtask: npm ci in {}", dir.display());
    let status = Command::new("npm")
        .args(["ci", "--no-audit", "--no-fund"])
        .current_dir(&dir)
        .status()
        .map_err(|e| {
            format!("cannot run npm (Node.js and npm are needed for the glTF validator): {e}")
        })?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("npm ci failed in {}", dir.display()))
    }
}

/// Runs `f`, then says how long it took (CI's time is a target: under 30 minutes).
fn timed<T>(what: &str, f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    let t0 = std::time::Instant::now();
    let r = f();
    eprintln!("xtask: {what}: {:.0} s", t0.elapsed().as_secs_f64());
    r
}

fn ci() -> Result<(), String> {
    timed("npm", || {
        install_gltf_validator()?;
        // The viewer's packages (the browser test drives Chromium with playwright-core), and the
        // committed page bundle current with its sources.
        viewer::check()
    })?;
    cargo(&["fmt", "--all", "--", "--check"])?;
    timed("clippy", || {
        cargo(&[
            "clippy",
            "--workspace",
            "--all-targets",
            "--",
            "-D",
            "warnings",
        ])
    })?;
    tidy::run()?;
    // Every reader through a few thousand mutated real files (the full run is `cargo xtask fuzz`).
    timed("fuzz --quick", || fuzz::run(&["--quick".to_string()]))?;
    // Every test, and every benchmark once as a test (`--all-targets` takes the benches in test
    // mode), so they cannot rot; nothing else runs them again. In the tools profile xtask itself
    // was built in, so the workspace is compiled once.
    let (passed, failed) = timed("tests", || {
        cargo_test_tally(&[
            "test",
            "--workspace",
            "--all-targets",
            "--profile",
            "tools",
            "--no-fail-fast",
        ])
    })?;
    println!("tests: {passed} passed, {failed} failed");
    if failed == 0 {
        // The trade-off sweeps at a few frames: every curve must have points.
        timed("tradeoff --quick", || {
            tradeoff(&[
                "--quick".to_string(),
                "--out".into(),
                "target/tradeoff-quick".into(),
            ])
        })?;
    }
    if failed > 0 {
        Err(format!("{failed} test(s) failed"))
    } else {
        Ok(())
    }
}

/// Runs `cargo test ...`, echoing its output, and adds up its `test result:` lines.
fn cargo_test_tally(args: &[&str]) -> Result<(u64, u64), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    eprintln!("xtask: cargo {}", args.join(" "));
    let out = Command::new(&cargo)
        .args(args)
        .stderr(std::process::Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot run {cargo}: {e}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    print!("{text}");
    let (mut passed, mut failed) = (0, 0);
    for line in text.lines().filter(|l| l.starts_with("test result:")) {
        let count = |word: &str| -> u64 {
            let words: Vec<&str> = line
                .split([' ', ';', '.'])
                .filter(|w| !w.is_empty())
                .collect();
            words
                .windows(2)
                .find(|w| w[1] == word)
                .and_then(|w| w[0].parse().ok())
                .unwrap_or(0)
        };
        passed += count("passed");
        failed += count("failed");
    }
    if !out.status.success() && failed == 0 {
        return Err(format!(
            "`cargo {}` failed ({})",
            args.join(" "),
            out.status
        ));
    }
    Ok((passed, failed))
}

fn bench(args: &[String]) -> Result<(), String> {
    if args.first().is_some_and(|a| a == "--realtime") {
        return realtime::run(&args[1..]);
    }
    // tryon-cli's bench runs the `tryon` binary (`tryon batch`).
    let mut a = vec!["bench", "-p", "tryon-benches", "-p", "tryon-cli", "--"];
    a.extend(args.iter().map(String::as_str));
    cargo(&a)
}

/// `cargo xtask tradeoff`: the sweeps, in a release build, from the workspace root.
/// P2's worn target shapes, made by the cloth solver (issue 23 item 3).
fn kimono_targets(args: &[String]) -> Result<(), String> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::env::set_current_dir(&root).map_err(|e| format!("{}: {e}", root.display()))?;
    let mut a = vec![
        "run",
        "--release",
        "-q",
        "-p",
        "tryon-pipeline",
        "--example",
        "kimono_targets",
        "--",
    ];
    a.extend(["data/kimono", "target/kimono-targets"]);
    a.extend(args.iter().map(String::as_str));
    cargo(&a)
}

/// The tradeoff sweeps: in release (fat LTO), whose times the report quotes; `--quick`, a check
/// that every curve has points, in xtask's own `tools` build (the crates CI has already built).
fn tradeoff(args: &[String]) -> Result<(), String> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    std::env::set_current_dir(&root).map_err(|e| format!("{}: {e}", root.display()))?;
    let profile = match args.iter().any(|a| a == "--quick") {
        true => "--profile=tools",
        false => "--release",
    };
    let mut a = vec!["run", profile, "-q", "-p", "tryon-tradeoff", "--"];
    a.extend(args.iter().map(String::as_str));
    cargo(&a)
}
