//! Architecture invariants, checked by `cargo xtask tidy` (and in CI):
//! - stage crates depend on tryon-core and external crates only, never on each other;
//! - only tryon-cli and xtask print or use anyhow;
//! - every Rust source file opens with a `//!` line saying what it is for, and has at most
//!   600 lines;
//! - no to-do or unimplemented macros, debug-print macros or ignored tests in the tree;
//! - docs/scenes.md is what the scene schema generates (`cargo xtask docs` rewrites it).

use std::fs;
use std::path::{Path, PathBuf};

const STAGES: &[&str] = &[
    "cloth-dyn",
    "body-collide",
    "body-model",
    "pnt-surface",
    "wrinkle",
    "mocap-retarget",
    "garment-fit",
    "fold",
    "kimono",
];
const MAY_PRINT: &[&str] = &["tryon-cli", "tryon-tradeoff", "xtask"];
/// The scene reference generated from the schema.
const SCENE_DOCS: &str = "docs/scenes.md";

/// Rewrites docs/scenes.md from the scene schema.
pub fn write_scene_docs() -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .ok_or("xtask has no parent folder")?;
    let path = root.join(SCENE_DOCS);
    tryon_io::write_atomic(&path, tryon_pipeline::scene::docs::markdown().as_bytes())
        .map_err(|e| format!("{}: {e}", path.display()))?;
    eprintln!("xtask: wrote {}", path.display());
    Ok(())
}

/// Longest a source file may be (lines).
const MAX_LINES: usize = 600;

pub fn run() -> Result<(), String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .ok_or("xtask has no parent folder")?
        .to_path_buf();
    let mut problems = Vec::new();
    let crates = root.join("crates");
    let mut entries: Vec<PathBuf> = fs::read_dir(&crates)
        .map_err(|e| format!("{}: {e}", crates.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    entries.sort();
    for dir in &entries {
        let name = dir
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_string();
        let manifest = fs::read_to_string(dir.join("Cargo.toml"))
            .map_err(|e| format!("{}: {e}", dir.display()))?;
        if STAGES.contains(&name.as_str()) {
            for other in STAGES
                .iter()
                .chain(["tryon-pipeline", "tryon-io", "tryon-cli", "tryon-view"].iter())
            {
                if *other != name
                    && manifest.lines().any(|l| {
                        l.trim_start().starts_with(&format!("{other} "))
                            || l.trim_start().starts_with(&format!("{other}."))
                    })
                {
                    problems.push(format!(
                        "{name}: stage crate depends on {other} (stages depend on tryon-core only)"
                    ));
                }
            }
        }
        let may_print = MAY_PRINT.contains(&name.as_str());
        for file in rust_files(&dir.join("src")) {
            check_file(&file, may_print, &mut problems);
        }
    }
    for extra in ["xtask/src", "tests", "benches"] {
        for file in rust_files(&root.join(extra)) {
            check_file(&file, true, &mut problems);
        }
    }
    let docs = root.join(SCENE_DOCS);
    if fs::read_to_string(&docs).ok().as_deref() != Some(&tryon_pipeline::scene::docs::markdown()) {
        problems.push(format!(
            "{}: not what the scene schema generates; run `cargo xtask docs`",
            docs.display()
        ));
    }
    if problems.is_empty() {
        eprintln!("xtask: tidy: architecture invariants hold");
        Ok(())
    } else {
        Err(format!(
            "tidy found {} problem(s):\n  {}",
            problems.len(),
            problems.join("\n  ")
        ))
    }
}

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(rd) = fs::read_dir(dir) else {
        return out;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

fn check_file(file: &Path, may_print: bool, problems: &mut Vec<String>) {
    let Ok(text) = fs::read_to_string(file) else {
        problems.push(format!("{}: unreadable", file.display()));
        return;
    };
    if !text.starts_with("//!") {
        problems.push(format!(
            "{}: does not open with a `//!` line saying what it is for",
            file.display()
        ));
    }
    let lines = text.lines().count();
    if lines > MAX_LINES {
        problems.push(format!(
            "{}: {lines} lines (at most {MAX_LINES}: split it by what its parts do)",
            file.display()
        ));
    }
    // Spelled in pieces so this file does not match itself.
    let forbidden: &[&str] = &[
        concat!("todo", "!("),
        concat!("unimplemented", "!("),
        concat!("dbg", "!("),
        concat!("#[", "ignore"),
    ];
    for (i, line) in text.lines().enumerate() {
        for f in forbidden {
            if line.contains(f) && !line.trim_start().starts_with("//") {
                problems.push(format!("{}:{}: contains `{f}`", file.display(), i + 1));
            }
        }
        if !may_print {
            for f in ["println!(", "eprintln!(", "print!(", "anyhow"] {
                if line.contains(f) && !line.trim_start().starts_with("//") {
                    problems.push(format!(
                        "{}:{}: `{f}` outside tryon-cli and xtask",
                        file.display(),
                        i + 1
                    ));
                }
            }
        }
    }
}
