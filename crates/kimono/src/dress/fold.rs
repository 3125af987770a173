//! The ohashori folded into the flat start, before the body grows: the skirt hangs from the
//! ohashori band's head level, the band's lower half goes down inside it and its upper half comes
//! up outside, each a layer further out; the left front's whole stack lies outside the right
//! front's (left over right, as a kimono is always worn). The collar and over-collar go with the
//! front vertex nearest along the mesh; the sleeves stay unfolded.

use crate::KimonoMesh;
use crate::mesh::sub;
use std::collections::VecDeque;
use tryon_core::math::{Real, Vec3};

/// Gap between the fold's layers (m).
const LAYER: Real = 0.004;

/// Where the flat kimono lies around the squashed body.
#[derive(Debug)]
pub struct Placement<'a> {
    /// The flat kimono moved over the body (fold line just over the shoulders).
    pub rest: &'a [Vec3],
    pub base: &'a KimonoMesh,
    /// The body's middle plane (z).
    pub zc: Real,
    /// The flat kimono's hem height (y).
    pub hem: Real,
    /// The cord's and the ohashori band head's heights above the hem on the pattern.
    pub cord: Real,
    pub band: Real,
}

/// The folded start and the rows the fold hangs from (the cord's and the band head's).
#[derive(Clone, Debug)]
pub struct Folded {
    pub start: Vec<Vec3>,
    pub band_rows: Vec<u32>,
    /// The height the band rows are held at while the body grows.
    pub band_y: Real,
}

/// Each vertex's side and the front vertex it moves with: the fronts their own, the collar and
/// over-collar those reached first by a flood through the collar from the fronts.
fn sides(p: &Placement) -> (Vec<bool>, Vec<u32>) {
    let subs = p.base.sub_mesh_vertices();
    let in_sub = |k: u8, v: u32| subs[k as usize].binary_search(&v).is_ok();
    let front = |w: u32| {
        !in_sub(sub::COLLAR, w) && (in_sub(sub::LEFT_FRONT, w) || in_sub(sub::RIGHT_FRONT, w))
    };
    let n = p.rest.len();
    let mut label: Vec<Option<(bool, u32)>> = (0..n as u32)
        .map(|v| front(v).then(|| (in_sub(sub::LEFT_FRONT, v), v)))
        .collect();
    let mut adj = vec![Vec::new(); n];
    for t in &p.base.triangles {
        for e in 0..3 {
            adj[t[e] as usize].push(t[(e + 1) % 3]);
            adj[t[(e + 1) % 3] as usize].push(t[e]);
        }
    }
    let mut queue: VecDeque<u32> = (0..n as u32)
        .filter(|&v| label[v as usize].is_some())
        .collect();
    while let Some(v) = queue.pop_front() {
        let l = label[v as usize];
        for &w in &adj[v as usize] {
            if label[w as usize].is_none() && in_sub(sub::COLLAR, w) {
                label[w as usize] = l;
                queue.push_back(w);
            }
        }
    }
    let left = label.iter().map(|l| l.is_some_and(|l| l.0)).collect();
    let source = (0..n as u32)
        .map(|v| match label[v as usize] {
            Some((_, s)) if in_sub(sub::COLLAR, v) => s,
            _ => v,
        })
        .collect();
    (left, source)
}

/// Folds the ohashori into `start` (the flat placement with the back collar behind the neck).
pub fn fold(p: &Placement, start: Vec<Vec3>) -> Folded {
    let subs = p.base.sub_mesh_vertices();
    let sleeve = |v: u32| {
        subs[sub::RIGHT_SLEEVE as usize].binary_search(&v).is_ok()
            || subs[sub::LEFT_SLEEVE as usize].binary_search(&v).is_ok()
    };
    let (cord, band) = (p.cord, p.band);
    let half = 0.5 * (band - cord);
    let band_y = p.hem + band;
    // Height on the pattern above the hem -> height in the start and the layer (0 innermost).
    let map = |h: Real, y: Real| -> (Real, Real) {
        if h > band + 1e-6 {
            (y, 0.0)
        } else if h >= cord + half {
            (band_y - (band - h), 2.0)
        } else if h > cord {
            (band_y - (h - cord), 1.0)
        } else {
            (band_y - (cord - h), 0.0)
        }
    };
    let (side_left, source) = sides(p);
    let mut start = start;
    for v in 0..p.rest.len() as u32 {
        let r = p.rest[v as usize];
        let outward = if r.z < p.zc { -1.0 } else { 1.0 };
        let left = outward > 0.0 && side_left[v as usize];
        let extra = if left { 3.0 * LAYER } else { 0.0 };
        let q = &mut start[v as usize];
        if sleeve(v) {
            q.z += extra;
            continue;
        }
        let src = p.rest[source[v as usize] as usize];
        let (ys, layer) = map(src.y - p.hem, src.y);
        q.y = r.y + (ys - src.y);
        if src.y - p.hem <= band + 1e-6 {
            if (r.z - p.zc).abs() < 0.5 * crate::mesh::GAP {
                // A side seam, the tube's edge in the flat layout: outward is sideways.
                q.x += r.x.signum() * layer * LAYER;
            } else {
                q.z += outward * layer * LAYER + extra;
            }
        } else {
            q.z += extra;
        }
    }
    let band_rows = (0..p.rest.len() as u32)
        .filter(|&v| {
            let h = p.rest[v as usize].y - p.hem;
            (h - cord).abs() < 0.016 || (h - band).abs() < 0.016
        })
        .collect();
    Folded {
        start,
        band_rows,
        band_y,
    }
}
