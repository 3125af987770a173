//! Polygon meshes of triangles and quads, their triangulated view, and validation that names the
//! offending face or vertex.

use crate::math::{Real, Vec3, is_finite, triangle_area_normal};
use thiserror::Error;

/// A mesh face: a triangle or a quad, counter-clockwise seen from outside (the front side).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
#[derive(Clone, Debug, Default, PartialEq)]
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
}
