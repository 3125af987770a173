//! One garment's separate pieces worn over each other. MakeHuman garments are often modelled as
//! several unsewn pieces: the elegant suit's jacket hangs over its skirt's waistband, the casual
//! suit's shorts carry a small patch on the front of the waist. As modelled they pass through
//! each other (95 crossing triangle pairs on the elegant suit, 30 on the casual suit), and a
//! tangle at the start of a simulation stays and spreads. [`place_pieces`] tells which piece
//! lies over which and lifts each over those beneath it with [`place_over`], as for garments.
//!
//! Which lies over which: the pieces vote. Each vertex's line along its body normal meets the
//! other piece (the nearest meeting, within `depth`, where the other faces the same way) above
//! or below it. On the casual suit the waist patch lies over the shorts (91 votes to 13) and
//! under the T-shirt's hem (17 to 0); the jacket over the elegant suit's skirt (226 to 5).
//!
//! A piece with fewer than `small_share` of the vertices of each piece it lies over (a patch, a
//! button) is lifted whole, keeping its shape.

use crate::attach::components;
use crate::layer::{Hash, LayerPlacement, faces_with, place_over, ray_triangle};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::stages::{Collider, Probe};

/// One piece as its own mesh, with its vertices' numbers in the whole.
struct Piece {
    verts: Vec<u32>,
    mesh: PolyMesh,
}

/// The pieces of `mesh` (`comp`: each vertex's piece) as meshes.
fn split(mesh: &PolyMesh, comp: &[usize], count: usize) -> Vec<Piece> {
    let mut local = vec![0u32; comp.len()];
    let mut pieces: Vec<Piece> = (0..count)
        .map(|_| Piece {
            verts: Vec::new(),
            mesh: PolyMesh::default(),
        })
        .collect();
    for (v, &c) in comp.iter().enumerate() {
        local[v] = pieces[c].verts.len() as u32;
        pieces[c].verts.push(v as u32);
        pieces[c].mesh.positions.push(mesh.positions[v]);
    }
    for f in &mesh.faces {
        let c = comp[f.vertices()[0] as usize];
        pieces[c].mesh.faces.push(match f {
            Face::Tri(t) => Face::Tri(t.map(|v| local[v as usize])),
            Face::Quad(q) => Face::Quad(q.map(|v| local[v as usize])),
        });
    }
    pieces
}

/// Of `a`'s vertices (`probes`: their body probes), how many meet `b` nearest below them, and
/// how many above (`b_probes`: `b`'s vertices' probes).
fn votes(
    a: &PolyMesh,
    probes: &[Probe],
    (b, b_probes): (&PolyMesh, &[Probe]),
    (cell, depth): (Real, Real),
) -> (usize, usize) {
    let (tris, _) = b.triangulate();
    let hash = Hash::new(&b.positions, &tris, cell.max(1e-3));
    let (mut below, mut above) = (0, 0);
    let mut near = Vec::new();
    for (p, probe) in a.positions.iter().zip(probes) {
        let n = probe.normal;
        if !probe.distance.is_finite() || n == tryon_core::math::Vec3::zeros() {
            continue;
        }
        hash.near(&(p - n * depth), &(p + n * depth), &mut near);
        let nearest = near
            .iter()
            .filter(|&&t| faces_with(&n, &tris[t as usize], b_probes))
            .filter_map(|&t| {
                let c = tris[t as usize].map(|v| b.positions[v as usize]);
                ray_triangle(p, &n, &c).filter(|s| s.abs() < depth)
            })
            .min_by(|s, t| s.abs().total_cmp(&t.abs()));
        match nearest {
            Some(s) if s < 0.0 => below += 1,
            Some(_) => above += 1,
            None => {}
        }
    }
    (below, above)
}

/// Rounds of lifting a small piece whole.
const RIGID_ROUNDS: usize = 4;

/// Lifts the small piece `piece` whole over `inner` (a patch keeps its shape; moved vertex by
/// vertex, its few millimetre triangles would fold into each other): each round moves it along
/// its mean body normal by the farthest [`place_over`] would move one of its vertices.
fn lift_whole(
    piece: &mut PolyMesh,
    inner: &PolyMesh,
    body: &mut dyn Collider,
    sizes: (Real, Real, Real),
) -> LayerPlacement {
    let start = piece.positions.clone();
    let all: Vec<u32> = (0..start.len() as u32).collect();
    let mut probes = Vec::new();
    for _ in 0..RIGID_ROUNDS {
        let mut trial = piece.clone();
        let r = place_over(&mut trial, inner, body, sizes);
        if r.moved == 0 {
            break;
        }
        body.probe(&piece.positions, &all, &mut probes);
        let n: Vec3 = probes.iter().map(|p| p.normal).sum();
        let Some(n) = n.try_normalize(1e-12) else {
            break;
        };
        // Along the mean normal a vertex rises less than along its own: take what the most
        // tilted vertex needs (at most twice the push).
        let tilt = probes
            .iter()
            .map(|p| p.normal.dot(&n))
            .fold(1.0, Real::min)
            .max(0.5);
        for p in &mut piece.positions {
            *p += n * (r.farthest / tilt);
        }
    }
    let farthest = piece
        .positions
        .iter()
        .zip(&start)
        .map(|(p, s)| (p - s).norm())
        .fold(0.0, Real::max);
    LayerPlacement {
        moved: if farthest > 0.0 { start.len() } else { 0 },
        farthest,
    }
}

/// Whether piece `a` is small against piece `b` (fewer than `small` of its vertices).
fn smaller(pieces: &[Piece], a: usize, b: usize, small: Real) -> bool {
    (pieces[a].verts.len() as Real) < small * pieces[b].verts.len() as Real
}

/// `over[a][b]`: piece `a` lies over piece `b` where they overlap.
fn layering(pieces: &[Piece], probes: &[Vec<Probe>], sizes: (Real, Real)) -> Vec<Vec<bool>> {
    let k = pieces.len();
    let mut v = vec![vec![(0, 0); k]; k];
    for a in 0..k {
        for b in (0..k).filter(|&b| b != a) {
            let other = (&pieces[b].mesh, probes[b].as_slice());
            v[a][b] = votes(&pieces[a].mesh, &probes[a], other, sizes);
        }
    }
    let mut over = vec![vec![false; k]; k];
    for a in 0..k {
        for b in (0..k).filter(|&b| b != a) {
            let (a_over, b_over) = (v[a][b].0 + v[b][a].1, v[b][a].0 + v[a][b].1);
            if a_over + b_over == 0 {
                continue;
            }
            over[a][b] = a_over > b_over || (a_over == b_over && a > b);
        }
    }
    over
}

/// Lifts each piece of `mesh` over the pieces it lies over (see the module's text) so it stands
/// `gap` above them (`body` gives the normals; `cell` and `depth` as for [`place_over`]). Pieces
/// with under `small_share` of the vertices of those beneath them are lifted whole. Returns what
/// it moved.
pub fn place_pieces(
    mesh: &mut PolyMesh,
    body: &mut dyn Collider,
    (gap, cell, depth): (Real, Real, Real),
    small_share: Real,
) -> LayerPlacement {
    let comp = components(mesh);
    let count = comp.iter().copied().max().map_or(0, |m| m + 1);
    if count < 2 {
        return LayerPlacement::default();
    }
    let mut pieces = split(mesh, &comp, count);
    let probes: Vec<Vec<Probe>> = pieces
        .iter()
        .map(|p| {
            let all: Vec<u32> = (0..p.verts.len() as u32).collect();
            let mut out = Vec::new();
            body.probe(&p.mesh.positions, &all, &mut out);
            out
        })
        .collect();
    let over = layering(&pieces, &probes, (cell, depth));
    // Innermost first: a piece ranks by how many pieces it lies over.
    let mut order: Vec<usize> = (0..count).collect();
    order.sort_by_key(|&a| (over[a].iter().filter(|&&o| o).count(), a));
    let mut report = LayerPlacement::default();
    for (rank, &a) in order.iter().enumerate() {
        let under: Vec<usize> = order[..rank]
            .iter()
            .copied()
            .filter(|&b| over[a][b])
            .collect();
        if under.is_empty() {
            continue;
        }
        let mut inner = PolyMesh::default();
        for &b in &under {
            let base = inner.positions.len() as u32;
            inner.positions.extend_from_slice(&pieces[b].mesh.positions);
            inner
                .faces
                .extend(pieces[b].mesh.faces.iter().map(|f| match f {
                    Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
                    Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
                }));
        }
        let sizes = (gap, cell, depth);
        let r = if under.iter().all(|&b| smaller(&pieces, a, b, small_share)) {
            lift_whole(&mut pieces[a].mesh, &inner, body, sizes)
        } else {
            place_over(&mut pieces[a].mesh, &inner, body, sizes)
        };
        report.moved += r.moved;
        report.farthest = report.farthest.max(r.farthest);
        for (l, &v) in pieces[a].verts.iter().enumerate() {
            mesh.positions[v as usize] = pieces[a].mesh.positions[l];
        }
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::Floor;
    use tryon_core::mesh::grid_xz;

    /// `b`'s vertices and faces appended to `a`.
    fn with(mut a: PolyMesh, b: &PolyMesh) -> PolyMesh {
        let base = a.positions.len() as u32;
        a.positions.extend_from_slice(&b.positions);
        a.faces.extend(b.faces.iter().map(|f| match f {
            Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
            Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
        }));
        a
    }

    const GAP: Real = 0.002;

    #[test]
    fn a_piece_dipping_through_the_one_beneath_comes_out_over_it() {
        // Beneath: a sheet at 1 cm. Over it: a sheet at 2 cm whose middle dips to 0.5 cm,
        // through the one beneath. Listed outer first, so the order is the votes', not the list's.
        let inner = grid_xz(10, 10, 0.2, 0.2, 0.01);
        let mut outer = grid_xz(10, 10, 0.2, 0.2, 0.02);
        for p in &mut outer.positions {
            if p.x.abs() < 0.03 && p.z.abs() < 0.03 {
                p.y = 0.005;
            }
        }
        let mut mesh = with(outer, &inner);
        let n = mesh.positions.len() / 2;
        let r = place_pieces(&mut mesh, &mut Floor, (GAP, 0.02, 0.05), 0.1);
        assert!(r.moved > 0, "{r:?}");
        for (v, p) in mesh.positions.iter().enumerate() {
            if v < n {
                assert!(p.y >= 0.01 + GAP - 1e-9, "outer vertex {v} at {p:?}");
            } else {
                assert_eq!(p.y, 0.01, "the piece beneath stays");
            }
        }
    }

    #[test]
    fn a_small_patch_through_its_host_is_lifted_whole() {
        let host = grid_xz(20, 20, 0.2, 0.2, 0.01);
        // A 3 cm patch over the host, tilted so one edge passes 3 mm under it.
        let mut patch = grid_xz(3, 3, 0.03, 0.03, 0.0);
        for p in &mut patch.positions {
            p.y = 0.012 - 0.1 * (p.x + 0.015);
        }
        let mut mesh = with(host, &patch);
        let n = mesh.positions.len() - patch.positions.len();
        let before = mesh.positions.clone();
        let r = place_pieces(&mut mesh, &mut Floor, (GAP, 0.02, 0.05), 0.1);
        assert_eq!(r.moved, patch.positions.len(), "{r:?}");
        assert_eq!(&mesh.positions[..n], &before[..n], "the host stays");
        let shift = mesh.positions[n] - before[n];
        for v in n..mesh.positions.len() {
            assert!(mesh.positions[v].y >= 0.01 + GAP - 1e-9);
            assert!(
                (mesh.positions[v] - before[v] - shift).norm() < 1e-12,
                "kept its shape"
            );
        }
    }

    #[test]
    fn pieces_side_by_side_stay_where_they_are() {
        // Two sheets at one height, not overlapping: neither lies over the other.
        let a = grid_xz(4, 4, 0.1, 0.1, 0.01);
        let mut b = grid_xz(4, 4, 0.1, 0.1, 0.01);
        for p in &mut b.positions {
            p.x += 0.2;
        }
        let mut mesh = with(a, &b);
        let before = mesh.positions.clone();
        let r = place_pieces(&mut mesh, &mut Floor, (GAP, 0.02, 0.05), 0.1);
        assert_eq!(r, LayerPlacement::default());
        assert_eq!(mesh.positions, before);
    }
}
