//! The `tryon` command line: `tryon demo`, `tryon run SCENE.toml`, `tryon check SCENE.toml`,
//! `tryon inspect FILE`.
//! Exit codes: 0 success, 2 bad input (the message names the file, line, key or value), 1 an
//! internal error (an output that could not be written, a failed export), 3 a `--strict` run whose
//! garment left the body (its outputs written), 4 a `batch` some of whose jobs failed (the others'
//! outputs and the summary written).

mod args;
mod batch;
mod live;
mod report;
mod resume;

use args::{BudgetFlags, Cli, Command, RunFlags, TargetShapes};
use clap::Parser;
use report::run;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use tryon_pipeline::{Options, Pipeline, Scene};

/// The exit status of a `--strict` run whose garment left the body.
const LEFT_THE_BODY: u8 = 3;

/// A failure and the exit code it maps to.
enum Failure {
    BadInput(String),
    Internal(String),
    /// A `--strict` run whose garment left the body (the summary said so).
    LeftTheBody,
    /// A batch some of whose jobs failed.
    JobsFailed(String),
}

fn load(path: &Path, sets: &[String]) -> Result<Scene, Failure> {
    Scene::load_with_overrides(path, sets).map_err(|e| Failure::BadInput(e.to_string()))
}

/// The embedded demo scene with `sets` applied.
fn demo_scene(sets: &[String]) -> Result<Scene, Failure> {
    Scene::parse_with_overrides(
        tryon_pipeline::DEMO_SCENE,
        Path::new("<embedded demo-dress-walk.toml>"),
        sets,
    )
    .map_err(|e| Failure::BadInput(e.to_string()))
}

/// Marks the default output folder `out/` as generated: a `.gitignore` of `*` inside it keeps
/// runs out of version control wherever they are started (as cargo does for `target/`).
fn mark_generated(out: &Path) {
    let mut top = out.components();
    if let Some(std::path::Component::Normal(first)) = top.next()
        && first == "out"
    {
        let ignore = Path::new("out").join(".gitignore");
        if !ignore.exists() {
            // Best effort: a folder we cannot write to fails later with a clear error.
            let _ = std::fs::create_dir_all("out").and_then(|()| std::fs::write(&ignore, "*\n"));
        }
    }
}

fn assemble(
    scene: Scene,
    file: &str,
    quiet: bool,
    budget: &BudgetFlags,
    frames: Option<usize>,
) -> Result<Pipeline, Failure> {
    // Long preparations (putting a kimono on) say how far they are instead of staying silent.
    let say = |line: &str| {
        if !quiet {
            eprintln!("{line}");
        }
    };
    let options = Options {
        progress: &say,
        limits: budget.limits(),
        frames,
    };
    let p = Pipeline::with_options(scene, &options).map_err(|e| match e {
        // Already placed at its file and line.
        e @ tryon_pipeline::build::AssembleError::At { .. } => Failure::BadInput(e.to_string()),
        e => Failure::BadInput(format!("{file}: {e}")),
    })?;
    for w in &p.warnings {
        eprintln!("warning: {w}");
    }
    Ok(p)
}

/// Runs `scene` (from `path`, or the embedded demo when `None`, with `sets` applied) as `flags`
/// ask; with `--strict`, a garment that left the body fails the run.
fn run_scene(
    scene: Scene,
    (path, sets): (Option<&Path>, &[String]),
    out: &Path,
    flags: &RunFlags,
) -> Result<(), Failure> {
    let file = path.map_or("<embedded demo>".into(), |p| p.display().to_string());
    let p = assemble(scene, &file, flags.quiet, &flags.budget, flags.frames)?;
    let invocation = resume::Invocation {
        scene: path.map(|p| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())),
        sets: sets.to_vec(),
        frames: flags.frames,
        limits: flags.budget.limits.clone(),
        every: flags.checkpoint_every,
    };
    let start = report::Start::Fresh {
        frames: flags.frames,
        checkpoints: invocation.checkpointing(),
    };
    strict(run(p, out, start, flags.quiet)?, flags.strict)
}

/// With `--strict`, a run whose garment left the body fails.
fn strict(left: bool, strict: bool) -> Result<(), Failure> {
    match left && strict {
        true => Err(Failure::LeftTheBody),
        false => Ok(()),
    }
}

/// The joint-naming scheme retargeting will use for a BVH or .mhskel file, if one fits.
fn naming_scheme(file: &Path) -> Option<&'static str> {
    let ext = file.extension()?.to_str()?.to_ascii_lowercase();
    let names: Vec<String> = match ext.as_str() {
        "bvh" => tryon_io::read_bvh(file, Some(1.0)).ok()?.skeleton.names,
        "mhskel" => tryon_io::read_mhskel(file)
            .ok()?
            .bones
            .into_iter()
            .map(|b| b.name)
            .collect(),
        _ => return None,
    };
    let skeleton = tryon_core::pose::Skeleton {
        parents: vec![None; names.len()],
        rest_offsets: vec![Default::default(); names.len()],
        names,
    };
    Some(mocap_retarget::RoleMap::detect(&skeleton).map_or(
        "none known (retargeting needs hips, thighs, shins and feet)",
        |m| m.scheme,
    ))
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo { out, flags, sets } => {
            demo_scene(&sets).and_then(|s| run_scene(s, (None, &sets), &out, &flags))
        }
        Command::Run {
            resume: Some(dir),
            flags,
            ..
        } => resume::resume(&dir, flags.quiet).and_then(|left| strict(left, flags.strict)),
        Command::Run {
            scene,
            out,
            flags,
            sets,
            ..
        } => {
            let scene = scene.unwrap_or_default();
            load(&scene, &sets).and_then(|s| {
                let out = out.unwrap_or_else(|| PathBuf::from("out").join(s.folder_name()));
                run_scene(s, (Some(&scene), &sets), &out, &flags)
            })
        }
        Command::Batch { manifest, flags } => batch::run(&manifest, &flags),
        Command::View {
            path,
            demo: _,
            sets,
            port,
            budget,
        } => match path {
            Some(p) if p.is_dir() => view(&p, port),
            Some(p) => std::fs::read_to_string(&p)
                .map_err(|e| Failure::BadInput(format!("{}: {e}", p.display())))
                .and_then(|text| {
                    let source = live::Source {
                        text,
                        file: p,
                        from_file: true,
                        sets,
                    };
                    live::serve(source, &budget, port)
                }),
            None => {
                let source = live::Source {
                    text: tryon_pipeline::DEMO_SCENE.to_string(),
                    file: PathBuf::from("<embedded demo-dress-walk.toml>"),
                    from_file: false,
                    sets,
                };
                live::serve(source, &budget, port)
            }
        },
        Command::Inspect { file } => tryon_io::inspect::summarize(&file)
            .map(|text| {
                print!("{text}");
                if let Some(scheme) = naming_scheme(&file) {
                    println!("naming scheme: {scheme}");
                }
            })
            .map_err(|e| Failure::BadInput(e.to_string())),
        Command::Canvas { scene, out, sets } => load(&scene, &sets).and_then(|s| {
            let path =
                out.unwrap_or_else(|| Path::new("out").join(s.folder_name()).join("canvas.png"));
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir).map_err(|e| {
                    Failure::Internal(format!("cannot create {}: {e}", dir.display()))
                })?;
            }
            mark_generated(&path);
            match tryon_pipeline::canvas::write(&s, &path) {
                Ok(()) => {
                    println!("wrote {}", path.display());
                    Ok(())
                }
                Err(e @ tryon_pipeline::build::AssembleError::Canvas(_)) => {
                    Err(Failure::Internal(e.to_string()))
                }
                Err(e @ tryon_pipeline::build::AssembleError::At { .. }) => {
                    Err(Failure::BadInput(e.to_string()))
                }
                Err(e) => Err(Failure::BadInput(format!("{}: {e}", scene.display()))),
            }
        }),
        Command::Kimono {
            height,
            bust,
            waist,
            hip,
            yuki,
            sleeve_length,
            targets,
            out,
            quiet,
        } => kimono(
            &tryon_pipeline::kimono::Wearer {
                height,
                bust,
                waist,
                hip,
                yuki,
                sleeve_length,
            },
            targets,
            &out,
            quiet,
        ),
        Command::Check {
            scene,
            sets,
            budget,
        } => load(&scene, &sets).and_then(|s| {
            let p = assemble(s, &scene.display().to_string(), false, &budget, None)?;
            let e = &p.estimate;
            println!(
                "{}: ok: scene `{}`, {} frames at {} fps, {} garment particles, stages: {}",
                scene.display(),
                p.scene.scene.name,
                p.frames,
                p.fps,
                p.garment.positions.len(),
                p.stages().join(", ")
            );
            println!(
                "estimate: {} substeps a frame x {} sweeps, {} fine vertices; peak memory about {:.2} GB, run time about {:.1} min, scene.glb about {:.2} GB (rough: docs/decisions, budgets)",
                e.substeps,
                e.iterations,
                e.fine_vertices,
                e.memory_gb,
                e.hours * 60.0,
                e.glb_gb
            );
            Ok(())
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::BadInput(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(2)
        }
        Err(Failure::Internal(m)) => {
            eprintln!("internal error: {m}");
            ExitCode::from(1)
        }
        Err(Failure::LeftTheBody) => ExitCode::from(LEFT_THE_BODY),
        Err(Failure::JobsFailed(m)) => {
            eprintln!("error: {m}");
            ExitCode::from(4)
        }
    }
}

/// `tryon view DIR`: serves the run until the process is stopped.
fn view(dir: &Path, port: u16) -> Result<(), Failure> {
    let files = tryon_view::RunFiles::read(dir).map_err(|e| Failure::BadInput(e.to_string()))?;
    let (name, frames) = (files.name.clone(), files.frames);
    tryon_view::serve(files, port, |addr| {
        println!("tryon view: {name}, {frames} frames: http://{addr}/ (Ctrl-C stops)");
    })
    .map_err(|e| match e {
        e @ tryon_view::ViewError::Listen { .. } => Failure::BadInput(e.to_string()),
        e => Failure::Internal(e.to_string()),
    })
}

/// `tryon kimono`: fit, write, print Table 1.
fn kimono(
    w: &tryon_pipeline::kimono::Wearer,
    targets: TargetShapes,
    out: &Path,
    quiet: bool,
) -> Result<(), Failure> {
    use tryon_pipeline::kimono::{KimonoError, Targets};
    let embedded =
        |name: &str| tryon_pipeline::kimono_wear::embedded::shape(name).map(str::to_string);
    let targets = match targets {
        TargetShapes::Worn => Targets::Worn(&embedded),
        TargetShapes::Flat => Targets::Flat,
    };
    let k = tryon_pipeline::kimono::fit_kimono(w, targets).map_err(|e| match e {
        KimonoError::Measurements(_) => Failure::BadInput(e.to_string()),
        e => Failure::Internal(e.to_string()),
    })?;
    mark_generated(out);
    tryon_pipeline::kimono::write_kimono(out, &k, (900, 1000))
        .map_err(|e| Failure::Internal(e.to_string()))?;
    if !quiet {
        let r = &k.report;
        println!(
            "{:<38} {:>9} {:>9} {:>9} {:>8}",
            "dimension", "target m", "initial", "fitted", "error"
        );
        for d in &r.dimensions {
            println!(
                "{:<38} {:>9.4} {:>9.4} {:>9.4} {:>7.2}%",
                d.name,
                d.target_m,
                d.initial_m,
                d.fitted_m,
                100.0 * d.rel_error
            );
        }
        println!(
            "mean relative error {:.2}% (initial {:.2}%), max {:.2}%; print squares' aspect {:.3} before the correction, {:.3} after; fit {:.1} ms, print {:.1} ms",
            100.0 * r.mean_rel_error,
            100.0 * r.initial_mean_rel_error,
            100.0 * r.max_rel_error,
            r.print.before[0],
            r.print.after[0],
            r.fit_ms,
            r.print_ms
        );
        println!("wrote {}", out.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_and_check_take_overrides_and_name_a_bad_one() {
        let s = demo_scene(&["effects.wrinkles=true".into()]).unwrap_or_else(|_| panic!());
        assert!(s.effects.wrinkles && !Scene::demo().effects.wrinkles);
        let Err(Failure::BadInput(m)) = demo_scene(&["effects.refine=9".into()]) else {
            panic!("a bad override must be bad input");
        };
        assert!(m.contains("effects.refine") && m.contains("0..=4"), "{m}");
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/scenes/skirt-walk.toml");
        let s = load(&file, &["effects.refine=2".into()]).unwrap_or_else(|_| panic!());
        assert_eq!(s.effects.refine, 2);
    }

    #[test]
    fn a_small_share_does_not_print_as_zero() {
        assert_eq!(report::percent(0.0), "0.0%");
        assert_eq!(report::percent(0.000188), "0.019%");
        assert_eq!(report::percent(0.0025), "0.25%");
        assert_eq!(report::percent(0.5), "50.0%");
    }

    #[test]
    fn only_the_default_output_folder_is_marked_generated() {
        let dir = std::env::temp_dir().join(format!("tryon-cli-mark-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let here = std::env::current_dir().unwrap();
        std::env::set_current_dir(&dir).unwrap();
        mark_generated(Path::new("elsewhere/x"));
        let before = Path::new("out/.gitignore").exists();
        mark_generated(Path::new("out/demo"));
        let text = std::fs::read_to_string("out/.gitignore");
        std::env::set_current_dir(here).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        assert!(!before);
        assert_eq!(text.unwrap(), "*\n");
    }

    #[test]
    fn zero_frames_and_non_numbers_are_refused() {
        use clap::Parser;
        for bad in ["0", "-1", "x", "1.5"] {
            let arg = format!("--frames={bad}");
            let e = Cli::try_parse_from(["tryon", "demo", arg.as_str()]).unwrap_err();
            assert_eq!(e.kind(), clap::error::ErrorKind::ValueValidation, "{bad}");
            assert!(e.to_string().contains("--frames"), "{e}");
        }
        assert!(Cli::try_parse_from(["tryon", "demo", "--frames", "3"]).is_ok());
    }

    #[test]
    fn a_strict_run_whose_garment_falls_off_fails_with_its_own_status_after_writing() {
        // A sheet over a sphere it does not collide with falls past it.
        let text = "[scene]\nduration = 1.0\n[body]\nkind = \"sphere\"\n[garment]\nkind = \"square\"\nparticles = 6\n[effects]\nbody_collision = \"none\"\n";
        let scene = Scene::parse(text, Path::new("t.toml")).unwrap_or_else(|e| panic!("{e}"));
        let out = std::env::temp_dir().join(format!("tryon-cli-strict-{}", std::process::id()));
        let flags = |strict| RunFlags {
            frames: None,
            quiet: true,
            strict,
            checkpoint_every: 0,
            budget: BudgetFlags { limits: Vec::new() },
        };
        let source = (Some(Path::new("t.toml")), &[][..]);
        assert!(run_scene(scene.clone(), source, &out, &flags(false)).is_ok());
        let strict = run_scene(scene, source, &out, &flags(true));
        let written = out.join("stats.json").exists();
        let _ = std::fs::remove_dir_all(&out);
        assert!(matches!(strict, Err(Failure::LeftTheBody)));
        assert!(written);
    }

    #[test]
    fn limits_are_checked_as_arguments() {
        use clap::Parser;
        let e = Cli::try_parse_from(["tryon", "demo", "--limit", "speed=3"]).unwrap_err();
        assert!(e.to_string().contains("`speed` is not a limit"), "{e}");
        let ok = Cli::try_parse_from(["tryon", "check", "x.toml", "--limit", "hours=9"]);
        assert!(ok.is_ok());
    }
}
