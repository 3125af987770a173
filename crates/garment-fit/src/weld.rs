//! A light coarsening for garments modelled for rendering: edges much shorter than the mesh's
//! typical edge (doubled hems, slivers at seams) are collapsed, their ends welded into one vertex.
//! Such edges carry no visible shape, but a mass-spring cloth pays for them with tiny substeps and
//! meaningless strain readings.

use crate::find_root as find;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{Face, MeshError, PolyMesh};

/// The welded mesh and, for each old vertex, its new index (`u32::MAX` when it was dropped).
#[derive(Clone, Debug, PartialEq)]
pub struct Welded {
    pub mesh: PolyMesh,
    pub map: Vec<u32>,
}

/// Median length of the mesh's face edges (0 without faces).
pub fn median_edge(mesh: &PolyMesh) -> Real {
    let mut e: Vec<Real> = Vec::new();
    for f in &mesh.faces {
        let v = f.vertices();
        for k in 0..v.len() {
            let (a, b) = (v[k] as usize, v[(k + 1) % v.len()] as usize);
            e.push((mesh.positions[a] - mesh.positions[b]).norm());
        }
    }
    if e.is_empty() {
        return 0.0;
    }
    e.sort_by(Real::total_cmp);
    e[e.len() / 2]
}

/// Collapses every face edge shorter than `min_len` (welded groups go to their mean position);
/// faces left with fewer than three distinct vertices are dropped, quads with three become
/// triangles, vertices no face uses are dropped. Vertices keep their relative order.
pub fn weld_short_edges(mesh: &PolyMesh, min_len: Real) -> Result<Welded, MeshError> {
    let n = mesh.positions.len();
    let mut parent: Vec<usize> = (0..n).collect();
    for f in &mesh.faces {
        let v = f.vertices();
        for k in 0..v.len() {
            let (a, b) = (v[k] as usize, v[(k + 1) % v.len()] as usize);
            if (mesh.positions[a] - mesh.positions[b]).norm() < min_len {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra.max(rb)] = ra.min(rb);
            }
        }
    }
    merge(mesh, &mut parent)
}

/// Merges the vertices of every union-find group of `parent` (one entry per vertex) into one at
/// their mean position; faces left with fewer than three distinct vertices or no area are dropped,
/// and vertices no face uses. Vertices keep their relative order.
pub(crate) fn merge(mesh: &PolyMesh, parent: &mut [usize]) -> Result<Welded, MeshError> {
    let n = mesh.positions.len();
    let roots: Vec<usize> = (0..n).map(|v| find(parent, v)).collect();
    let mut map = vec![u32::MAX; n];
    let mut sum: Vec<(Vec3, Real)> = Vec::new();
    for v in 0..n {
        let r = roots[v];
        if map[r] == u32::MAX {
            map[r] = sum.len() as u32;
            sum.push((Vec3::zeros(), 0.0));
        }
        map[v] = map[r];
        let e = &mut sum[map[v] as usize];
        e.0 += mesh.positions[v];
        e.1 += 1.0;
    }
    let positions: Vec<Vec3> = sum.iter().map(|(p, c)| p / *c).collect();
    let mut faces = Vec::with_capacity(mesh.faces.len());
    for f in &mesh.faces {
        let mut v: Vec<u32> = Vec::with_capacity(4);
        for &x in f.vertices() {
            let m = map[x as usize];
            if v.last() != Some(&m) && v.first() != Some(&m) {
                v.push(m);
            }
        }
        match v.len() {
            3 => faces.push(Face::Tri([v[0], v[1], v[2]])),
            4 => faces.push(Face::Quad([v[0], v[1], v[2], v[3]])),
            _ => {}
        }
    }
    // Drop faces whose area vanished in the weld.
    let probe = PolyMesh {
        positions,
        faces: faces.clone(),
    };
    let keep: Vec<Face> = (0..faces.len())
        .filter(|&i| probe.face_area(i) > 1e-12)
        .map(|i| faces[i])
        .collect();
    // Drop vertices no face uses any more (a cloth particle without area would fly free).
    let mut used = vec![false; probe.positions.len()];
    for f in &keep {
        for &v in f.vertices() {
            used[v as usize] = true;
        }
    }
    let mut compact = vec![u32::MAX; used.len()];
    let mut positions = Vec::with_capacity(used.len());
    for (v, u) in used.iter().enumerate() {
        if *u {
            compact[v] = positions.len() as u32;
            positions.push(probe.positions[v]);
        }
    }
    let faces = keep
        .iter()
        .map(|f| match *f {
            Face::Tri(t) => Face::Tri(t.map(|v| compact[v as usize])),
            Face::Quad(q) => Face::Quad(q.map(|v| compact[v as usize])),
        })
        .collect();
    let map = map.iter().map(|m| compact[*m as usize]).collect();
    let mesh = PolyMesh::new(positions, faces)?;
    Ok(Welded { mesh, map })
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn a_sliver_row_is_welded_and_the_rest_kept() {
        let mut g = grid_xz(3, 2, 0.3, 0.2, 0.0);
        // Squeeze the last column to 0.5 mm from its neighbour.
        for p in &mut g.positions {
            if p.x > 0.14 {
                p.x = 0.0505;
            }
        }
        let w = weld_short_edges(&g, 0.002).unwrap();
        assert_eq!(w.mesh.positions.len(), g.positions.len() - 3);
        assert_eq!(w.mesh.faces.len(), g.faces.len() - 2);
        assert_eq!(w.map.len(), g.positions.len());
        // Nothing to weld: the mesh comes back unchanged.
        let g = grid_xz(3, 2, 0.3, 0.2, 0.0);
        let w = weld_short_edges(&g, 0.002).unwrap();
        assert_eq!(w.mesh, g);
        assert!((median_edge(&g) - 0.1).abs() < 1e-12);
    }
}
