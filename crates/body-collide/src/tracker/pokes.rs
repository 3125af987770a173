//! Body vertices under cloth triangles ([`Collider::pokes`]): the body's features narrower than
//! the cloth's triangles (a nipple, a shoulder's tip) that poke through between particles which
//! are all outside. For each cloth triangle, a walk over the body's vertex rings from the tracked
//! nearest vertices of its corners, through vertices within the triangle's reach, collects those
//! whose projection along the triangle's normal falls inside it.

use super::NearestVertexCollider;
use crate::body::BodyMesh;
use rayon::prelude::*;
use tryon_core::math::{Real, Vec3};
use tryon_core::stages::Poke;

/// Most body vertices one triangle's walk visits: a 2 cm cloth triangle covers about 3 cm^2 of a
/// MakeHuman body (0.7 vertices per cm^2); the walk stops short on a much finer body.
const MAX_VISITS: usize = 96;

/// Least |cos| between a body vertex's normal and the triangle's for the vertex to count as under
/// it (a vertex of a limb seen edge-on is not).
const FACING: Real = 0.5;

impl NearestVertexCollider {
    /// [`Collider::pokes`] over the points' tracked nearest vertices (`probe_nearest`, kept by
    /// [`Collider::probe`]); nothing for points never probed.
    pub(super) fn find_pokes(
        &self,
        points: &[Vec3],
        triangles: &[[u32; 3]],
        which: &[u32],
        limits: (Real, Real),
        out: &mut Vec<Poke>,
    ) {
        out.clear();
        if self.probe_nearest.len() != points.len() {
            return;
        }
        let cloth = (points, triangles, which);
        pokes_from(&self.body, &self.probe_nearest, cloth, limits, out);
    }
}

/// [`Collider::pokes`] by a walk over `body`'s vertex rings from `nearest[k]`, a body vertex near
/// each point `k` (`u32::MAX` for none: the walk starts from the other corners), in parallel,
/// written in the order of `which`.
pub(crate) fn pokes_from(
    body: &BodyMesh,
    nearest: &[u32],
    (points, triangles, which): (&[Vec3], &[[u32; 3]], &[u32]),
    limits: (Real, Real),
    out: &mut Vec<Poke>,
) {
    out.clear();
    let n = body.positions.len();
    let found: Vec<Poke> = which
        .par_iter()
        .with_min_len(64)
        .map_init(
            || Seen::new(n),
            |seen, &t| {
                let Some(tri) = triangles.get(t as usize) else {
                    return Vec::new();
                };
                under_triangle(body, nearest, points, (t, *tri), limits, seen)
            },
        )
        .flat_map_iter(|found| found)
        .collect();
    out.extend(found);
}

/// Which body vertices one walk has visited: a stamp per vertex, so a walk costs what it visits,
/// and the walk's queue, kept between walks so that none allocates.
struct Seen {
    stamp: Vec<u32>,
    now: u32,
    queue: Vec<u32>,
}

impl Seen {
    fn new(n: usize) -> Self {
        Seen {
            stamp: vec![0; n],
            now: 0,
            queue: Vec::with_capacity(MAX_VISITS + 16),
        }
    }

    /// Starts a new walk.
    fn clear(&mut self) {
        self.queue.clear();
        self.now = self.now.wrapping_add(1);
        if self.now == 0 {
            self.stamp.fill(0);
            self.now = 1;
        }
    }

    /// Marks `v`; whether it was new to this walk.
    fn insert(&mut self, v: u32) -> bool {
        let s = &mut self.stamp[v as usize];
        let new = *s != self.now;
        *s = self.now;
        new
    }
}

/// The body vertices under triangle `t` (corners `tri` of `points`).
fn under_triangle(
    body: &BodyMesh,
    nearest: &[u32],
    points: &[Vec3],
    (t, tri): (u32, [u32; 3]),
    (reach, depth): (Real, Real),
    seen: &mut Seen,
) -> Vec<Poke> {
    let mut out = Vec::new();
    if tri.iter().any(|&k| k as usize >= points.len()) {
        return out;
    }
    let c = tri.map(|k| points[k as usize]);
    let normal = (c[1] - c[0]).cross(&(c[2] - c[0]));
    let area2 = normal.norm();
    if !(area2 > 1e-14) {
        return out;
    }
    let nt = normal / area2;
    let centre = (c[0] + c[1] + c[2]) / 3.0;
    let spread = c.iter().map(|p| (p - centre).norm()).fold(0.0, Real::max);
    let radius = spread + reach + depth;
    // A vertex under the triangle projects inside it, so within `spread` of the centre across the
    // normal, and lies at most `max(reach, depth) / FACING` from its plane along it (`poke_at`'s
    // limits hold along the vertex's normal, at least FACING to the triangle's).
    let (across2, along) = (spread * spread, reach.max(depth) / FACING);
    seen.clear();
    for &k in &tri {
        let v = nearest.get(k as usize).copied().unwrap_or(u32::MAX);
        if (v as usize) < body.positions.len() && seen.insert(v) {
            seen.queue.push(v);
        }
    }
    let mut next = 0;
    while next < seen.queue.len() && seen.queue.len() < MAX_VISITS {
        let v = seen.queue[next];
        next += 1;
        let p = body.positions[v as usize];
        let d = p - centre;
        let d2 = d.norm_squared();
        if d2 > radius * radius {
            continue;
        }
        let h = nt.dot(&d);
        let under = h.abs() <= along * (1.0 + 1e-9) && d2 - h * h <= across2 * (1.0 + 1e-9) + 1e-18;
        if under && let Some(poke) = poke_at(body, v, p, &c, nt, area2, (reach, depth)) {
            out.push(Poke {
                triangle: t,
                ..poke
            });
        }
        for &w in body.ring.row(v as usize) {
            if seen.insert(w) {
                seen.queue.push(w);
            }
        }
    }
    out
}

/// Vertex `v` at `p` as a poke of the triangle with corners `c`, unit normal `nt` and twice the
/// area `area2`, when it lies under the triangle within the limits.
fn poke_at(
    body: &BodyMesh,
    v: u32,
    p: Vec3,
    c: &[Vec3],
    nt: Vec3,
    area2: Real,
    (reach, depth): (Real, Real),
) -> Option<Poke> {
    let n = body.vertex_normal(v);
    let cos = n.dot(&nt);
    if cos.abs() < FACING {
        return None;
    }
    // The projection along the triangle's normal, and its barycentric coordinates.
    let q = p + nt * nt.dot(&(c[0] - p));
    let w = |a: Vec3, b: Vec3| (b - a).cross(&(q - a)).dot(&nt) / area2;
    let bary = [w(c[1], c[2]), w(c[2], c[0]), w(c[0], c[1])];
    if bary.iter().any(|&b| b < 0.0) {
        return None;
    }
    let s = n.dot(&(q - p));
    (s >= -depth && s < reach).then_some(Poke {
        triangle: 0,
        bary,
        point: p,
        normal: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::{Face, PolyMesh};
    use tryon_core::stages::{Collider, Probe};

    /// A flat square body (a grid in the y = 0 plane, normals +y) with one vertex raised by
    /// `bump` at its middle.
    fn bumpy(bump: Real) -> PolyMesh {
        let n = 8;
        let mut pos = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let y = if i == n / 2 && j == n / 2 { bump } else { 0.0 };
                pos.push(Vec3::new(i as Real * 0.01, y, j as Real * 0.01));
            }
        }
        let mut faces = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let a = (i * (n + 1) + j) as u32;
                let (b, c, d) = (a + 1, a + n as u32 + 2, a + n as u32 + 1);
                faces.push(Face::Tri([a, b, c]));
                faces.push(Face::Tri([a, c, d]));
            }
        }
        // Close nothing: an open sheet is enough for the walk.
        PolyMesh {
            positions: pos,
            faces,
        }
    }

    #[test]
    fn a_bump_under_a_cloth_triangle_is_found_with_its_height_and_place() {
        let mut col = NearestVertexCollider::new(&bumpy(0.004), 0.002).unwrap();
        // One cloth triangle 3 mm over the sheet around the bump at (0.04, 0.04).
        let cloth = vec![
            Vec3::new(0.02, 0.003, 0.02),
            Vec3::new(0.07, 0.003, 0.03),
            Vec3::new(0.03, 0.003, 0.07),
        ];
        let mut probes: Vec<Probe> = Vec::new();
        col.probe(&cloth, &[0, 1, 2], &mut probes);
        let mut out = Vec::new();
        col.pokes(&cloth, &[[0, 1, 2]], &[0], (0.002, 0.01), &mut out);
        // Only the bump is nearer than 2 mm (the flat vertices are 3 mm under the cloth); the
        // cloth is 1 mm below its tip.
        assert_eq!(out.len(), 1, "{out:?}");
        let p = out[0];
        assert!((p.point - Vec3::new(0.04, 0.004, 0.04)).norm() < 1e-12);
        let q: Vec3 = (0..3).map(|k| cloth[k] * p.bary[k]).sum();
        assert!((q - Vec3::new(0.04, 0.003, 0.04)).norm() < 1e-9, "{q}");
        // A farther reach also finds the flat vertices under the triangle.
        col.pokes(&cloth, &[[0, 1, 2]], &[0], (0.0035, 0.01), &mut out);
        assert!(out.len() > 5, "{}", out.len());
        // Outside the triangle's shadow nothing is found.
        let far = vec![
            Vec3::new(0.0, 0.003, 0.0),
            Vec3::new(0.02, 0.003, 0.0),
            Vec3::new(0.0, 0.003, 0.02),
        ];
        col.probe(&far, &[0, 1, 2], &mut probes);
        col.pokes(&far, &[[0, 1, 2]], &[0], (0.002, 0.01), &mut out);
        assert!(out.is_empty(), "{out:?}");
    }
}
