//! The body's triangle mesh with the topology the colliders need, and its per-frame shape
//! (positions, face normals, velocities).

use crate::grid::VertexGrid;
use thiserror::Error;
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, Vec3, closest_point_on_triangle};
use tryon_core::mesh::PolyMesh;
use tryon_core::topology::{Csr, Topology, TopologyError};

/// Why a body mesh was rejected.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum BodyError {
    #[error("body mesh: {0}")]
    Topology(#[from] TopologyError),
    #[error("body frame has {got} vertices, the body mesh has {expected}")]
    VertexCount { got: usize, expected: usize },
}

/// How far from a point [`BodyMesh::nearest_vertex`] looks for a nearer vertex than the climb
/// found (m), and the hash's cell size: a point nearer the body than this (the cloth's contact
/// reach is 3 cm plus the thickness) always gets its true nearest vertex.
pub const SNAP_REACH: Real = 0.05;

/// A body triangle mesh, its topology, and its current shape.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct BodyMesh {
    pub triangles: Vec<[u32; 3]>,
    /// Neighbouring vertices of each vertex.
    pub ring: Csr,
    /// Triangles around each vertex.
    pub vertex_faces: Csr,
    pub positions: Vec<Vec3>,
    /// Unit outward normal of each triangle (empty after [`BodyMesh::set_shape`]: see
    /// [`BodyMesh::face_normal`]).
    pub face_normals: Vec<Vec3>,
    /// Vertex velocities (empty when the body is at rest).
    pub velocities: Vec<Vec3>,
    /// The vertices hashed for [`BodyMesh::nearest_vertex`], built on first use after each shape
    /// (a checkpoint leaves it out: it is made again from the shape).
    #[serde(skip)]
    grid: std::sync::OnceLock<VertexGrid>,
    /// Unit vertex normals (sums of the fan's face normals), made on first use after each shape.
    #[serde(skip)]
    vertex_normals: std::sync::OnceLock<Vec<Vec3>>,
}

impl BodyMesh {
    /// Validates the mesh (triangulating quads) and builds its topology.
    pub fn new(mesh: &PolyMesh) -> Result<Self, BodyError> {
        let (triangles, _) = mesh.triangulate();
        let tri_mesh = PolyMesh::from_triangles(mesh.positions.clone(), &triangles)
            .map_err(TopologyError::from)?;
        let topo = Topology::build(&tri_mesh)?;
        let mut body = BodyMesh {
            triangles,
            ring: topo.vertex_ring,
            vertex_faces: topo.vertex_faces,
            positions: mesh.positions.clone(),
            face_normals: Vec::new(),
            velocities: Vec::new(),
            grid: std::sync::OnceLock::new(),
            vertex_normals: std::sync::OnceLock::new(),
        };
        body.compute_normals();
        Ok(body)
    }

    /// Takes a new body shape. Frames with the wrong vertex count are ignored and reported.
    pub fn set_frame(&mut self, frame: &BodyFrame) -> Result<(), BodyError> {
        self.set_shape(frame)?;
        self.compute_normals();
        Ok(())
    }

    /// Takes a new body shape without computing the face normals (`face_normals` is left empty),
    /// for users that need only a few of them ([`BodyMesh::face_normal`]).
    pub fn set_shape(&mut self, frame: &BodyFrame) -> Result<(), BodyError> {
        if frame.positions.len() != self.positions.len() {
            return Err(BodyError::VertexCount {
                got: frame.positions.len(),
                expected: self.positions.len(),
            });
        }
        self.positions.copy_from_slice(&frame.positions);
        self.velocities.clear();
        if frame.velocities.len() == frame.positions.len() {
            self.velocities.extend_from_slice(&frame.velocities);
        }
        self.face_normals.clear();
        self.grid = std::sync::OnceLock::new();
        self.vertex_normals = std::sync::OnceLock::new();
        Ok(())
    }

    fn compute_normals(&mut self) {
        let mut normals = std::mem::take(&mut self.face_normals);
        normals.clear();
        normals.extend((0..self.triangles.len()).map(|f| self.normal_now(f)));
        self.face_normals = normals;
    }

    /// Unit normal of triangle `f` computed from the current positions (zero when degenerate).
    #[inline]
    fn normal_now(&self, f: usize) -> Vec3 {
        let [a, b, c] = self.corners(f);
        let n = (b - a).cross(&(c - a));
        let len = n.norm();
        if len > 0.0 { n / len } else { Vec3::zeros() }
    }

    /// Unit outward normal of triangle `f`: from `face_normals`, or computed now when they were
    /// not ([`BodyMesh::set_shape`]).
    #[inline]
    pub fn face_normal(&self, f: usize) -> Vec3 {
        match self.face_normals.get(f) {
            Some(n) => *n,
            None => self.normal_now(f),
        }
    }

    /// Corner positions of triangle `f`.
    #[inline]
    pub fn corners(&self, f: usize) -> [Vec3; 3] {
        let [a, b, c] = self.triangles[f];
        let p = &self.positions;
        [p[a as usize], p[b as usize], p[c as usize]]
    }

    /// Velocity of the surface at barycentric `bary` on triangle `f` (zero for a body at rest).
    pub fn velocity_at(&self, f: usize, bary: [Real; 3]) -> Vec3 {
        if self.velocities.is_empty() {
            return Vec3::zeros();
        }
        let t = self.triangles[f];
        (0..3)
            .map(|k| self.velocities[t[k] as usize] * bary[k])
            .sum()
    }

    /// Steepest descent on distance to `p` over the vertex graph, from vertex `start`.
    pub fn climb(&self, p: &Vec3, start: u32) -> u32 {
        let mut v = start;
        let mut best = (self.positions[v as usize] - p).norm_squared();
        loop {
            let mut next = v;
            for &w in self.ring.row(v as usize) {
                let d = (self.positions[w as usize] - p).norm_squared();
                if d < best {
                    best = d;
                    next = w;
                }
            }
            if next == v {
                return v;
            }
            v = next;
        }
    }

    /// The nearest vertex to `p`, from a guess: the hill-climb from `start` (P1's tracking), unless
    /// the spatial hash of the vertices knows a nearer vertex within [`SNAP_REACH`] (the climb
    /// stopped at a local minimum: another limb). Exact for points within that reach of a vertex.
    pub fn nearest_vertex(&self, p: &Vec3, start: u32) -> u32 {
        let v = self.climb(p, start);
        let d2 = (self.positions[v as usize] - p).norm_squared();
        let r = d2.sqrt().min(SNAP_REACH);
        match self.grid().nearest_within(&self.positions, p, r) {
            Some((w, d)) if d < d2 => w,
            _ => v,
        }
    }

    /// The vertices' hash for the current shape (built on first use).
    pub fn grid(&self) -> &VertexGrid {
        self.grid
            .get_or_init(|| VertexGrid::new(&self.positions, SNAP_REACH))
    }

    /// Unit normal at vertex `v`: its fan's face normals summed (zero for a vertex in no face).
    pub fn vertex_normal(&self, v: u32) -> Vec3 {
        let normals = self.vertex_normals.get_or_init(|| {
            (0..self.positions.len())
                .map(|w| {
                    let n: Vec3 = self
                        .vertex_faces
                        .row(w)
                        .iter()
                        .map(|&f| self.face_normal(f as usize))
                        .sum();
                    n.try_normalize(1e-12).unwrap_or(Vec3::zeros())
                })
                .collect()
        });
        normals[v as usize]
    }

    /// The nearest vertex to `p` by checking every vertex.
    pub fn nearest_vertex_brute(&self, p: &Vec3) -> u32 {
        let mut best = (0, Real::INFINITY);
        for (i, q) in self.positions.iter().enumerate() {
            let d = (q - p).norm_squared();
            if d < best.1 {
                best = (i as u32, d);
            }
        }
        best.0
    }

    /// Closest point to `p` on the triangles around vertex `v`: (face, point, barycentric).
    pub fn closest_on_fan(&self, p: &Vec3, v: u32) -> (u32, Vec3, [Real; 3]) {
        let mut best = (u32::MAX, Vec3::zeros(), [0.0; 3], Real::INFINITY);
        for &f in self.vertex_faces.row(v as usize) {
            let [a, b, c] = self.corners(f as usize);
            let (q, w) = closest_point_on_triangle(p, &a, &b, &c);
            let d = (q - p).norm_squared();
            if d < best.3 {
                best = (f, q, w, d);
            }
        }
        (best.0, best.1, best.2)
    }

    /// Axis-aligned bounds of the current shape.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::repeat(Real::INFINITY);
        let mut hi = Vec3::repeat(Real::NEG_INFINITY);
        for p in &self.positions {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        (lo, hi)
    }

    /// One vertex of each connected piece of the body (by the vertex graph), largest piece first, and
    /// each vertex's piece in that order (`u32::MAX` for a vertex in no face).
    pub fn pieces(&self) -> (Vec<u32>, Vec<u32>) {
        let body = self;
        let n = body.positions.len();
        let mut label = vec![u32::MAX; n];
        let mut found: Vec<(usize, u32)> = Vec::new();
        for start in 0..n {
            if label[start] != u32::MAX || body.vertex_faces.row(start).is_empty() {
                continue;
            }
            let id = found.len() as u32;
            label[start] = id;
            let mut stack = vec![start as u32];
            let mut size = 0;
            while let Some(v) = stack.pop() {
                size += 1;
                for &w in body.ring.row(v as usize) {
                    if label[w as usize] == u32::MAX {
                        label[w as usize] = id;
                        stack.push(w);
                    }
                }
            }
            found.push((size, start as u32));
        }
        let mut order: Vec<usize> = (0..found.len()).collect();
        order.sort_by_key(|&i| std::cmp::Reverse(found[i].0));
        let mut rank = vec![0u32; found.len()];
        for (r, &i) in order.iter().enumerate() {
            rank[i] = r as u32;
        }
        let piece_of = label
            .into_iter()
            .map(|l| if l == u32::MAX { l } else { rank[l as usize] })
            .collect();
        (order.into_iter().map(|i| found[i].1).collect(), piece_of)
    }
}
