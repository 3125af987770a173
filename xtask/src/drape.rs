//! `cargo xtask drape`: runs the drape scene in release and prints what it measured.

use cloth_dyn::IntegratorKind;
use tryon_pipeline::{DrapeConfig, DrapeScene};

pub fn run(args: &[String]) -> Result<(), String> {
    let mut sizes = Vec::new();
    let mut kinds = vec![IntegratorKind::Rk4, IntegratorKind::SymplecticEuler];
    let mut frames = None;
    let mut trace = false;
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
        "| N | integrator | substep (ms) | median ms/frame | mean ms/frame | max stretch | max penetration (mm) | retries | rollbacks |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
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
            let r = scene.run(|f| {
                if trace {
                    eprintln!(
                        "frame {:4}/{}: {:.3} ms, stretch {:.4} at {:.3?}, contacts {}",
                        f.frame,
                        f.frames,
                        f.ms,
                        f.stretch,
                        f.worst_at.as_slice(),
                        f.contacts
                    );
                }
            });
            println!(
                "| {} | {} | {:.3} | {:.3} | {:.3} | {:.4} | {:.3} | {} | {} |",
                r.n,
                r.integrator,
                r.substep * 1e3,
                r.median_ms,
                r.mean_ms,
                r.max_stretch,
                r.max_penetration * 1e3,
                r.steps.retries,
                r.steps.rollbacks
            );
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
        "thickness" => cfg.thickness = x,
        "penetration" => cfg.measure_penetration = x != 0.0,
        "friction" => p.friction = x,
        _ => {
            return Err(format!(
                "--set: unknown key `{key}` (max_strain, strain_iterations, max_substep, k_scale, thickness, friction)"
            ));
        }
    }
    Ok(())
}
