//! One garment worn over another: [`place_over`] moves the outer garment's vertices out along the
//! body's normal until they clear the inner garment by a gap, the way a tailor's layer sits on
//! what is beneath it. Garments fitted one by one to the skin (MakeHuman's .mhclo offsets, or
//! two patterns with little ease between them) otherwise pass through each other.
//!
//! For each outer vertex, where the line along its body normal meets the inner garment's
//! triangles (within a few centimetres) tells how high the inner layer stands there; the vertex
//! must stand at least `gap` above the highest. The pushes are then spread over a few
//! rings of the outer mesh (each vertex takes at least a share of its neighbours' mean), so a
//! lone vertex is not pulled out into a spike.

use std::collections::HashMap;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Probe};

/// Passes spreading the pushes over the outer mesh's rings.
const SPREAD_PASSES: usize = 4;

/// Share of its neighbours' mean push a vertex takes in a spreading pass.
const SPREAD_SHARE: Real = 0.8;

/// What [`place_over`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LayerPlacement {
    /// Outer vertices moved, and the farthest move (m).
    pub moved: usize,
    pub farthest: Real,
}

/// The inner garment's triangles hashed by their boxes on a uniform grid of cell `cell`.
pub(crate) struct Hash {
    cell: Real,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl Hash {
    fn key(&self, p: &Vec3) -> [i64; 3] {
        [0, 1, 2].map(|k| (p[k] / self.cell).floor() as i64)
    }

    pub(crate) fn new(x: &[Vec3], tris: &[[u32; 3]], cell: Real) -> Hash {
        let mut h = Hash {
            cell,
            cells: HashMap::new(),
        };
        for (t, tri) in tris.iter().enumerate() {
            let c = tri.map(|v| x[v as usize]);
            let lo = h.key(&c[0].inf(&c[1]).inf(&c[2]));
            let hi = h.key(&c[0].sup(&c[1]).sup(&c[2]));
            for i in lo[0]..=hi[0] {
                for j in lo[1]..=hi[1] {
                    for k in lo[2]..=hi[2] {
                        h.cells.entry([i, j, k]).or_default().push(t as u32);
                    }
                }
            }
        }
        h
    }

    /// Triangles in the cells of the box spanning `a` and `b` (with repeats).
    pub(crate) fn near(&self, a: &Vec3, b: &Vec3, out: &mut Vec<u32>) {
        out.clear();
        let (lo, hi) = (self.key(&a.inf(b)), self.key(&a.sup(b)));
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    if let Some(c) = self.cells.get(&[x, y, z]) {
                        out.extend_from_slice(c);
                    }
                }
            }
        }
    }
}

/// Where the line `p + s n` meets triangle `c` (Moller-Trumbore): `s`, if it does.
pub(crate) fn ray_triangle(p: &Vec3, n: &Vec3, c: &[Vec3; 3]) -> Option<Real> {
    let (e1, e2) = (c[1] - c[0], c[2] - c[0]);
    let q = n.cross(&e2);
    let det = e1.dot(&q);
    if det.abs() < 1e-14 {
        return None;
    }
    let t = p - c[0];
    let u = t.dot(&q) / det;
    let r = t.cross(&e1);
    let v = n.dot(&r) / det;
    if u < 0.0 || v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some(e2.dot(&r) / det)
}

/// Least cosine between a vertex's body normal and the mean body normal of a triangle's corners
/// for the triangle to count as a layer over or under the vertex. A sleeve hanging by the hip
/// meets the skirt along its normal, but the skirt there faces the other way: it is beside the
/// sleeve, not under it.
const SAME_SIDE: Real = 0.5;

/// Whether the triangle `tri`, whose corners' body normals `probes` give, faces the same way
/// as the body normal `n`.
pub(crate) fn faces_with(n: &Vec3, tri: &[u32; 3], probes: &[Probe]) -> bool {
    let m: Vec3 = tri
        .iter()
        .filter_map(|&v| probes.get(v as usize))
        .map(|p| p.normal)
        .sum();
    n.dot(&m) > SAME_SIDE * m.norm()
}

/// How far each outer vertex must move out along `probes`' normals to stand `gap` above where
/// its normal line meets the inner garment (`inner`, `tris`, its vertices' body probes
/// `inner_probes`) within `depth` above or below it.
fn pushes(
    outer: &[Vec3],
    probes: &[Probe],
    (inner, tris, inner_probes): (&[Vec3], &[[u32; 3]], &[Probe]),
    (gap, cell, depth): (Real, Real, Real),
) -> Vec<Real> {
    let hash = Hash::new(inner, tris, cell.max(1e-3));
    let mut near = Vec::new();
    outer
        .iter()
        .zip(probes)
        .map(|(p, probe)| {
            let n = probe.normal;
            if !probe.distance.is_finite() || n == Vec3::zeros() {
                return 0.0;
            }
            hash.near(&(p - n * depth), &(p + n * depth), &mut near);
            let mut need: Real = 0.0;
            for &t in &near {
                let tri = tris[t as usize];
                if !faces_with(&n, &tri, inner_probes) {
                    continue;
                }
                let c = tri.map(|v| inner[v as usize]);
                if let Some(s) = ray_triangle(p, &n, &c).filter(|s| s.abs() < depth) {
                    need = need.max(s + gap);
                }
            }
            need
        })
        .collect()
}

/// Each vertex's push raised to a share of its neighbours' mean, `SPREAD_PASSES` times.
fn spread(mesh: &PolyMesh, push: &mut [Real]) {
    let (tris, _) = mesh.triangulate();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); push.len()];
    for t in &tris {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            neighbours[a as usize].push(b);
            neighbours[b as usize].push(a);
        }
    }
    for _ in 0..SPREAD_PASSES {
        let before = push.to_vec();
        for (v, nb) in neighbours.iter().enumerate() {
            if nb.is_empty() {
                continue;
            }
            let mean = nb.iter().map(|&u| before[u as usize]).sum::<Real>() / nb.len() as Real;
            push[v] = push[v].max(SPREAD_SHARE * mean);
        }
    }
}

/// Passes carrying pushes up through the outer garment's own layers.
const STACK_PASSES: usize = 3;

/// Raises the push of every outer triangle that stands over an outer vertex (on the vertex's
/// normal line, within `depth` above it, facing the same way) to at least that vertex's push: a
/// lapel over a jacket's front, a doubled hem, moves out as far as the layer under it, so
/// lifting a garment over another does not press its own layers into each other.
fn stack(
    (x, tris, probes): (&[Vec3], &[[u32; 3]], &[Probe]),
    push: &mut [Real],
    (cell, depth): (Real, Real),
) {
    let hash = Hash::new(x, tris, cell.max(1e-3));
    let mut near = Vec::new();
    for _ in 0..STACK_PASSES {
        let mut raised = false;
        for (v, (p, probe)) in x.iter().zip(probes).enumerate() {
            let n = probe.normal;
            if !(push[v] > 0.0) || n == Vec3::zeros() {
                continue;
            }
            hash.near(p, &(p + n * depth), &mut near);
            for &t in &near {
                let tri = tris[t as usize];
                if tri.contains(&(v as u32)) || !faces_with(&n, &tri, probes) {
                    continue;
                }
                let c = tri.map(|u| x[u as usize]);
                if ray_triangle(p, &n, &c).is_some_and(|s| s > 0.0 && s < depth) {
                    for u in tri {
                        if push[u as usize] < push[v] {
                            push[u as usize] = push[v];
                            raised = true;
                        }
                    }
                }
            }
        }
        if !raised {
            break;
        }
    }
}

/// Rounds of placement: each looks again at the shapes the last left.
const ROUNDS: usize = 3;

/// How far each outer triangle's corners must move out for the inner garment's vertices
/// (`inner`, with their body `probes`) to stand `gap` under it: where an inner vertex's normal
/// line meets an outer triangle (its corners' body probes `outer_probes`) less than `gap` above
/// it (or below it, within `depth`), the triangle's corners take the difference.
fn lifts(
    (outer, tris, outer_probes): (&[Vec3], &[[u32; 3]], &[Probe]),
    inner: &[Vec3],
    probes: &[Probe],
    (gap, cell, depth): (Real, Real, Real),
) -> Vec<Real> {
    let hash = Hash::new(outer, tris, cell.max(1e-3));
    let mut near = Vec::new();
    let mut need = vec![0.0; outer.len()];
    for (u, probe) in inner.iter().zip(probes) {
        let n = probe.normal;
        if !probe.distance.is_finite() || n == Vec3::zeros() {
            continue;
        }
        hash.near(&(u - n * depth), &(u + n * depth), &mut near);
        for &t in &near {
            let tri = tris[t as usize];
            if !faces_with(&n, &tri, outer_probes) {
                continue;
            }
            let c = tri.map(|v| outer[v as usize]);
            if let Some(s) = ray_triangle(u, &n, &c).filter(|s| s.abs() < depth && *s < gap) {
                for v in tri {
                    need[v as usize] = Real::max(need[v as usize], gap - s);
                }
            }
        }
    }
    need
}

/// Moves `outer`'s vertices out along the body's normal (`body`'s probes) until each stands at
/// least `gap` above the inner garment `inner` where its normal line meets it, and no inner
/// vertex stands within `gap` of the outer garment along its own normal (both within `depth`
/// above or below; `cell` sizes the hashes of triangles, about their edge). Pushes are spread
/// over a few rings of the outer mesh.
pub fn place_over(
    outer: &mut PolyMesh,
    inner: &PolyMesh,
    body: &mut dyn Collider,
    (gap, cell, depth): (Real, Real, Real),
) -> LayerPlacement {
    let all: Vec<u32> = (0..outer.positions.len() as u32).collect();
    let under: Vec<u32> = (0..inner.positions.len() as u32).collect();
    let (mut probes, mut inner_probes) = (Vec::new(), Vec::new());
    body.probe(&inner.positions, &under, &mut inner_probes);
    let (inner_tris, _) = inner.triangulate();
    let (outer_tris, _) = outer.triangulate();
    let start = outer.positions.clone();
    for _ in 0..ROUNDS {
        body.probe(&outer.positions, &all, &mut probes);
        let sizes = (gap, cell, depth);
        let inner_mesh = (
            inner.positions.as_slice(),
            inner_tris.as_slice(),
            inner_probes.as_slice(),
        );
        let mut push = pushes(&outer.positions, &probes, inner_mesh, sizes);
        let outer_mesh = (
            outer.positions.as_slice(),
            outer_tris.as_slice(),
            probes.as_slice(),
        );
        let lift = lifts(outer_mesh, &inner.positions, &inner_probes, sizes);
        for (p, l) in push.iter_mut().zip(&lift) {
            *p = p.max(*l);
        }
        spread(outer, &mut push);
        stack(outer_mesh, &mut push, (cell, depth));
        let mut moved = false;
        for ((p, probe), s) in outer.positions.iter_mut().zip(&probes).zip(&push) {
            if *s > 0.0 && s.is_finite() {
                *p += probe.normal * *s;
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    let mut report = LayerPlacement::default();
    for (p, s) in outer.positions.iter().zip(&start) {
        let d = (p - s).norm();
        if d > 0.0 {
            report.moved += 1;
            report.farthest = report.farthest.max(d);
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Floor;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn an_outer_sheet_is_lifted_over_a_bump_of_the_inner_one() {
        // Inner: a sheet at 1 cm with a bump to 3 cm in the middle; outer: flat at 2 cm.
        let mut inner = grid_xz(10, 10, 0.2, 0.2, 0.01);
        for p in &mut inner.positions {
            if p.x.abs() < 0.03 && p.z.abs() < 0.03 {
                p.y = 0.03;
            }
        }
        let mut outer = grid_xz(13, 13, 0.2, 0.2, 0.02);
        let gap = 0.002;
        let r = place_over(&mut outer, &inner, &mut Floor, (gap, 0.02, 0.1));
        assert!(
            r.moved > 0 && r.farthest > 0.011 && r.farthest < 0.02,
            "{r:?}"
        );
        // Every outer vertex over the bump stands a gap above it; far from it, on the flat
        // part, the outer sheet stays within 0.5 mm of where it was (1 cm over the inner).
        for p in &outer.positions {
            if p.x.abs() < 0.02 && p.z.abs() < 0.02 {
                assert!(p.y >= 0.03 + gap - 1e-12, "{p:?}");
            }
            if p.x.abs() > 0.08 && p.z.abs() > 0.08 {
                assert!((p.y - 0.02).abs() < 5e-4, "{p:?}");
            }
        }
    }

    #[test]
    fn an_outer_sheet_already_clear_is_left_alone() {
        let inner = grid_xz(8, 8, 0.2, 0.2, 0.01);
        let mut outer = grid_xz(9, 9, 0.2, 0.2, 0.02);
        let before = outer.positions.clone();
        let r = place_over(&mut outer, &inner, &mut Floor, (0.002, 0.02, 0.1));
        assert_eq!(r, LayerPlacement::default());
        assert_eq!(outer.positions, before);
    }

    #[test]
    fn an_outer_sheet_under_the_inner_comes_out_over_it() {
        let inner = grid_xz(8, 8, 0.2, 0.2, 0.02);
        let mut outer = grid_xz(11, 11, 0.2, 0.2, 0.01);
        place_over(&mut outer, &inner, &mut Floor, (0.002, 0.02, 0.1));
        assert!(outer.positions.iter().all(|p| p.y >= 0.022 - 1e-12));
    }

    #[test]
    fn a_flap_of_the_outer_garment_stays_over_the_layer_it_covers() {
        // The outer garment: a sheet at 1.2 cm with a flap of its own 4 mm over its middle. The
        // inner sheet at 1 cm makes the outer sheet rise to 1.6 cm (gap 6 mm), as high as the
        // flap: the flap must rise with it.
        let inner = grid_xz(10, 10, 0.2, 0.2, 0.01);
        let mut outer = grid_xz(10, 10, 0.2, 0.2, 0.012);
        let base = outer.positions.len() as u32;
        let flap = grid_xz(4, 4, 0.08, 0.08, 0.016);
        outer.positions.extend_from_slice(&flap.positions);
        outer.faces.extend(flap.faces.iter().map(|f| match f {
            tryon_core::mesh::Face::Tri(t) => tryon_core::mesh::Face::Tri(t.map(|v| v + base)),
            tryon_core::mesh::Face::Quad(q) => tryon_core::mesh::Face::Quad(q.map(|v| v + base)),
        }));
        place_over(&mut outer, &inner, &mut Floor, (0.006, 0.02, 0.05));
        let sheet = &outer.positions[..base as usize];
        for f in &outer.positions[base as usize..] {
            let under = sheet
                .iter()
                .min_by(|a, b| {
                    let d = |p: &Vec3| (p.x - f.x).hypot(p.z - f.z);
                    d(a).total_cmp(&d(b))
                })
                .unwrap();
            assert!(f.y - under.y >= 0.004 - 1e-9, "flap {f:?} over {under:?}");
        }
    }
}
