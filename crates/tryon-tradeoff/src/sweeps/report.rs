//! The report: the sweeps run in order, tables and SVG plots with their Pareto fronts written to
//! report.md under the output folder, and the short summary.

use super::*;

/// The cheapest collider setting of a scene with max penetration <= 1 mm and stretch <= 1.03.
fn cheapest(points: &[ColliderPoint], scene: &str) -> String {
    let ok: Vec<&ColliderPoint> = points
        .iter()
        .filter(|p| p.scene == scene && p.max_mm <= 1.0 && p.stretch <= 1.03)
        .collect();
    match ok.iter().min_by(|a, b| a.ms.total_cmp(&b.ms)) {
        Some(p) => format!("{} ({:.2} ms/frame)", p.label, p.ms),
        None => {
            let best = points
                .iter()
                .filter(|p| p.scene == scene)
                .min_by(|a, b| a.max_mm.total_cmp(&b.max_mm));
            match best {
                Some(b) => format!(
                    "none meets both (least penetration: {} at {:.2} mm, stretch {:.3}, {:.2} ms/frame)",
                    b.label, b.max_mm, b.stretch, b.ms
                ),
                None => "no points".into(),
            }
        }
    }
}

pub fn run_all(quick: bool, out: &Path, summary: Option<&Path>) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let started = Instant::now();
    let mut log = String::new();
    let colliders = collider_sweep(quick, &mut log)?;
    let (integrators, stability, h_ref_ms) = integrator_sweep(quick, &mut log)?;
    let refine = refine_sweep(quick, &mut log)?;
    let wrinkles = wrinkle_sweep(quick, &mut log)?;
    let spot = spot_sweep(quick, &mut log)?;
    let guard = guard_sweep(quick, &mut log)?;
    let solvers = super::solvers::solver_sweep(quick, &mut log)?;
    let layers = super::layers::layer_sweep(quick, &mut log)?;

    // Plots.
    let mut plots = Vec::new();
    for scene in COLLIDER_SCENES {
        let pts: Vec<&ColliderPoint> = colliders.iter().filter(|p| p.scene == scene).collect();
        for (metric, get) in [
            (
                "max",
                (|p: &ColliderPoint| p.max_mm) as fn(&ColliderPoint) -> Real,
            ),
            ("p99", |p: &ColliderPoint| p.p99_mm),
        ] {
            let series = vec![Series {
                name: format!("{scene} colliders"),
                points: pts
                    .iter()
                    .map(|p| (p.ms, get(p), p.label.clone()))
                    .collect(),
            }];
            let file = format!("colliders-{scene}-{metric}.svg");
            scatter(
                &out.join(&file),
                &format!("{scene}: {metric} penetration against time"),
                "ms per frame (all stages but the referee)",
                &format!("{metric} penetration (mm)"),
                Scale::Linear,
                Scale::Linear,
                &series,
                true,
            )?;
            plots.push(file);
        }
    }
    let series: Vec<Series> = KINDS
        .iter()
        .map(|k| Series {
            name: k.as_str().into(),
            points: integrators
                .iter()
                .filter(|p| p.integrator == k.as_str() && p.error_mm.is_finite())
                .map(|p| (p.ms, p.error_mm, format!("{:.2}", p.h_ms)))
                .collect(),
        })
        .collect();
    scatter(
        &out.join("integrators.svg"),
        "drape: error against a converged reference (labels: step in ms)",
        "ms per frame",
        "RMS position error (mm)",
        Scale::Log { floor: 1e-3 },
        Scale::Log { floor: 1e-6 },
        &series,
        true,
    )?;
    plots.push("integrators.svg".into());
    let series: Vec<Series> = KINDS
        .iter()
        .map(|k| Series {
            name: k.as_str().into(),
            points: stability
                .iter()
                .filter(|p| p.integrator == k.as_str())
                .filter_map(|p| p.largest_ms.map(|h| (p.k_scale, h, String::new())))
                .collect(),
        })
        .collect();
    scatter(
        &out.join("stability.svg"),
        "drape: largest stable step against stretch stiffness",
        "stretch stiffness (times the scene's)",
        "largest stable step (ms)",
        Scale::Log { floor: 1e-3 },
        Scale::Log { floor: 1e-3 },
        &series,
        false,
    )?;
    plots.push("stability.svg".into());
    scatter(
        &out.join("refine.svg"),
        "demo: surface deviation from the finest level against time (labels: level)",
        "ms per frame (surface stages)",
        "mean deviation (mm)",
        Scale::Linear,
        Scale::Linear,
        &[Series {
            name: "refine level".into(),
            points: refine
                .iter()
                .map(|p| (p.ms, p.mean_dev_mm, format!("L{}", p.level)))
                .collect(),
        }],
        true,
    )?;
    plots.push("refine.svg".into());
    scatter(
        &out.join("wrinkles.svg"),
        "length restoration against time (refine 2)",
        "ms per frame (surface stages)",
        "mean |fine length - rest| / rest",
        Scale::Linear,
        Scale::Linear,
        &["demo-dress-walk", "shirt-elbow-bend"]
            .iter()
            .map(|scene| Series {
                name: scene.to_string(),
                points: wrinkles
                    .iter()
                    .filter(|p| p.scene == *scene)
                    .map(|p| (p.ms, p.length_error, p.model.into()))
                    .collect(),
            })
            .collect::<Vec<_>>(),
        true,
    )?;
    plots.push("wrinkles.svg".into());

    // Every curve must have points.
    let mut empty = Vec::new();
    for scene in COLLIDER_SCENES {
        if !colliders.iter().any(|p| p.scene == scene) {
            empty.push(format!("colliders on {scene}"));
        }
    }
    for k in KINDS {
        if !integrators
            .iter()
            .any(|p| p.integrator == k.as_str() && p.error_mm.is_finite())
        {
            empty.push(format!("integrator error of {}", k.as_str()));
        }
        if !stability
            .iter()
            .any(|p| p.integrator == k.as_str() && p.largest_ms.is_some())
        {
            empty.push(format!("stable steps of {}", k.as_str()));
        }
    }
    if refine.len() != 5 {
        empty.push("refine levels".into());
    }
    if wrinkles.iter().any(|p| !p.length_error.is_finite()) {
        empty.push("wrinkle length error".into());
    }
    if spot.len() != 4 {
        empty.push("spot".into());
    }
    if guard.len() != 3 {
        empty.push("stretch guard".into());
    }
    if solvers.len() != super::solvers::POINTS {
        empty.push("solvers".into());
    }
    if layers.len() != super::layers::POINTS {
        empty.push("self-contact".into());
    }

    // Report.
    let mut r = String::new();
    let mode = if quick {
        " (quick: few frames, few settings)"
    } else {
        ""
    };
    let _ = writeln!(r, "# What accuracy costs in time{mode}\n");
    let _ = writeln!(
        r,
        "Machine: {}. Date: {}. Sweep time {:.0} s. Times are means per frame of one run on a noisy machine; compare them as ratios.\n",
        tryon_io::machine::description(),
        tryon_io::machine::today(),
        started.elapsed().as_secs_f64()
    );
    let _ = writeln!(r, "## (a) Colliders\n");
    let _ = writeln!(
        r,
        "Penetration of the output surface (fine when the scene refines) by the exact referee, over all frames; ms are all stages but the referee; collider ms is the collider update plus the fine collision stage.\n"
    );
    let _ = writeln!(
        r,
        "| scene | collider | ms/frame | collider ms | max mm | p99 mm | share > 1 mm | max stretch |\n|---|---|---|---|---|---|---|---|"
    );
    for p in &colliders {
        let _ = writeln!(
            r,
            "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4} | {:.3} |",
            p.scene, p.label, p.ms, p.collider_ms, p.max_mm, p.p99_mm, p.share, p.stretch
        );
    }
    let _ = writeln!(
        r,
        "\nCheapest setting with max penetration <= 1 mm and stretch <= 1.03:\n"
    );
    for scene in COLLIDER_SCENES {
        let _ = writeln!(r, "- {scene}: {}", cheapest(&colliders, scene));
    }
    let _ = writeln!(r, "\n## (b) Integrators\n");
    let _ = writeln!(
        r,
        "Drape, fixed substep (no automatic step, no retries), error = RMS particle distance from RK4 at {h_ref_ms} ms after the same simulated time.\n"
    );
    let _ = writeln!(
        r,
        "| integrator | step ms | ms/frame | RMS error mm | stable |\n|---|---|---|---|---|"
    );
    for p in &integrators {
        let _ = writeln!(
            r,
            "| {} | {:.3} | {:.2} | {:.4} | {} |",
            p.integrator, p.h_ms, p.ms, p.error_mm, p.stable
        );
    }
    let _ = writeln!(
        r,
        "\nLargest stable step (0.25 ms times powers of sqrt 2, up to a 1/60 s frame) against stretch stiffness, with the strain limit off (it would hide an unstable integrator):\n\n| integrator | stiffness x | largest stable step ms |\n|---|---|---|"
    );
    for p in &stability {
        let _ = writeln!(
            r,
            "| {} | {} | {} |",
            p.integrator,
            p.k_scale,
            p.largest_ms
                .map_or("none".to_string(), |h| format!("{h:.2}"))
        );
    }
    let _ = writeln!(r, "\n## (c) Refinement level (demo)\n");
    let _ = writeln!(
        r,
        "| level | fine vertices | surface ms | max deviation mm | mean deviation mm |\n|---|---|---|---|---|"
    );
    for p in &refine {
        let _ = writeln!(
            r,
            "| {} | {} | {:.2} | {:.3} | {:.3} |",
            p.level, p.fine_vertices, p.ms, p.max_dev_mm, p.mean_dev_mm
        );
    }
    let _ = writeln!(r, "\n## (d) Wrinkles (level 2)\n");
    let _ = writeln!(
        r,
        "Over the coarse edges compressed on the reference surface (the refined surface before \
         wrinkles), mean |fine path - rest| / rest, and the share back within 2% of rest. \
         `force` is P1.4.3 as written, `compression` the default relief (docs/decisions, *wrinkle model*, \
         2026-11-29).\n\n\
         | scene | wrinkles | surface ms | length error | reference's | restored share | reference's |\n\
         |---|---|---|---|---|---|---|"
    );
    for p in &wrinkles {
        let _ = writeln!(
            r,
            "| {} | {} | {:.2} | {:.4} | {:.4} | {:.3} | {:.3} |",
            p.scene,
            p.model,
            p.ms,
            p.length_error,
            p.reference_error,
            p.restored,
            p.reference_restored
        );
    }
    let _ = writeln!(r, "\n## (e) P4: cloth on spot\n");
    let _ = writeln!(
        r,
        "| run | stage ms/frame | wall ms/frame | fine max mm | fine p99 mm | share > 1 mm |\n|---|---|---|---|---|---|"
    );
    for p in &spot {
        let _ = writeln!(
            r,
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4} |",
            p.label, p.ms, p.wall_ms, p.max_mm, p.p99_mm, p.share
        );
    }
    let _ = writeln!(r, "\n## (f) Stretch guard (demo walk, P1's solver)\n");
    let _ = writeln!(
        r,
        "P1's solver (the demo itself runs VBD, which needs no guard): a substep that stretches a structural edge past the guard ratio is retried at half the step (`[cloth.p1] stretch_guard`). Stretch is over the coarse edges, penetration over the output surface. The walk is chaotic: a setting that changes any substep changes the whole run after it, so single figures here move between settings by more than the setting itself explains.\n"
    );
    let _ = writeln!(
        r,
        "| guard | cloth ms/frame | retries | max stretch | mean stretch | frames over 1.1 | max penetration mm |\n|---|---|---|---|---|---|---|"
    );
    for p in &guard {
        let _ = writeln!(
            r,
            "| {} | {:.2} | {} | {:.3} | {:.4} | {:.2} | {:.2} |",
            p.label, p.cloth_ms, p.retries, p.max_stretch, p.mean_stretch, p.over, p.max_mm
        );
    }
    super::solvers::section(&mut r, &solvers);
    super::layers::section(&mut r, &layers);
    let _ = writeln!(r, "\n## Plots\n");
    for f in &plots {
        let _ = writeln!(r, "![{f}]({f})\n");
    }
    let _ = writeln!(r, "## Log\n\n```\n{log}```");
    write_atomic(&out.join("report.md"), &r)?;
    if let Some(path) = summary {
        write_atomic(path, &r)?;
    }
    eprintln!("tradeoff: wrote {}", out.join("report.md").display());
    if !empty.is_empty() {
        return Err(format!("curves without points: {}", empty.join(", ")));
    }
    Ok(())
}

/// Writes `text` to a temporary file beside `path`, then renames it into place.
fn write_atomic(path: &Path, text: &str) -> Result<(), String> {
    if let Some(dir) = path.parent()
        && !dir.as_os_str().is_empty()
    {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    let tmp = path.with_extension("md.tmp");
    std::fs::write(&tmp, text).map_err(|e| format!("{}: {e}", tmp.display()))?;
    std::fs::rename(&tmp, path).map_err(|e| format!("{}: {e}", path.display()))
}
