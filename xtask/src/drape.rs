//! `cargo xtask drape`: runs the drape scene in release and prints what it measured.

use cloth_dyn::IntegratorKind;
use std::process::Command;
use tryon_pipeline::{DrapeConfig, DrapeScene};

/// Runs [`run`] in a release build: xtask itself is built without whole-program LTO (the `tools`
/// profile), whose times are not the ones to quote, so from there it runs itself again in release.
pub fn run_in_release(args: &[String]) -> Result<(), String> {
    let exe = std::env::current_exe().map_err(|e| format!("cannot find xtask's own path: {e}"))?;
    let in_release = exe
        .parent()
        .and_then(|d| d.file_name())
        .is_some_and(|d| d == "release");
    if in_release {
        return run(args);
    }
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let status = Command::new(&cargo)
        .args(["run", "--release", "-q", "-p", "xtask", "--", "drape"])
        .args(args)
        .status()
        .map_err(|e| format!("cannot run {cargo}: {e}"))?;
    match status.success() {
        true => Ok(()),
        false => Err(format!("the release drape run failed ({status})")),
    }
}

pub fn run(args: &[String]) -> Result<(), String> {
    let mut sizes = Vec::new();
    let mut kinds = vec![IntegratorKind::Rk4, IntegratorKind::SymplecticEuler];
    let mut frames = None;
    let mut trace = false;
    let mut png: Option<std::path::PathBuf> = None;
    let mut sets: Vec<(String, f64)> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--integrator" => {
                let v = it
                    .next()
                    .ok_or("--integrator needs a value: rk4, symplectic_euler or all")?;
                kinds = match v.as_str() {
                    "all" => kinds,
                    s => vec![IntegratorKind::parse(s).ok_or(format!(
                        "unknown integrator `{s}`: expected rk4, symplectic_euler or all"
                    ))?],
                };
            }
            "--frames" => {
                let v = it.next().ok_or("--frames needs a number")?;
                frames = Some(
                    v.parse::<usize>()
                        .map_err(|_| format!("--frames: `{v}` is not a whole number"))?,
                );
            }
            "--trace" => trace = true,
            "--png" => png = Some(it.next().ok_or("--png needs a file path")?.into()),
            "--set" => {
                let v = it.next().ok_or("--set needs key=value")?;
                let (k, x) = v
                    .split_once('=')
                    .ok_or(format!("--set: `{v}` is not key=value"))?;
                let x = x
                    .parse::<f64>()
                    .map_err(|_| format!("--set {k}: `{x}` is not a number"))?;
                sets.push((k.to_string(), x));
            }
            s => sizes.push(
                s.parse::<usize>()
                    .map_err(|_| format!("`{s}` is not a particle count per side"))?,
            ),
        }
    }
    if sizes.is_empty() {
        sizes = vec![32, 64, 128];
    }
    println!(
        "| N | integrator | substep (ms) | median ms/frame | mean ms/frame | max stretch | max penetration (mm) | max drift (mm) | retries | rollbacks |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for &n in &sizes {
        for &k in &kinds {
            let mut cfg = DrapeConfig::new(n, k);
            if let Some(f) = frames {
                cfg.duration = f as f64 / cfg.fps;
            }
            for (key, x) in &sets {
                apply_set(&mut cfg, key, *x)?;
            }
            let mut scene = DrapeScene::new(cfg).map_err(|e| e.to_string())?;
            let progress = std::io::IsTerminal::is_terminal(&std::io::stderr()) && !trace;
            let r = scene.run(|f| {
                if progress && (f.frame % 10 == 0 || f.frame == f.frames) {
                    eprint!(
                        "\rxtask: drape N = {n} {}: frame {}/{}",
                        k.as_str(),
                        f.frame,
                        f.frames
                    );
                    if f.frame == f.frames {
                        eprint!("\r\x1b[2K");
                    }
                }
                if trace {
                    eprintln!(
                        "frame {:4}/{}: {:.3} ms, stretch {:.4} at {:.3?}, contacts {}, centroid {:.4?}, kinetic {:.2e} J",
                        f.frame,
                        f.frames,
                        f.ms,
                        f.stretch,
                        f.worst_at.as_slice(),
                        f.contacts,
                        f.centroid.as_slice(),
                        f.kinetic
                    );
                }
            });
            println!(
                "| {} | {} | {:.3} | {:.3} | {:.3} | {:.4} | {:.3} | {:.1} | {} | {} |",
                r.n,
                r.integrator,
                r.substep * 1e3,
                r.median_ms,
                r.mean_ms,
                r.max_stretch,
                r.max_penetration * 1e3,
                r.max_drift * 1e3,
                r.steps.retries,
                r.steps.rollbacks
            );
            if let Some(path) = &png {
                picture(&scene, path)?;
            }
        }
    }
    Ok(())
}

/// Overrides one drape setting by name.
fn apply_set(cfg: &mut DrapeConfig, key: &str, x: f64) -> Result<(), String> {
    let p = &mut cfg.params;
    match key {
        "max_strain" => p.max_strain = if x > 0.0 { Some(x) } else { None },
        "strain_iterations" => p.strain_iterations = x as u32,
        "strain_relaxation" => p.strain_relaxation = x,
        "tethers" => p.tethers = x != 0.0,
        "max_substep" => p.max_substep = x,
        "k_scale" => {
            p.k_stretch *= x;
            p.k_compress *= x;
            p.k_shear *= x;
            p.k_bend *= x;
        }
        "bend_scale" => p.k_bend *= x,
        "long_range" => p.long_range = x != 0.0,
        "stretch_guard" => p.stretch_guard = if x > 0.0 { Some(x) } else { None },
        "min_bend_ratio" => p.min_bend_ratio = if x > 0.0 { Some(x) } else { None },
        "compress_scale" => p.k_compress *= x,
        "thickness" => cfg.thickness = x,
        "penetration" => cfg.measure_penetration = x != 0.0,
        "friction" => p.friction = x,
        "velocity_damping" => p.velocity_damping = x,
        "air_drag" => p.air_drag = x,
        "bending_rigidity" => p.bending_rigidity = x,
        "auto_substep" => p.auto_substep = x != 0.0,
        "k_bend" => p.k_bend = x,
        _ => {
            return Err(format!(
                "--set: unknown key `{key}` (max_strain, strain_iterations, strain_relaxation, tethers, max_substep, k_scale, bend_scale, compress_scale, long_range, stretch_guard, min_bend_ratio, thickness, penetration, friction, velocity_damping, air_drag, bending_rigidity, k_bend, auto_substep)"
            ));
        }
    }
    Ok(())
}

/// Writes a picture of the scene's current frame (the last run's, when several run).
fn picture(scene: &DrapeScene, path: &std::path::Path) -> Result<(), String> {
    use tryon_io::{Camera, PreviewMesh, render, write_png};
    let p = &scene.pipeline;
    let body = &p.referee.body;
    let garment = p.output_triangles();
    let meshes = [
        PreviewMesh {
            positions: &body.positions,
            triangles: &body.triangles,
            color: [190, 190, 200],
        },
        PreviewMesh {
            positions: p.output_garment(),
            triangles: &garment,
            color: [200, 70, 60],
        },
    ];
    let cam = Camera::framing(&meshes);
    write_png(path, &render(&meshes, &cam, 800, 600)).map_err(|e| e.to_string())?;
    eprintln!("xtask: wrote {}", path.display());
    Ok(())
}
