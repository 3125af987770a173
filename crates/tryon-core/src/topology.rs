//! Mesh topology built once: unique edges, edge -> faces, vertex one-rings, vertex -> faces, face
//! adjacency and boundary edges. Works on the polygon faces (a quad's diagonal is not an edge).

use crate::mesh::{MeshError, PolyMesh};
use std::collections::HashMap;
use thiserror::Error;

/// Marks "no face" in [`Topology::edge_faces`].
pub const NO_FACE: u32 = u32::MAX;

/// Compressed rows: row `i` is `items[offsets[i]..offsets[i + 1]]`.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Csr {
    pub offsets: Vec<u32>,
    pub items: Vec<u32>,
}

impl Csr {
    /// Row `i`.
    #[inline]
    pub fn row(&self, i: usize) -> &[u32] {
        &self.items[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// True when there are no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn from_rows(rows: Vec<Vec<u32>>) -> Self {
        let mut offsets = Vec::with_capacity(rows.len() + 1);
        let mut items = Vec::new();
        offsets.push(0);
        for r in rows {
            items.extend(r);
            offsets.push(items.len() as u32);
        }
        Csr { offsets, items }
    }
}

/// Connectivity of a [`PolyMesh`].
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Topology {
    /// Unique edges, each with its smaller vertex first.
    pub edges: Vec<[u32; 2]>,
    /// The one or two faces of each edge; the second is [`NO_FACE`] on a boundary edge.
    pub edge_faces: Vec<[u32; 2]>,
    /// Neighbouring vertices of each vertex (its one-ring), ascending.
    pub vertex_ring: Csr,
    /// Faces around each vertex, ascending.
    pub vertex_faces: Csr,
    /// Faces sharing an edge with each face, ascending.
    pub face_adjacency: Csr,
    /// Indices into `edges` of the edges with a single face.
    pub boundary_edges: Vec<u32>,
}

/// Why topology could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum TopologyError {
    #[error(transparent)]
    Mesh(#[from] MeshError),
    #[error("edge ({a}, {b}) is shared by more than two faces (faces {faces:?})")]
    NonManifoldEdge { a: u32, b: u32, faces: Vec<u32> },
}

impl Topology {
    /// Builds the topology of a mesh after validating it.
    pub fn build(mesh: &PolyMesh) -> Result<Self, TopologyError> {
        mesh.validate()?;
        let nv = mesh.positions.len();
        let mut index: HashMap<(u32, u32), u32> = HashMap::new();
        let mut edges = Vec::new();
        let mut edge_faces: Vec<Vec<u32>> = Vec::new();
        let mut vertex_faces = vec![Vec::new(); nv];
        for (fi, f) in mesh.faces.iter().enumerate() {
            let vs = f.vertices();
            for k in 0..vs.len() {
                let (a, b) = (vs[k], vs[(k + 1) % vs.len()]);
                let key = (a.min(b), a.max(b));
                let e = *index.entry(key).or_insert_with(|| {
                    edges.push([key.0, key.1]);
                    edge_faces.push(Vec::new());
                    (edges.len() - 1) as u32
                });
                edge_faces[e as usize].push(fi as u32);
                vertex_faces[a as usize].push(fi as u32);
            }
        }
        let mut ef = Vec::with_capacity(edges.len());
        let mut boundary = Vec::new();
        let mut ring = vec![Vec::new(); nv];
        let mut fadj = vec![Vec::new(); mesh.faces.len()];
        for (e, faces) in edge_faces.into_iter().enumerate() {
            let [a, b] = edges[e];
            ring[a as usize].push(b);
            ring[b as usize].push(a);
            match faces.as_slice() {
                [f] => {
                    ef.push([*f, NO_FACE]);
                    boundary.push(e as u32);
                }
                [f, g] => {
                    ef.push([*f, *g]);
                    fadj[*f as usize].push(*g);
                    fadj[*g as usize].push(*f);
                }
                _ => return Err(TopologyError::NonManifoldEdge { a, b, faces }),
            }
        }
        for r in ring
            .iter_mut()
            .chain(vertex_faces.iter_mut())
            .chain(fadj.iter_mut())
        {
            r.sort_unstable();
            r.dedup();
        }
        Ok(Topology {
            edges,
            edge_faces: ef,
            vertex_ring: Csr::from_rows(ring),
            vertex_faces: Csr::from_rows(vertex_faces),
            face_adjacency: Csr::from_rows(fadj),
            boundary_edges: boundary,
        })
    }

    /// True when every edge has exactly two faces.
    pub fn is_closed(&self) -> bool {
        self.boundary_edges.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{Face, grid_xz};

    #[test]
    fn grid_topology_counts() {
        let m = grid_xz(3, 2, 1.0, 1.0, 0.0);
        let t = Topology::build(&m).unwrap();
        // 3x2 quads: horizontal edges 3*3, vertical 4*2.
        assert_eq!(t.edges.len(), 17);
        assert_eq!(t.boundary_edges.len(), 10);
        assert_eq!(t.vertex_ring.row(5), &[1, 4, 6, 9]);
        assert_eq!(t.face_adjacency.row(1), &[0, 2, 4]);
        assert_eq!(t.vertex_faces.row(5), &[0, 1, 3, 4]);
        assert!(!t.is_closed());
    }

    #[test]
    fn non_manifold_edge_is_named() {
        let mut m = grid_xz(1, 1, 1.0, 1.0, 0.0);
        m.positions.push(crate::Vec3::new(0.0, 1.0, 0.0));
        m.positions.push(crate::Vec3::new(0.0, -1.0, 0.0));
        m.faces.push(Face::Tri([0, 1, 4]));
        m.faces.push(Face::Tri([1, 0, 5]));
        let err = Topology::build(&m).unwrap_err();
        assert!(
            matches!(err, TopologyError::NonManifoldEdge { a: 0, b: 1, .. }),
            "{err}"
        );
    }
}
