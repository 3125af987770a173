//! (h) What the cloth's contact with itself and between garments costs and buys on every scene:
//! VBD with `[effects] self_collision` and `cloth_collision` both off and both on (each scene's
//! own settings otherwise; `cloth_collision` does nothing with one garment).

use super::*;

/// One scene with self-contact off or on.
#[derive(Clone, Debug)]
pub(super) struct LayerPoint {
    pub scene: &'static str,
    pub on: bool,
    pub crossings: usize,
    pub max_mm: Real,
    pub max_stretch: Real,
    pub cloth_ms: Real,
}

/// The scenes compared, with the frames of a quick run and of a full one (`None`: the scene's own
/// length). The real garments run their first 3 s in full: with self-contact a torn garment's
/// step grows to seconds (casual-131 over its whole clip ran more than 16 minutes).
const SCENES: [(&str, Option<usize>, Option<usize>); 7] = [
    ("drape-sphere.toml", Some(30), None),
    ("demo-dress-walk.toml", Some(12), None),
    ("skirt-walk.toml", Some(12), None),
    ("layered-walk.toml", Some(12), None),
    ("makehuman-dress-walk.toml", Some(4), Some(90)),
    ("makehuman-casual-131.toml", Some(4), Some(90)),
    ("makehuman-layered-131.toml", Some(4), Some(60)),
];

/// Points a complete sweep makes.
pub(super) const POINTS: usize = SCENES.len() * 2;

pub(super) fn layer_sweep(quick: bool, log: &mut String) -> Result<Vec<LayerPoint>, String> {
    let mut out = Vec::new();
    for (file, quick_frames, full_frames) in SCENES {
        for on in [false, true] {
            let sets = vec![
                "cloth.solver=\"vbd\"".to_string(),
                format!("effects.self_collision={on}"),
                format!("effects.cloth_collision={on}"),
            ];
            let frames = if quick { quick_frames } else { full_frames };
            let (s, _) = run_scene(file, &sets, frames)?;
            let m = &s.metrics;
            let p = LayerPoint {
                scene: file.trim_end_matches(".toml"),
                on,
                crossings: m.cloth_intersections,
                max_mm: m.max_penetration_m * 1e3,
                max_stretch: m.max_stretch,
                cloth_ms: stage_ms(&s, &["cloth"]),
            };
            logln!(
                log,
                "self-contact {} {}: {} crossing pairs, penetration {:.2} mm, stretch {:.3}, cloth {:.2} ms",
                p.scene,
                if on { "on" } else { "off" },
                p.crossings,
                p.max_mm,
                p.max_stretch,
                p.cloth_ms
            );
            out.push(p);
        }
    }
    Ok(out)
}

/// The report's section (h).
pub(super) fn section(r: &mut String, points: &[LayerPoint]) {
    let _ = writeln!(r, "\n## (h) The cloth against itself\n");
    let _ = writeln!(
        r,
        "`[effects] self_collision` and `cloth_collision` under VBD, both off and both on (two garments in the layered scenes): the most crossing pairs of garment triangles in a frame (the referee, `body-collide/src/crossings.rs`), penetration into the body, stretch, and the cloth step's cost. The MakeHuman scenes run their first 90 frames (makehuman-layered-131: 60), the others their whole length.\n"
    );
    let _ = writeln!(
        r,
        "| scene | self-contact | crossing pairs | penetration max mm | stretch max | cloth ms/frame |\n|---|---|---|---|---|---|"
    );
    for p in points {
        let _ = writeln!(
            r,
            "| {} | {} | {} | {:.2} | {:.3} | {:.2} |",
            p.scene,
            if p.on { "on" } else { "off" },
            p.crossings,
            p.max_mm,
            p.max_stretch,
            p.cloth_ms
        );
    }
}
