//! Polygon meshes of triangles and quads, their triangulated view, and validation that names the
//! offending face or vertex.

use crate::math::{Real, Vec3, is_finite, triangle_area_normal};
use thiserror::Error;

/// A mesh face: a triangle or a quad, counter-clockwise seen from outside (the front side).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Face {
    Tri([u32; 3]),
    Quad([u32; 4]),
}

impl Face {
    /// The face's vertex indices in order.
    #[inline]
    pub fn vertices(&self) -> &[u32] {
        match self {
            Face::Tri(v) => v,
            Face::Quad(v) => v,
        }
    }
}

/// A polygon mesh: positions and faces (triangles and quads).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PolyMesh {
    pub positions: Vec<Vec3>,
    pub faces: Vec<Face>,
}

/// Why a mesh was rejected. Every variant names the face or vertex at fault.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MeshError {
    #[error("mesh has no faces")]
    NoFaces,
    #[error("vertex {vertex} has a non-finite coordinate {value:?}")]
    NonFiniteCoordinate { vertex: usize, value: [Real; 3] },
    #[error("face {face} refers to vertex {index}, but the mesh has only {vertex_count} vertices")]
    IndexOutOfRange {
        face: usize,
        index: u32,
        vertex_count: usize,
    },
    #[error("face {face} lists vertex {vertex} more than once")]
    RepeatedVertex { face: usize, vertex: u32 },
    #[error("face {face} has a zero-length edge between vertices {a} and {b}")]
    ZeroLengthEdge { face: usize, a: u32, b: u32 },
    #[error("face {face} is degenerate: area {area:e} (at most {tolerance:e} is rejected)")]
    DegenerateFace {
        face: usize,
        area: Real,
        tolerance: Real,
    },
    #[error("vertices {a} and {b} are duplicates: both at {position:?}")]
    DuplicateVertex {
        a: usize,
        b: usize,
        position: [Real; 3],
    },
}

impl PolyMesh {
    /// A mesh from positions and faces, validated.
    pub fn new(positions: Vec<Vec3>, faces: Vec<Face>) -> Result<Self, MeshError> {
        let mesh = PolyMesh { positions, faces };
        mesh.validate()?;
        Ok(mesh)
    }

    /// A mesh of triangles only, validated.
    pub fn from_triangles(positions: Vec<Vec3>, tris: &[[u32; 3]]) -> Result<Self, MeshError> {
        Self::new(positions, tris.iter().map(|t| Face::Tri(*t)).collect())
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Triangulated view: quads split along their 0-2 diagonal. The second vector gives, for each
    /// triangle, the index of the face it came from.
    pub fn triangulate(&self) -> (Vec<[u32; 3]>, Vec<u32>) {
        let mut tris = Vec::with_capacity(self.faces.len() * 2);
        let mut origin = Vec::with_capacity(self.faces.len() * 2);
        for (fi, f) in self.faces.iter().enumerate() {
            match *f {
                Face::Tri(t) => {
                    tris.push(t);
                    origin.push(fi as u32);
                }
                Face::Quad([a, b, c, d]) => {
                    tris.push([a, b, c]);
                    tris.push([a, c, d]);
                    origin.push(fi as u32);
                    origin.push(fi as u32);
                }
            }
        }
        (tris, origin)
    }

    /// Area of face `fi` (for a quad, the norm of its vector area).
    pub fn face_area(&self, fi: usize) -> Real {
        let p = &self.positions;
        match self.faces[fi] {
            Face::Tri([a, b, c]) => {
                0.5 * triangle_area_normal(&p[a as usize], &p[b as usize], &p[c as usize]).norm()
            }
            Face::Quad([a, b, c, d]) => {
                let d02 = p[c as usize] - p[a as usize];
                let d13 = p[d as usize] - p[b as usize];
                0.5 * d02.cross(&d13).norm()
            }
        }
    }

    /// Diagonal of the axis-aligned bounding box (0 for an empty mesh).
    pub fn bbox_diagonal(&self) -> Real {
        let mut lo = Vec3::repeat(Real::INFINITY);
        let mut hi = Vec3::repeat(Real::NEG_INFINITY);
        for p in &self.positions {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if self.positions.is_empty() {
            0.0
        } else {
            (hi - lo).norm()
        }
    }

    /// Checks indices, finiteness, repeated corners, zero-length edges, degenerate faces and duplicate
    /// vertices. Lengths are judged relative to the bounding-box diagonal (tolerance 1e-9 of it).
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.faces.is_empty() {
            return Err(MeshError::NoFaces);
        }
        for (i, p) in self.positions.iter().enumerate() {
            if !is_finite(p) {
                return Err(MeshError::NonFiniteCoordinate {
                    vertex: i,
                    value: [p.x, p.y, p.z],
                });
            }
        }
        let n = self.positions.len();
        let eps = 1e-9 * self.bbox_diagonal().max(Real::MIN_POSITIVE);
        for (fi, f) in self.faces.iter().enumerate() {
            let vs = f.vertices();
            for (k, &v) in vs.iter().enumerate() {
                if v as usize >= n {
                    return Err(MeshError::IndexOutOfRange {
                        face: fi,
                        index: v,
                        vertex_count: n,
                    });
                }
                if vs[..k].contains(&v) {
                    return Err(MeshError::RepeatedVertex {
                        face: fi,
                        vertex: v,
                    });
                }
            }
            for k in 0..vs.len() {
                let (a, b) = (vs[k], vs[(k + 1) % vs.len()]);
                if (self.positions[a as usize] - self.positions[b as usize]).norm() <= eps {
                    return Err(MeshError::ZeroLengthEdge { face: fi, a, b });
                }
            }
            let area = self.face_area(fi);
            if area <= eps * eps {
                return Err(MeshError::DegenerateFace {
                    face: fi,
                    area,
                    tolerance: eps * eps,
                });
            }
        }
        self.check_duplicates(eps)
    }

    fn check_duplicates(&self, eps: Real) -> Result<(), MeshError> {
        let mut order: Vec<usize> = (0..self.positions.len()).collect();
        let p = &self.positions;
        order.sort_by(|&a, &b| p[a].x.total_cmp(&p[b].x));
        for (k, &a) in order.iter().enumerate() {
            for &b in &order[k + 1..] {
                if p[b].x - p[a].x > eps {
                    break;
                }
                if (p[a] - p[b]).norm() <= eps {
                    let (a, b) = (a.min(b), a.max(b));
                    return Err(MeshError::DuplicateVertex {
                        a,
                        b,
                        position: [p[a].x, p[a].y, p[a].z],
                    });
                }
            }
        }
        Ok(())
    }
}

/// What [`PolyMesh::welded`] changed: how many vertices were merged into others and how many
/// faces were dropped as slivers (no area left, or a corner repeated once merged).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Welding {
    pub merged_vertices: usize,
    pub dropped_faces: usize,
}

impl Welding {
    /// Whether the mesh was changed.
    pub fn changed(&self) -> bool {
        self.merged_vertices + self.dropped_faces > 0
    }
}

impl PolyMesh {
    /// The mesh with duplicate vertices (within [`PolyMesh::validate`]'s tolerance, 1e-9 of the
    /// bounding-box diagonal) merged into the lowest-numbered of them, faces with no area dropped,
    /// and vertices no face uses removed. A quad that loses a corner becomes a triangle. Indices
    /// out of range are left for `validate` to name.
    pub fn welded(&self) -> (PolyMesh, Welding) {
        let eps = 1e-9 * self.bbox_diagonal().max(Real::MIN_POSITIVE);
        let root = self.duplicate_roots(eps);
        let merged_vertices = root.iter().enumerate().filter(|(i, r)| *i != **r).count();
        let mut faces = Vec::with_capacity(self.faces.len());
        for f in &self.faces {
            let mut vs: Vec<u32> = Vec::with_capacity(4);
            for &v in f.vertices() {
                let v = root.get(v as usize).map_or(v, |&r| r as u32);
                if !vs.contains(&v) {
                    vs.push(v);
                }
            }
            let face = match vs[..] {
                [a, b, c] => Face::Tri([a, b, c]),
                [a, b, c, d] => Face::Quad([a, b, c, d]),
                _ => continue,
            };
            faces.push(face);
        }
        let mut mesh = PolyMesh {
            positions: self.positions.clone(),
            faces,
        };
        let n = mesh.positions.len();
        let in_range = |f: &Face| f.vertices().iter().all(|&v| (v as usize) < n);
        mesh.faces = (0..mesh.faces.len())
            .filter(|&fi| !in_range(&mesh.faces[fi]) || mesh.face_area(fi) > eps * eps)
            .map(|fi| mesh.faces[fi])
            .collect();
        let dropped_faces = self.faces.len() - mesh.faces.len();
        (
            mesh.without_unused(),
            Welding {
                merged_vertices,
                dropped_faces,
            },
        )
    }

    /// The volume the faces enclose, positive when they face outward (for a closed mesh; an open
    /// one gives the volume of the cone from the origin, a hint at best).
    pub fn signed_volume(&self) -> Real {
        let p = &self.positions;
        let n = p.len();
        self.triangulate()
            .0
            .iter()
            .filter(|t| t.iter().all(|&v| (v as usize) < n))
            .map(|&[a, b, c]| p[a as usize].dot(&p[b as usize].cross(&p[c as usize])) / 6.0)
            .sum()
    }

    /// The mesh with every face's order reversed (front and back swapped).
    pub fn flipped(mut self) -> PolyMesh {
        for f in &mut self.faces {
            match f {
                Face::Tri(t) => t.reverse(),
                Face::Quad(q) => q.reverse(),
            }
        }
        self
    }

    /// For each vertex, the lowest-numbered vertex within `eps` of it, through chains of such.
    fn duplicate_roots(&self, eps: Real) -> Vec<usize> {
        let p = &self.positions;
        let mut root: Vec<usize> = (0..p.len()).collect();
        fn find(root: &mut [usize], mut v: usize) -> usize {
            while root[v] != v {
                root[v] = root[root[v]];
                v = root[v];
            }
            v
        }
        let mut order: Vec<usize> = (0..p.len()).collect();
        order.sort_by(|&a, &b| p[a].x.total_cmp(&p[b].x));
        for (k, &a) in order.iter().enumerate() {
            for &b in &order[k + 1..] {
                if !(p[b].x - p[a].x <= eps) {
                    break;
                }
                if (p[a] - p[b]).norm() <= eps {
                    let (ra, rb) = (find(&mut root, a), find(&mut root, b));
                    root[ra.max(rb)] = ra.min(rb);
                }
            }
        }
        (0..p.len()).map(|v| find(&mut root, v)).collect()
    }

    /// The mesh without the vertices no face uses (indices renumbered, order kept).
    fn without_unused(self) -> PolyMesh {
        let n = self.positions.len();
        let mut used = vec![false; n];
        for f in &self.faces {
            for &v in f.vertices() {
                if let Some(u) = used.get_mut(v as usize) {
                    *u = true;
                }
            }
        }
        if used.iter().all(|&u| u) {
            return self;
        }
        let mut new_index = vec![u32::MAX; n];
        let mut positions = Vec::new();
        for (v, p) in self.positions.iter().enumerate().filter(|(v, _)| used[*v]) {
            new_index[v] = positions.len() as u32;
            positions.push(*p);
        }
        let remap = |v: u32| new_index.get(v as usize).copied().unwrap_or(v);
        let faces = self
            .faces
            .iter()
            .map(|f| match *f {
                Face::Tri(t) => Face::Tri(t.map(remap)),
                Face::Quad(q) => Face::Quad(q.map(remap)),
            })
            .collect();
        PolyMesh { positions, faces }
    }
}

/// An `nx` by `nz` grid of quads (`(nx+1) * (nz+1)` vertices) of the given size in the XZ plane at
/// height `y`, centred on the Y axis; vertex (i, j) has index `j * (nx + 1) + i`. Faces point up (+Y).
pub fn grid_xz(nx: usize, nz: usize, size_x: Real, size_z: Real, y: Real) -> PolyMesh {
    let mut positions = Vec::with_capacity((nx + 1) * (nz + 1));
    for j in 0..=nz {
        for i in 0..=nx {
            let x = -0.5 * size_x + size_x * i as Real / nx as Real;
            let z = -0.5 * size_z + size_z * j as Real / nz as Real;
            positions.push(Vec3::new(x, y, z));
        }
    }
    let w = (nx + 1) as u32;
    let mut faces = Vec::with_capacity(nx * nz);
    for j in 0..nz as u32 {
        for i in 0..nx as u32 {
            let a = j * w + i;
            // Counter-clockwise seen from +Y: (x, z) -> (x, z+1) -> (x+1, z+1) -> (x+1, z).
            faces.push(Face::Quad([a, a + w, a + w + 1, a + 1]));
        }
    }
    PolyMesh { positions, faces }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> PolyMesh {
        grid_xz(1, 1, 1.0, 1.0, 0.0)
    }

    #[test]
    fn grid_is_valid_and_faces_up() {
        let m = grid_xz(4, 3, 1.0, 2.0, 0.5);
        m.validate().unwrap();
        assert_eq!(m.positions.len(), 20);
        let (tris, origin) = m.triangulate();
        assert_eq!(tris.len(), 24);
        assert_eq!(origin[23], 11);
        let p = &m.positions;
        for t in tris {
            let n = triangle_area_normal(&p[t[0] as usize], &p[t[1] as usize], &p[t[2] as usize]);
            assert!(n.y > 0.0, "grid triangle faces down: {n:?}");
        }
    }

    #[test]
    fn rejects_named_faults() {
        let mut m = quad();
        m.positions[2].y = Real::NAN;
        assert!(matches!(
            m.validate(),
            Err(MeshError::NonFiniteCoordinate { vertex: 2, .. })
        ));
        let mut m = quad();
        m.faces.push(Face::Tri([0, 1, 9]));
        assert_eq!(
            m.validate(),
            Err(MeshError::IndexOutOfRange {
                face: 1,
                index: 9,
                vertex_count: 4
            })
        );
        let mut m = quad();
        m.faces.push(Face::Tri([0, 1, 0]));
        assert_eq!(
            m.validate(),
            Err(MeshError::RepeatedVertex { face: 1, vertex: 0 })
        );
        let mut m = quad();
        m.positions.push(m.positions[1] + Vec3::new(0.5, 0.0, 0.0));
        m.faces.push(Face::Tri([1, 4, 3]));
        m.positions[3] = m.positions[1];
        assert!(matches!(
            m.validate(),
            Err(MeshError::ZeroLengthEdge { face: 0, .. })
        ));
        let mut m = quad();
        m.positions.push(Vec3::new(1.5, 0.0, -0.5));
        m.positions.push(Vec3::new(2.5, 0.0, -0.5));
        m.faces.push(Face::Tri([0, 4, 5]));
        assert!(matches!(
            m.validate(),
            Err(MeshError::DegenerateFace { face: 1, .. })
        ));
        let mut m = quad();
        m.positions.push(m.positions[2]);
        assert!(matches!(
            m.validate(),
            Err(MeshError::DuplicateVertex { a: 2, b: 4, .. })
        ));
        let msg = m.validate().unwrap_err().to_string();
        assert!(msg.contains("vertices 2 and 4"), "{msg}");
    }

    #[test]
    fn welding_merges_seams_and_drops_slivers_to_a_valid_mesh() {
        // Two quads side by side, each with its own copy of the shared edge (a seam), a
        // triangle whose corners collapse once welded, and a vertex no face uses.
        let mut m = grid_xz(1, 1, 1.0, 1.0, 0.0);
        let shift = Vec3::new(1.0, 0.0, 0.0);
        let copy: Vec<Vec3> = m.positions.iter().map(|p| p + shift).collect();
        m.positions.extend(copy);
        m.faces.push(Face::Quad([4, 6, 7, 5]));
        m.positions.push(m.positions[3]); // 8 = a duplicate of 3
        m.faces.push(Face::Tri([3, 8, 2])); // zero area once 8 is 3
        m.positions.push(Vec3::new(9.0, 9.0, 9.0)); // 9 unused
        assert!(m.validate().is_err());
        let (w, report) = m.welded();
        w.validate().unwrap();
        // The copy's x = 0.5 corners 4 and 6 fall on 1 and 3; 8 on 3.
        assert_eq!(report.merged_vertices, 3);
        assert_eq!(report.dropped_faces, 1);
        assert_eq!(w.positions.len(), 6);
        assert_eq!(w.faces.len(), 2);
        // A valid mesh is left as it was.
        let g = grid_xz(3, 2, 1.0, 1.0, 0.0);
        let (same, none) = g.welded();
        assert_eq!(same, g);
        assert!(!none.changed());
    }

    #[test]
    fn a_closed_meshs_volume_is_positive_facing_out_and_flips_sign() {
        // A 2 x 0.5 x 2 box: volume 2.
        let slab = crate::shapes::table_slab(2.0, 0.5, 3);
        let v = slab.signed_volume();
        assert!((v - 2.0).abs() < 1e-12, "{v}");
        assert!((slab.flipped().signed_volume() + 2.0).abs() < 1e-12);
    }
}
