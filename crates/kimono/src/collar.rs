//! The collar: a strip sewn along both sides' collar edges (from one collar end up the front,
//! across the back neck, down to the other end), standing out of the flat kimono by the collar's
//! width, which widens from the back centre to the ends (バチ衿). Its middle, from the back centre
//! to [`OVER_COLLAR`] below the shoulder fold on each front, is the over-collar (共衿), cut from the
//! other half of the collar strip.

use crate::builder::{Builder, lerp};
use crate::dims::Dimensions;
use crate::levels::Layout;
use crate::mesh::{HALF_BOLT, LAYER, OVER_COLLAR, Part, bolt_starts, sub};
use crate::panels::CollarEdge;
use tryon_core::math::{Real, Vec3};

/// One vertex of the collar's sewn edge.
struct Seam {
    id: u32,
    /// Unit direction the collar stands out in, in the kimono's plane.
    out: Vec3,
    /// Which side: +1 left, −1 right.
    side: Real,
    /// Arc length from the left end.
    arc: Real,
    /// Arc length from the back centre.
    from_centre: Real,
    /// Collar width here.
    width: Real,
}

/// The collar along `edges` (right side, left side) and its two width dimension sets.
pub(crate) fn collar(b: &mut Builder, d: &Dimensions, layout: &Layout, edges: &[CollarEdge; 2]) {
    let seam = seam(b, d, edges);
    let n = layout.collar;
    let v0 = bolt_starts(d)[5];
    let over_at = d.neck_half + OVER_COLLAR;
    let over: Vec<bool> = seam
        .iter()
        .map(|s| s.from_centre <= over_at + 1e-9)
        .collect();
    let first = over.iter().position(|&o| o).unwrap_or(0);
    let last = over.iter().rposition(|&o| o).unwrap_or(seam.len() - 1);
    let mut ids = Vec::with_capacity(seam.len());
    for s in &seam {
        let p = b.pos[s.id as usize];
        let z = if s.out.y > 0.999 { 0.0 } else { s.side * LAYER };
        let mut row = vec![s.id];
        for k in 1..=n {
            let q = p + s.out * (s.width * k as Real / n as Real);
            row.push(b.vert(q.x, q.y, p.z + z));
        }
        ids.push(row);
    }
    let uv_rows = |range: std::ops::RangeInclusive<usize>, u0: Real, v_at: Real| {
        range
            .map(|m| {
                let s = &seam[m];
                (0..=n)
                    .map(|k| [u0 + s.width * k as Real / n as Real, v0 + s.arc - v_at])
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>()
    };
    let v_over = seam[first].arc;
    for (range, part) in [
        (0..=first, Part::Collar),
        (first..=last, Part::OverCollar),
        (last..=seam.len() - 1, Part::Collar),
    ] {
        let (u0, v_at) = if part == Part::OverCollar {
            (HALF_BOLT, v_over)
        } else {
            (0.0, 0.0)
        };
        let uv = uv_rows(range.clone(), u0, v_at);
        b.grid(&ids[range], &uv, part, sub::COLLAR);
    }
    let centre = edges[1].ids.len() - 1;
    let none = |_: usize| false;
    b.dimension(14, true, sub::COLLAR, &ids[centre], &none);
    b.dimension(15, true, sub::COLLAR, &ids[0], &none);
    b.dimension(15, false, sub::COLLAR, &ids[seam.len() - 1], &none);
}

/// The sewn edge from the left end to the right end, with the direction and width of the collar at
/// each vertex.
fn seam(b: &Builder, d: &Dimensions, edges: &[CollarEdge; 2]) -> Vec<Seam> {
    let mut sides: Vec<Vec<Seam>> = Vec::new();
    for (e, side) in [(&edges[1], 1.0), (&edges[0], -1.0)] {
        let p: Vec<Vec3> = e.ids.iter().map(|&i| b.pos[i as usize]).collect();
        let mut arc = vec![0.0; p.len()];
        for m in 1..p.len() {
            arc[m] = arc[m - 1] + (p[m] - p[m - 1]).norm();
        }
        let total = arc[p.len() - 1];
        let up = Vec3::y();
        let mut v = Vec::new();
        for m in 0..p.len() {
            let t = p[(m + 1).min(p.len() - 1)] - p[m.saturating_sub(1)];
            let normal = Vec3::new(-t.y, t.x, 0.0).normalize() * side;
            let out = if m >= e.back_from {
                up
            } else if m + 1 == e.back_from {
                (normal + up).normalize()
            } else {
                normal
            };
            let from_centre = total - arc[m];
            v.push(Seam {
                id: e.ids[m],
                out,
                side,
                arc: 0.0,
                from_centre,
                width: lerp(d.collar_width_back, d.collar_width_tip, from_centre / total),
            });
        }
        sides.push(v);
    }
    // Left end to the back centre, then the right side back out to its end.
    let right = sides.pop().unwrap_or_default();
    let mut all = sides.pop().unwrap_or_default();
    all.extend(right.into_iter().rev().skip(1));
    for m in 1..all.len() {
        let step = (b.pos[all[m].id as usize] - b.pos[all[m - 1].id as usize]).norm();
        all[m].arc = all[m - 1].arc + step;
    }
    all
}
