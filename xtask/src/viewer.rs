//! `cargo xtask viewer`: the page of `tryon view`. three.js and the viewer's code (tools/viewer,
//! npm packages pinned by its package-lock.json) are bundled by esbuild into
//! crates/tryon-view/assets/viewer.js, which is committed and compiled into the binary, so a
//! build needs neither npm nor a network. `ci` checks that the committed bundle is what its
//! sources make now.

use std::path::{Path, PathBuf};
use std::process::Command;

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/viewer")
}

const BUNDLE: &str = "crates/tryon-view/assets/viewer.js";

/// `npm ci` in tools/viewer unless its packages are there.
pub fn install() -> Result<(), String> {
    let dir = dir();
    if dir.join("node_modules/three").is_dir() && dir.join("node_modules/esbuild").is_dir() {
        return Ok(());
    }
    eprintln!("xtask: npm ci in {}", dir.display());
    run(Command::new("npm")
        .args(["ci", "--no-audit", "--no-fund"])
        .current_dir(&dir))
}

fn run(cmd: &mut Command) -> Result<(), String> {
    let status = cmd
        .status()
        .map_err(|e| format!("cannot run {cmd:?} (Node.js and npm build the viewer): {e}"))?;
    match status.success() {
        true => Ok(()),
        false => Err(format!("{cmd:?} failed")),
    }
}

/// esbuild's command bundling the viewer into `out` (relative to tools/viewer).
fn esbuild(out: &str) -> Command {
    let mut cmd = Command::new(dir().join("node_modules/.bin/esbuild"));
    cmd.args([
        "src/main.js",
        "--bundle",
        "--minify",
        "--format=esm",
        "--target=es2020",
        "--legal-comments=eof",
        "--log-level=warning",
    ])
    .arg(format!("--outfile={out}"))
    .current_dir(dir());
    cmd
}

/// `cargo xtask viewer`: rebuilds the bundle.
pub fn build() -> Result<(), String> {
    install()?;
    run(&mut esbuild(&format!("../../{BUNDLE}")))?;
    println!("xtask: wrote {BUNDLE}");
    Ok(())
}

/// The committed bundle is what tools/viewer's sources make.
pub fn check() -> Result<(), String> {
    install()?;
    let fresh = "../../target/viewer-check.js";
    run(&mut esbuild(fresh))?;
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let a = std::fs::read(root.join(BUNDLE)).map_err(|e| format!("{BUNDLE}: {e}"))?;
    let b = std::fs::read(root.join("target/viewer-check.js")).map_err(|e| e.to_string())?;
    match a == b {
        true => Ok(()),
        false => Err(format!(
            "{BUNDLE} is not what tools/viewer/src makes: run `cargo xtask viewer` and commit it"
        )),
    }
}
