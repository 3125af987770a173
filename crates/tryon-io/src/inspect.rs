//! One-screen summaries of asset files for `tryon inspect`: counts, joints, frames and rate,
//! bounding box and the units the numbers most likely are in.

use crate::bvh::{guess_unit, parse_bvh, rest_points};
use crate::read::{ReadError, read_text};
use std::fmt::Write;
use std::path::Path;
use tryon_core::math::{Real, Vec3};

/// The unit that makes a figure of `extent` file units closest to 1.7 m tall (ratio).
fn likely_unit(extent: Real) -> &'static str {
    crate::bvh::KNOWN_UNITS
        .iter()
        .min_by(|a, b| {
            let da = (extent * a.0 / 1.7).ln().abs();
            let db = (extent * b.0 / 1.7).ln().abs();
            da.total_cmp(&db)
        })
        .map_or("metres", |u| u.1)
}

fn bounds(p: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *p.first()?;
    Some(
        p.iter()
            .fold((first, first), |(lo, hi), q| (lo.inf(q), hi.sup(q))),
    )
}

fn fmt_box(out: &mut String, p: &[Vec3], unit_hint: bool) {
    if let Some((lo, hi)) = bounds(p) {
        let size = hi - lo;
        let _ = writeln!(
            out,
            "bounding box: min ({:.4}, {:.4}, {:.4}) max ({:.4}, {:.4}, {:.4}), size {:.4} x {:.4} x {:.4}",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, size.x, size.y, size.z
        );
        if unit_hint {
            let _ = writeln!(
                out,
                "likely units: {} (if it is a standing person: {:.3} file units tall)",
                likely_unit(size.max()),
                size.max()
            );
        }
    }
}

/// A summary of the asset at `path`, by its extension (.obj, .bvh, .mhskel, .mhw, .target,
/// .mhclo, .proxy).
pub fn summarize(path: &Path) -> Result<String, ReadError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let mut out = format!("{}\n", path.display());
    match ext.as_str() {
        "obj" => {
            let m = crate::read_obj(path)?;
            let quads = m
                .faces
                .iter()
                .filter(|f| matches!(f, tryon_core::mesh::Face::Quad(_)))
                .count();
            let _ = writeln!(
                out,
                "OBJ: {} vertices, {} faces ({} quads, {} triangles), {} texture coordinates{}",
                m.positions.len(),
                m.faces.len(),
                quads,
                m.faces.len() - quads,
                m.uvs.len(),
                if m.face_uvs.is_empty() {
                    ""
                } else {
                    " (every face mapped)"
                }
            );
            let _ = writeln!(out, "groups: {}", m.groups.len());
            for (name, r) in m.groups.iter().filter(|(_, r)| !r.is_empty()).take(8) {
                let _ = writeln!(out, "  {name}: {} faces", r.len());
            }
            fmt_box(&mut out, &m.positions, true);
        }
        "bvh" => {
            let f = parse_bvh(&read_text(path)?, path)?;
            let s = &f.skeleton;
            let (unit, name) = guess_unit(s, &f.end_sites);
            let frames = f.frames.len();
            let _ = writeln!(
                out,
                "BVH: {} joints (root `{}`), {} end sites, {} channels, {} frames at {:.2} fps ({:.2} s)",
                s.names.len(),
                s.names.first().map_or("", String::as_str),
                f.end_sites.len(),
                f.channels.iter().map(Vec::len).sum::<usize>(),
                frames,
                1.0 / f.frame_time,
                frames.saturating_sub(1) as Real * f.frame_time
            );
            let _ = writeln!(out, "joints: {}", s.names.join(" "));
            let _ = writeln!(out, "likely units: {name}");
            fmt_box(&mut out, &rest_points(s, &f.end_sites), false);
            if let (Some(a), Some(b)) = (f.frames.first(), f.frames.last()) {
                let d = (b.root_translation - a.root_translation) * unit;
                let _ = writeln!(
                    out,
                    "root travels ({:.2}, {:.2}, {:.2}) m from the first frame to the last",
                    d.x, d.y, d.z
                );
            }
        }
        "mhskel" => {
            let s = crate::read_mhskel(path)?;
            let roots: Vec<&str> = s
                .bones
                .iter()
                .filter(|b| b.parent.is_none())
                .map(|b| b.name.as_str())
                .collect();
            let _ = writeln!(
                out,
                "MakeHuman skeleton `{}`: {} bones, roots {:?}",
                s.name,
                s.bones.len(),
                roots
            );
            let names: Vec<&str> = s.bones.iter().map(|b| b.name.as_str()).collect();
            let _ = writeln!(out, "bones: {}", names.join(" "));
        }
        "mhw" => {
            let w = crate::read_mhw(path)?;
            let pairs: usize = w.bones.iter().map(|(_, l)| l.len()).sum();
            let mut per_vertex = std::collections::BTreeMap::<u32, (Real, usize)>::new();
            for (_, l) in &w.bones {
                for (v, x) in l {
                    let e = per_vertex.entry(*v).or_default();
                    e.0 += x;
                    e.1 += 1;
                }
            }
            let (lo, hi) = per_vertex
                .values()
                .fold((Real::MAX, Real::MIN), |(a, b), e| (a.min(e.0), b.max(e.0)));
            let most = per_vertex.values().map(|e| e.1).max().unwrap_or(0);
            let _ = writeln!(
                out,
                "MakeHuman weights: {} bones, {} (vertex, weight) pairs over {} vertices; sums {:.2}..{:.2}, up to {} bones per vertex (normalised and cut to 4 when skinning)",
                w.bones.len(),
                pairs,
                per_vertex.len(),
                lo,
                hi,
                most
            );
        }
        "target" => {
            let t = crate::read_target(path)?;
            let max = t.offsets.iter().map(|(_, d)| d.norm()).fold(0.0, Real::max);
            let _ = writeln!(
                out,
                "MakeHuman target `{}`: {} vertices moved, largest offset {:.4} m (read as decimetres)",
                t.name,
                t.offsets.len(),
                max
            );
        }
        "mhclo" | "proxy" => {
            let b = crate::read_binding(path)?;
            let refs = b.refs.iter().flatten().copied();
            let (lo, hi) = refs.fold((u32::MAX, 0), |(a, c), v| (a.min(v), c.max(v)));
            let _ = writeln!(
                out,
                "MakeHuman binding `{}` -> {}: {} bound vertices referring to base vertices {lo}..={hi}, {} scale references, {} base vertices hidden",
                b.name,
                b.obj_file,
                b.refs.len(),
                b.scales.iter().filter(|s| s.is_some()).count(),
                b.delete_verts.len()
            );
        }
        _ => {
            return Err(ReadError::UnknownKind {
                file: path.to_path_buf(),
                expected: ".obj, .bvh, .mhskel, .mhw, .target, .mhclo or .proxy",
            });
        }
    }
    Ok(out)
}
