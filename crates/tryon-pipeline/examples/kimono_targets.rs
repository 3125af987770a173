//! Makes P2's target shapes (issue 23 item 3): the family's initial kimono and its ten targets,
//! each tailored flat and put on the mannequin of its wearer's size by the cloth solver
//! (`tryon_pipeline::kimono_wear`). Run by `cargo xtask kimono-targets`, which writes
//! data/kimono/NAME.obj and data/kimono/targets.json, and four pictures per shape under
//! target/kimono-targets/.
//!
//! `cargo run --release -p tryon-pipeline --example kimono_targets -- OUT PICTURES [INDEX...]`
//! (indices 0 = the initial shape, 1-10 the targets; all when none are given).

use std::path::{Path, PathBuf};
use std::time::Instant;
use tryon_core::math::Vec3;
use tryon_io::preview::{Camera, PreviewMesh, render, write_png};
use tryon_pipeline::kimono_wear::store::{ShapeRecord, family_wearers, shape_name, shape_obj};
use tryon_pipeline::kimono_wear::{WearSettings, Worn, wear};

fn pictures(stem: &Path, worn: &Worn, triangles: &[[u32; 3]]) -> Result<(), String> {
    let views = [
        (Vec3::new(0.0, 1.0, 3.2), Vec3::new(0.0, 0.85, 0.0)),
        (Vec3::new(2.4, 1.0, -2.2), Vec3::new(0.0, 0.85, 0.0)),
        (Vec3::new(0.5, 0.4, 1.0), Vec3::new(0.0, 0.2, 0.0)),
        (Vec3::new(0.3, 1.0, 1.0), Vec3::new(0.0, 0.9, 0.0)),
    ];
    for (k, (eye, target)) in views.iter().enumerate() {
        let cam = Camera {
            eye: *eye,
            target: *target,
            up: Vec3::y(),
            fov_y: 40.0,
        };
        let meshes = [
            PreviewMesh {
                positions: &worn.body,
                triangles: &worn.body_triangles,
                color: [200, 170, 150],
            },
            PreviewMesh {
                positions: &worn.positions,
                triangles,
                color: [60, 90, 170],
            },
        ];
        let img = render(&meshes, &cam, 480, 640);
        let path = PathBuf::from(format!("{}-{k}.png", stem.display()));
        write_png(&path, &img).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (out, pics) = match (args.first(), args.get(1)) {
        (Some(o), Some(p)) => (PathBuf::from(o), PathBuf::from(p)),
        _ => return Err("usage: kimono_targets OUT PICTURES [INDEX...]".into()),
    };
    let wearers = family_wearers();
    let mut only = Vec::new();
    for a in &args[2..] {
        match a.parse::<usize>() {
            Ok(i) if i < wearers.len() => only.push(i),
            _ => return Err(format!("`{a}`: an index is 0 to {}", wearers.len() - 1)),
        }
    }
    for d in [&out, &pics] {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
    }
    let fam = kimono::family::flat_family().map_err(|e| e.to_string())?;
    let settings = WearSettings::default();
    let mut records = Vec::new();
    for (i, w) in wearers.iter().enumerate() {
        if !only.is_empty() && !only.contains(&i) {
            continue;
        }
        let flat = if i == 0 {
            &fam.base.positions
        } else {
            &fam.targets[i - 1]
        };
        let name = shape_name(w);
        let clock = Instant::now();
        let mut last = String::new();
        let mut progress = |act: &str, f: usize, n: usize| {
            if f == n || f.is_multiple_of(30) {
                last = format!("{name}: {act} {f}/{n}");
                eprintln!("{last}");
            }
        };
        let worn = wear(w, flat, &fam.base, &settings, &mut progress)
            .map_err(|e| format!("{name}: {e}"))?;
        let path = out.join(&name);
        tryon_io::write_atomic(
            &path,
            shape_obj(w, &worn.positions, &fam.base.triangles).as_bytes(),
        )
        .map_err(|e| format!("{}: {e}", path.display()))?;
        pictures(
            &pics.join(name.trim_end_matches(".obj")),
            &worn,
            &fam.base.triangles,
        )?;
        println!(
            "{name}: crossings start {} inflated {} tied {}; rows off their rings {:.3?} m; hem {:+.3} m from the ankle; {:.0} ms a frame, {:.0} s",
            worn.crossings[0],
            worn.crossings[1],
            worn.crossings[2],
            worn.row_lag_m,
            worn.hem_above_ankle_m,
            worn.ms_per_frame,
            clock.elapsed().as_secs_f64()
        );
        records.push(ShapeRecord {
            file: name,
            role: if i == 0 { "initial" } else { "target" },
            wearer: [w.height, w.bust, w.waist, w.hip],
            crossings: worn.crossings,
            row_lag_m: worn.row_lag_m,
            hem_above_ankle_m: worn.hem_above_ankle_m,
            ms_per_frame: worn.ms_per_frame,
        });
    }
    if only.is_empty() {
        let json = serde_json::to_string_pretty(
            &serde_json::json!({ "settings": format!("{settings:?}"), "shapes": records }),
        )
        .map_err(|e| e.to_string())?;
        let path = out.join("targets.json");
        tryon_io::write_atomic(&path, json.as_bytes())
            .map_err(|e| format!("{}: {e}", path.display()))?;
    }
    Ok(())
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
