//! Straight grid lines of a quad mesh and the long-range strain constraints built along them.
//!
//! Gauss-Seidel strain limiting moves a correction one spring per pass, so a hanging chain of L
//! springs needs a number of passes growing with L. Constraints between vertices 2, 4, 8, 16, ...
//! steps apart along the mesh's straight lines (rest = the rest length of the path between them, so a
//! constraint never asks for more than its springs allow) carry corrections across the chain in a few
//! passes, as the coarse levels of a multigrid cycle do. They are stretch-only and split corrections
//! by inverse mass, so they keep momentum like every other spring. Triangle regions and irregular
//! vertices (valence other than 4) simply end the lines.

use std::collections::HashMap;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::topology::{NO_FACE, Topology};

/// For a directed edge (p, v), the vertex q continuing the straight line p-v-q through v.
pub fn continuations(mesh: &PolyMesh, topo: &Topology) -> HashMap<(u32, u32), u32> {
    let mut next = HashMap::new();
    // Along the boundary: a vertex with two boundary edges and one interior edge continues the
    // boundary line (corners, with no interior edge, end it).
    let mut boundary_nbrs: Vec<Vec<u32>> = vec![Vec::new(); mesh.positions.len()];
    for &e in &topo.boundary_edges {
        let [a, b] = topo.edges[e as usize];
        boundary_nbrs[a as usize].push(b);
        boundary_nbrs[b as usize].push(a);
    }
    for (v, nb) in boundary_nbrs.iter().enumerate() {
        if let [p, q] = nb[..]
            && topo.vertex_ring.row(v).len() == 3
        {
            next.insert((p, v as u32), q);
            next.insert((q, v as u32), p);
        }
    }
    for (e, &[a, b]) in topo.edges.iter().enumerate() {
        let [f, g] = topo.edge_faces[e];
        if g == NO_FACE {
            continue;
        }
        let (Face::Quad(fq), Face::Quad(gq)) = (mesh.faces[f as usize], mesh.faces[g as usize])
        else {
            continue;
        };
        for (v, other) in [(a, b), (b, a)] {
            if topo.vertex_ring.row(v as usize).len() != 4
                || topo.vertex_faces.row(v as usize).len() != 4
            {
                continue;
            }
            let (Some(p), Some(q)) = (side(&fq, v, other), side(&gq, v, other)) else {
                continue;
            };
            if p != q {
                next.insert((p, v), q);
                next.insert((q, v), p);
            }
        }
    }
    next
}

/// The neighbour of `v` in quad `face` that is not `other`.
fn side(face: &[u32; 4], v: u32, other: u32) -> Option<u32> {
    let k = face.iter().position(|&x| x == v)?;
    let (prev, next) = (face[(k + 3) % 4], face[(k + 1) % 4]);
    Some(if prev == other { next } else { prev })
}

/// Pairs (i, j, rest) of vertices `s` steps apart along straight lines, for each `s` in `scales`
/// (given coarse first; the output keeps that order), rest being the path's rest length.
pub fn long_range_pairs(
    mesh: &PolyMesh,
    topo: &Topology,
    scales: &[usize],
) -> Vec<(u32, u32, Real)> {
    let next = continuations(mesh, topo);
    let max = scales.iter().copied().max().unwrap_or(0);
    let len = |a: u32, b: u32| -> Real {
        (mesh.positions[a as usize] - mesh.positions[b as usize]).norm()
    };
    let mut by_scale: Vec<Vec<(u32, u32, Real)>> = vec![Vec::new(); scales.len()];
    let mut seen = std::collections::HashSet::new();
    let mut path: Vec<u32> = Vec::with_capacity(max + 1);
    for &[a, b] in &topo.edges {
        for (v, w) in [(a, b), (b, a)] {
            path.clear();
            path.extend([v, w]);
            let mut rest = len(v, w);
            let mut rests = vec![0.0, rest];
            while path.len() <= max {
                let n = path.len();
                let Some(&c) = next.get(&(path[n - 2], path[n - 1])) else {
                    break;
                };
                if path.contains(&c) {
                    break;
                }
                rest += len(path[n - 1], c);
                path.push(c);
                rests.push(rest);
            }
            for (k, &s) in scales.iter().enumerate() {
                if s >= 2 && s < path.len() {
                    let (i, j) = (path[0].min(path[s]), path[0].max(path[s]));
                    if seen.insert((i, j, s)) {
                        by_scale[k].push((i, j, rests[s]));
                    }
                }
            }
        }
    }
    by_scale.into_iter().flatten().collect()
}

/// Powers of two from 2 up to the longest straight line a mesh of `n` vertices could hold, coarse first.
pub fn default_scales(n: usize) -> Vec<usize> {
    let side = (n as Real).sqrt().ceil() as usize;
    let mut s = Vec::new();
    let mut k = 2;
    while k < side {
        s.push(k);
        k *= 2;
    }
    s.reverse();
    s
}

/// Largest ratio of current distance to rest over the pairs (1 when there are none).
pub fn worst_ratio(pairs: &[(u32, u32, Real)], x: &[Vec3]) -> Real {
    pairs
        .iter()
        .map(|&(i, j, r)| (x[i as usize] - x[j as usize]).norm() / r)
        .fold(1.0, Real::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn grid_lines_give_straight_long_range_pairs() {
        let m = grid_xz(8, 8, 1.0, 1.0, 0.0);
        let t = Topology::build(&m).unwrap();
        let pairs = long_range_pairs(&m, &t, &[4, 2]);
        // Along each of the 9 rows and 9 columns of 9 vertices: 5 pairs 4 apart and 7 pairs 2 apart.
        assert_eq!(pairs.len(), 18 * (5 + 7));
        for &(i, j, r) in &pairs {
            let d = (m.positions[i as usize] - m.positions[j as usize]).norm();
            assert!(
                (d - r).abs() < 1e-12,
                "pair ({i}, {j}) is not straight: {d} vs path {r}"
            );
        }
        assert!((worst_ratio(&pairs, &m.positions) - 1.0).abs() < 1e-12);
        assert_eq!(default_scales(4096), vec![32, 16, 8, 4, 2]);
    }

    #[test]
    fn triangles_end_the_lines() {
        let m = tryon_core::shapes::icosphere(1.0, 1, Vec3::zeros());
        let t = Topology::build(&m).unwrap();
        assert!(long_range_pairs(&m, &t, &[4, 2]).is_empty());
    }
}
