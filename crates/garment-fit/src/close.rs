//! Closures a modeller left as coincident borders: a jacket's front edges that overlap where it is
//! buttoned, a skirt's slit held shut, panels modelled touching but not joined. A renderer shows
//! them closed; a simulated cloth would fall open at the first movement (the elegant suit's jacket
//! did, baring the torso by frame 25 of a walk). Pairs of border vertices that lie within a gap of
//! each other, far apart on the mesh, and each the other's nearest such vertex, are welded into one
//! vertex. Only runs of at least two pairs along both borders are kept, so that every closure is a
//! seam of shared edges and no vertex joins two fans at a single point.

use crate::weld::{Welded, merge};
use std::collections::{HashSet, VecDeque};
use tryon_core::math::Real;
use tryon_core::mesh::{MeshError, PolyMesh};
use tryon_core::topology::{Topology, TopologyError};

/// Why closures could not be found or welded.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum CloseError {
    #[error(transparent)]
    Topology(#[from] TopologyError),
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

/// The gap, as a fraction of the median edge, under which a modelled garment's border vertices are
/// taken as closed unless a scene says otherwise. The elegant suit's buttoned front lies 0.31 to
/// 0.58 median edges apart; the next border vertices across its neck opening lie 0.95 apart.
pub const MODELLED_CLOSURE_GAP: Real = 0.6;

/// Border vertices within `max_gap` of each other are not joined if a path of `min_hops` edges or
/// fewer already connects them (they are neighbours on the same border, not two sides of an
/// opening).
pub const MIN_HOPS: u32 = 4;

/// The closed garment and the number of vertex pairs welded.
pub fn close_openings(mesh: &PolyMesh, max_gap: Real) -> Result<(Welded, usize), CloseError> {
    let topo = Topology::build(mesh)?;
    let n = mesh.positions.len();
    let mut border_next: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &e in &topo.boundary_edges {
        let [a, b] = topo.edges[e as usize];
        border_next[a as usize].push(b);
        border_next[b as usize].push(a);
    }
    let border: Vec<u32> = (0..n as u32)
        .filter(|&v| !border_next[v as usize].is_empty())
        .collect();
    let x = &mesh.positions;
    // Each border vertex's nearest border vertex within the gap that is far on the mesh.
    let nearest: Vec<Option<u32>> = (0..n)
        .map(|i| {
            if border_next[i].is_empty() {
                return None;
            }
            let near = within_hops(&topo, i as u32, MIN_HOPS);
            border
                .iter()
                .copied()
                .filter(|&j| j as usize != i && !near.contains(&j))
                .map(|j| ((x[i] - x[j as usize]).norm(), j))
                .filter(|(d, _)| *d < max_gap)
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, j)| j)
        })
        .collect();
    let mutual = |i: u32| nearest[i as usize].filter(|&j| nearest[j as usize] == Some(i));
    // Keep a pair when a border neighbour of each end is paired with a border neighbour of the
    // other: the pair continues a seam.
    let mut parent: Vec<usize> = (0..n).collect();
    let mut pairs = 0;
    for &i in &border {
        let Some(j) = mutual(i) else { continue };
        if j < i {
            continue;
        }
        let continues = border_next[i as usize]
            .iter()
            .any(|&a| mutual(a).is_some_and(|b| border_next[j as usize].contains(&b)));
        if continues {
            let (ri, rj) = (
                crate::find_root(&mut parent, i as usize),
                crate::find_root(&mut parent, j as usize),
            );
            parent[ri.max(rj)] = ri.min(rj);
            pairs += 1;
        }
    }
    if pairs == 0 {
        return Ok((
            Welded {
                mesh: mesh.clone(),
                map: (0..n as u32).collect(),
            },
            0,
        ));
    }
    Ok((merge(mesh, &mut parent)?, pairs))
}

/// Vertices reachable from `v` over at most `hops` mesh edges (`v` included).
fn within_hops(topo: &Topology, v: u32, hops: u32) -> HashSet<u32> {
    let mut seen = HashSet::from([v]);
    let mut queue = VecDeque::from([(v, 0)]);
    while let Some((u, d)) = queue.pop_front() {
        if d == hops {
            continue;
        }
        for &w in topo.vertex_ring.row(u as usize) {
            if seen.insert(w) {
                queue.push_back((w, d + 1));
            }
        }
    }
    seen
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::math::Vec3;
    use tryon_core::mesh::{Face, grid_xz};

    /// Two 4 x 3 panels side by side with a `gap` between their facing borders (x = 0 and x = gap).
    fn two_panels(gap: Real) -> PolyMesh {
        let a = grid_xz(3, 3, 0.3, 0.3, 0.0);
        let mut positions: Vec<Vec3> = a.positions.iter().map(|p| p - Vec3::x() * 0.15).collect();
        let off = positions.len() as u32;
        positions.extend(a.positions.iter().map(|p| p + Vec3::x() * (0.15 + gap)));
        let mut faces = a.faces.clone();
        faces.extend(a.faces.iter().map(|f| match *f {
            Face::Tri(t) => Face::Tri(t.map(|v| v + off)),
            Face::Quad(q) => Face::Quad(q.map(|v| v + off)),
        }));
        PolyMesh::new(positions, faces).unwrap()
    }

    #[test]
    fn touching_panels_are_sewn_along_their_whole_facing_border() {
        let m = two_panels(0.004);
        let (w, pairs) = close_openings(&m, 0.05).unwrap();
        // The four facing vertex pairs become one column: 32 - 4 vertices, faces unchanged.
        assert_eq!(pairs, 4);
        assert_eq!(w.mesh.positions.len(), 28);
        assert_eq!(w.mesh.faces.len(), 18);
        // Sewn: the three joined edges now have two faces each, so the border lost six edges.
        let before = Topology::build(&m).unwrap().boundary_edges.len();
        let after = Topology::build(&w.mesh).unwrap().boundary_edges.len();
        assert_eq!(before - after, 6);
    }

    #[test]
    fn open_borders_and_a_single_touching_point_stay_open() {
        // Farther apart than the gap: nothing.
        let (w, pairs) = close_openings(&two_panels(0.08), 0.05).unwrap();
        assert_eq!((pairs, w.mesh.positions.len()), (0, 32));
        // One sheet: its own border vertices are close to their neighbours only.
        let g = grid_xz(6, 6, 0.3, 0.3, 0.0);
        assert_eq!(close_openings(&g, 0.06).unwrap().1, 0);
        // Only one pair of corners touching: no seam, left alone.
        let mut m = two_panels(0.2);
        let last = m.positions.len() - 1;
        m.positions[3] = m.positions[last - 3] - Vec3::x() * 0.001;
        assert_eq!(close_openings(&m, 0.05).unwrap().1, 0);
    }
}
