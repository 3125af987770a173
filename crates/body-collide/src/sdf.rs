//! P3's collider: a signed distance field sampled on a regular grid and trilinearly interpolated.
//!
//! P3 precomputes the field once for a rigid object. A body that moves deforms, so here the field
//! is rebuilt from the deformed mesh at every [`Collider::update`]:
//! 1. exact distances in a narrow band: every triangle visits the grid nodes within `band` cells of
//!    its bounds and keeps the nearest triangle per node (eight nodes at a time, [`crate::sdf_band`]);
//! 2. signs in the band from the angle-weighted pseudo-normal of the nearest feature (face, edge or
//!    vertex), as the exact referee does;
//! 3. nodes beyond the band get their sign by a flood fill from the grid's border (what the fill
//!    cannot reach is inside); outside they keep a bound of `band + 1` cells, inside they take the
//!    distance to the nearest triangle among their neighbours', propagated breadth-first from the
//!    band, so a point deep inside still has a distance and a way out.
//!
//! The rebuild costs time proportional to the number of body triangles times (2 band + 1)^3 when
//! the triangles are smaller than a cell, as a body's are; a static body pays it once. Told where
//! the cloth is ([`Collider::focus`]), the grid covers only the cloth's bounds and
//! [`SdfCollider::FOCUS_MARGIN`] around them, on the same nodes as the whole body's grid; a face of
//! that grid cut through the body does not start the flood fill, so the body's inside stays
//! inside. It is rebuilt around the cloth when the cloth comes within
//! [`SdfCollider::FOCUS_SLACK`] of its edge. Resolution is the number of cells along the body's
//! longest side.

use crate::body::{BodyError, BodyMesh};
use crate::sdf_band::BandGrid;
use std::collections::VecDeque;
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3, closest_point_on_triangle};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Probe};

/// Grid collider (P3).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct SdfCollider {
    pub body: BodyMesh,
    /// Distance the cloth keeps from the body surface (m).
    pub thickness: Real,
    /// Cells along the longest side of the body's bounds.
    pub resolution: usize,
    /// Width of the exact band, in cells (>= 1).
    pub band: usize,
    origin: Vec3,
    cell: Real,
    dims: [usize; 3],
    /// Signed distance at each node (x fastest).
    dist: Vec<Real>,
    /// Nearest body triangle of each band node (`u32::MAX` beyond the band).
    face: Vec<u32>,
    vertex_normals: Vec<Vec3>,
    /// The region the field covers when the cloth is known ([`Collider::focus`]), and the
    /// cloth's last bounds.
    region: Option<(Vec3, Vec3)>,
    cloth: Option<(Vec3, Vec3)>,
    /// Whether each face of the grid (axis, low/high) lies on the body's padded bounds, where
    /// the flood fill may start; a face cut through the body by the region may not.
    open_faces: [[bool; 2]; 3],
}

impl SdfCollider {
    /// Cells along the body's longest side unless a scene says otherwise.
    pub const DEFAULT_RESOLUTION: usize = 64;

    /// A grid of `resolution` cells along the body's longest side.
    pub fn new(mesh: &PolyMesh, thickness: Real, resolution: usize) -> Result<Self, BodyError> {
        let mut c = SdfCollider {
            body: BodyMesh::new(mesh)?,
            thickness,
            resolution: resolution.max(4),
            band: 2,
            origin: Vec3::zeros(),
            cell: 1.0,
            dims: [0; 3],
            dist: Vec::new(),
            face: Vec::new(),
            vertex_normals: Vec::new(),
            region: None,
            cloth: None,
            open_faces: [[true; 2]; 3],
        };
        c.rebuild();
        Ok(c)
    }

    /// Edge length of a grid cell (m).
    pub fn cell_size(&self) -> Real {
        self.cell
    }

    /// Nodes along x, y and z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    #[inline]
    fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.dims[0] * (j + self.dims[1] * k)
    }

    /// How far beyond the cloth's bounds the field reaches (m): farther than cloth moves in a
    /// frame (4.5 m/s at 30 fps).
    pub const FOCUS_MARGIN: Real = 0.15;
    /// The cloth may come this close to the edge of the field before it is rebuilt around it.
    pub const FOCUS_SLACK: Real = 0.05;

    fn rebuild(&mut self) {
        let (lo, hi) = self.body.bounds();
        let extent = (hi - lo).max().max(1e-6);
        self.cell = extent / self.resolution as Real;
        let pad = (self.band + 2) as Real * self.cell + self.thickness;
        let (full_lo, full_hi) = (lo - Vec3::repeat(pad), hi + Vec3::repeat(pad));
        let (mut glo, mut ghi) = (full_lo, full_hi);
        self.open_faces = [[true; 2]; 3];
        self.region = None;
        if let Some((clo, chi)) = self.cloth {
            // The cloth's surroundings only, on the full grid's nodes, where they cut the body.
            let m = Vec3::repeat(Self::FOCUS_MARGIN.max(3.0 * self.cell));
            let (rlo, rhi) = (clo - m, chi + m);
            let mut open = [[true; 2]; 3];
            let (mut flo, mut fhi) = (full_lo, full_hi);
            for a in 0..3 {
                if rlo[a] > lo[a] {
                    flo[a] =
                        full_lo[a] + ((rlo[a] - pad - full_lo[a]) / self.cell).floor() * self.cell;
                    open[a][0] = false;
                }
                if rhi[a] < hi[a] {
                    fhi[a] =
                        full_lo[a] + ((rhi[a] + pad - full_lo[a]) / self.cell).ceil() * self.cell;
                    open[a][1] = false;
                }
            }
            // The outside must still touch an open face, and the region must hold the body.
            if open.iter().flatten().any(|&o| o) && (0..3).all(|a| flo[a] < fhi[a]) {
                (glo, ghi, self.open_faces) = (flo, fhi, open);
                self.region = Some((rlo, rhi));
            }
        }
        self.origin = glo;
        let span = ghi - glo;
        self.dims = [0, 1, 2].map(|a| ((span[a] / self.cell - 1e-6).ceil() as usize + 1).max(2));
        let total = self.dims[0] * self.dims[1] * self.dims[2];
        self.dist.clear();
        self.dist.resize(total, Real::INFINITY);
        self.face.clear();
        self.face.resize(total, u32::MAX);
        self.angle_weighted_normals();
        self.narrow_band();
        self.signs_in_band();
        self.flood_fill();
    }

    /// Angle-weighted vertex normals (the pseudo-normals of Baerentzen and Aanaes).
    fn angle_weighted_normals(&mut self) {
        let b = &self.body;
        self.vertex_normals.clear();
        self.vertex_normals.resize(b.positions.len(), Vec3::zeros());
        for (f, t) in b.triangles.iter().enumerate() {
            let p = b.corners(f);
            for k in 0..3 {
                let e1 = p[(k + 1) % 3] - p[k];
                let e2 = p[(k + 2) % 3] - p[k];
                let denom = e1.norm() * e2.norm();
                if denom > 0.0 {
                    let angle = (e1.dot(&e2) / denom).clamp(-1.0, 1.0).acos();
                    self.vertex_normals[t[k] as usize] += b.face_normals[f] * angle;
                }
            }
        }
        for n in &mut self.vertex_normals {
            *n = n.try_normalize(1e-30).unwrap_or(Vec3::zeros());
        }
    }

    /// Squared distances to the nearest triangle within the band ([`crate::sdf_band`]).
    fn narrow_band(&mut self) {
        let reach = self.band as Real * self.cell;
        let mut grid = BandGrid {
            origin: self.origin,
            cell: self.cell,
            dims: self.dims,
            dist2: &mut self.dist,
            face: &mut self.face,
        };
        for f in 0..self.body.triangles.len() {
            grid.add_triangle(f as u32, self.body.corners(f), reach);
        }
    }

    #[inline]
    fn node(&self, i: usize, j: usize, k: usize) -> Vec3 {
        self.origin + Vec3::new(i as Real, j as Real, k as Real) * self.cell
    }

    /// Outward pseudo-normal of the feature of face `f` nearest `p`, with the nearest point.
    fn pseudo_normal(&self, f: usize, p: &Vec3) -> (Vec3, Vec3, [Real; 3]) {
        let t = self.body.triangles[f];
        let [a, b, c] = self.body.corners(f);
        let (q, w) = closest_point_on_triangle(p, &a, &b, &c);
        let eps = 1e-9;
        let zeros: Vec<usize> = (0..3).filter(|&k| w[k] <= eps).collect();
        let n = match zeros.len() {
            2 => {
                let k = (0..3).find(|k| !zeros.contains(k)).unwrap_or(0);
                self.vertex_normals[t[k] as usize]
            }
            1 => {
                // Edge opposite the zero weight: add the neighbouring face across it.
                let z = zeros[0];
                let (u, v) = (t[(z + 1) % 3], t[(z + 2) % 3]);
                let mut n = self.body.face_normals[f];
                for &g in self.body.vertex_faces.row(u as usize) {
                    if g as usize != f && self.body.triangles[g as usize].contains(&v) {
                        n += self.body.face_normals[g as usize];
                        break;
                    }
                }
                n
            }
            _ => self.body.face_normals[f],
        };
        (n, q, w)
    }

    fn signs_in_band(&mut self) {
        for k in 0..self.dims[2] {
            for j in 0..self.dims[1] {
                for i in 0..self.dims[0] {
                    let n = self.index(i, j, k);
                    let f = self.face[n];
                    if f == u32::MAX {
                        continue;
                    }
                    let p = self.node(i, j, k);
                    let (pn, q, _) = self.pseudo_normal(f as usize, &p);
                    let d = (p - q).norm();
                    self.dist[n] = if (p - q).dot(&pn) < 0.0 { -d } else { d };
                }
            }
        }
    }

    /// Nodes beyond the band: outside when a 6-connected path of non-negative nodes reaches the
    /// grid's border, inside otherwise.
    fn flood_fill(&mut self) {
        let [nx, ny, nz] = self.dims;
        let far = (self.band + 1) as Real * self.cell;
        let mut reached = vec![false; self.dist.len()];
        let mut queue = VecDeque::new();
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let o = &self.open_faces;
                    if (i == 0 && o[0][0])
                        || (j == 0 && o[1][0])
                        || (k == 0 && o[2][0])
                        || (i == nx - 1 && o[0][1])
                        || (j == ny - 1 && o[1][1])
                        || (k == nz - 1 && o[2][1])
                    {
                        let n = self.index(i, j, k);
                        if self.dist[n] >= 0.0 {
                            reached[n] = true;
                            queue.push_back((i, j, k));
                        }
                    }
                }
            }
        }
        while let Some((i, j, k)) = queue.pop_front() {
            let mut visit = |i: usize, j: usize, k: usize| {
                let n = self.index(i, j, k);
                if !reached[n] && self.dist[n] >= 0.0 {
                    reached[n] = true;
                    queue.push_back((i, j, k));
                }
            };
            if i > 0 {
                visit(i - 1, j, k);
            }
            if i + 1 < nx {
                visit(i + 1, j, k);
            }
            if j > 0 {
                visit(i, j - 1, k);
            }
            if j + 1 < ny {
                visit(i, j + 1, k);
            }
            if k > 0 {
                visit(i, j, k - 1);
            }
            if k + 1 < nz {
                visit(i, j, k + 1);
            }
        }
        for n in 0..self.dist.len() {
            if self.dist[n].is_infinite() && reached[n] {
                self.dist[n] = far;
            }
        }
        self.propagate_inside();
    }

    /// Inside nodes beyond the band take the nearest of their neighbours' triangles, in
    /// breadth-first order from the band (closest-point propagation), so a point deep inside still
    /// gets a distance and a direction out. Outside, beyond the band, the bound is enough.
    fn propagate_inside(&mut self) {
        let [nx, ny, nz] = self.dims;
        let mut queue = VecDeque::new();
        let mut pending = vec![false; self.dist.len()];
        let mut done = vec![false; self.dist.len()];
        let band: Vec<bool> = self.face.iter().map(|&f| f != u32::MAX).collect();
        for n in 0..self.dist.len() {
            if self.dist[n] < 0.0 && self.dist[n].is_finite() {
                queue.push_back(n);
            }
        }
        while let Some(n) = queue.pop_front() {
            let f = self.face[n] as usize;
            let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
            let [a, b, c] = self.body.corners(f);
            let mut neighbours = [usize::MAX; 6];
            if i > 0 {
                neighbours[0] = n - 1;
            }
            if i + 1 < nx {
                neighbours[1] = n + 1;
            }
            if j > 0 {
                neighbours[2] = n - nx;
            }
            if j + 1 < ny {
                neighbours[3] = n + nx;
            }
            if k > 0 {
                neighbours[4] = n - nx * ny;
            }
            if k + 1 < nz {
                neighbours[5] = n + nx * ny;
            }
            done[n] = true;
            for m in neighbours {
                // Unset inside nodes, and nodes set by this propagation but not yet passed on.
                if m == usize::MAX || done[m] || !(self.dist[m] == Real::INFINITY || pending[m]) {
                    continue;
                }
                let (mi, mj, mk) = (m % nx, (m / nx) % ny, m / (nx * ny));
                let p = self.node(mi, mj, mk);
                let (q, _) = closest_point_on_triangle(&p, &a, &b, &c);
                let d = -(q - p).norm();
                if self.dist[m] == Real::INFINITY {
                    pending[m] = true;
                    queue.push_back(m);
                } else if d <= self.dist[m] {
                    continue;
                }
                self.dist[m] = d;
                self.face[m] = f as u32;
            }
        }
        // Breadth-first order is not distance order: two sweeps (forward, backward) let each deep
        // node try its neighbours' triangles again.
        let deep: Vec<usize> = (0..self.dist.len())
            .filter(|&n| done[n] && !band[n])
            .collect();
        for pass in 0..2 {
            for idx in 0..deep.len() {
                let n = if pass == 0 {
                    deep[idx]
                } else {
                    deep[deep.len() - 1 - idx]
                };
                let (i, j, k) = (n % nx, (n / nx) % ny, n / (nx * ny));
                let p = self.node(i, j, k);
                let steps = [1, nx, nx * ny];
                for (axis, &step) in steps.iter().enumerate() {
                    let coord = [i, j, k][axis];
                    let lim = self.dims[axis];
                    for m in [
                        (coord > 0).then(|| n - step),
                        (coord + 1 < lim).then(|| n + step),
                    ]
                    .into_iter()
                    .flatten()
                    {
                        let g = self.face[m];
                        if g == u32::MAX || g == self.face[n] || self.dist[m] >= 0.0 {
                            continue;
                        }
                        let [a, b, c] = self.body.corners(g as usize);
                        let d = -(closest_point_on_triangle(&p, &a, &b, &c).0 - p).norm();
                        if d > self.dist[n] {
                            self.dist[n] = d;
                            self.face[n] = g;
                        }
                    }
                }
            }
        }
        // Anything left (a cavity the band does not border) keeps a bound.
        let far = (self.band + 1) as Real * self.cell;
        for d in &mut self.dist {
            if d.is_infinite() {
                *d = -far;
            }
        }
    }

    /// Interpolated signed distance and its gradient at `p`; `None` outside the grid.
    pub fn sample(&self, p: &Vec3) -> Option<(Real, Vec3)> {
        let g = (p - self.origin) / self.cell;
        let mut base = [0usize; 3];
        let mut t = [0.0; 3];
        for a in 0..3 {
            if !(g[a] >= 0.0 && g[a] <= (self.dims[a] - 1) as Real) {
                return None;
            }
            let i = (g[a].floor() as usize).min(self.dims[a] - 2);
            base[a] = i;
            t[a] = g[a] - i as Real;
        }
        let [i, j, k] = base;
        let v = |di: usize, dj: usize, dk: usize| self.dist[self.index(i + di, j + dj, k + dk)];
        let (c000, c100, c010, c110) = (v(0, 0, 0), v(1, 0, 0), v(0, 1, 0), v(1, 1, 0));
        let (c001, c101, c011, c111) = (v(0, 0, 1), v(1, 0, 1), v(0, 1, 1), v(1, 1, 1));
        let [u, w, s] = t;
        let x00 = c000 + (c100 - c000) * u;
        let x10 = c010 + (c110 - c010) * u;
        let x01 = c001 + (c101 - c001) * u;
        let x11 = c011 + (c111 - c011) * u;
        let y0 = x00 + (x10 - x00) * w;
        let y1 = x01 + (x11 - x01) * w;
        let d = y0 + (y1 - y0) * s;
        let dx0 = (c100 - c000) * (1.0 - w) + (c110 - c010) * w;
        let dx1 = (c101 - c001) * (1.0 - w) + (c111 - c011) * w;
        let dy0 = x10 - x00;
        let dy1 = x11 - x01;
        let grad = Vec3::new(
            dx0 * (1.0 - s) + dx1 * s,
            dy0 * (1.0 - s) + dy1 * s,
            y1 - y0,
        ) / self.cell;
        Some((d, grad))
    }

    /// Nearest band triangle to `p` (from the nearest node that has one).
    fn nearest_face(&self, p: &Vec3) -> Option<u32> {
        let g = (p - self.origin) / self.cell;
        let c = [0, 1, 2].map(|a| (g[a].round().max(0.0) as usize).min(self.dims[a] - 1));
        let f = self.face[self.index(c[0], c[1], c[2])];
        if f != u32::MAX {
            return Some(f);
        }
        // The rounded node lies beyond the band: try the cell's corners.
        let b = [0, 1, 2].map(|a| (g[a].floor().max(0.0) as usize).min(self.dims[a] - 2));
        (0..8).find_map(|m| {
            let f = self.face[self.index(b[0] + (m & 1), b[1] + (m >> 1 & 1), b[2] + (m >> 2))];
            (f != u32::MAX).then_some(f)
        })
    }
}

impl Collider for SdfCollider {
    tryon_core::whole_state!();
    fn name(&self) -> &'static str {
        "sdf"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities {
            focus: true,
            ..tryon_core::stages::Capabilities::NONE
        }
    }

    fn update(&mut self, frame: &BodyFrame) {
        // A body that has not moved (a settle, a still pose) keeps its field, unless the cloth
        // came near its edge: the rebuild is most of this collider's cost.
        let same = frame.positions == self.body.positions;
        let outgrown = match (self.region, self.cloth) {
            (Some((rlo, rhi)), Some((clo, chi))) => {
                let s = Vec3::repeat(Self::FOCUS_SLACK);
                (0..3).any(|a| clo[a] - s[a] < rlo[a] || chi[a] + s[a] > rhi[a])
            }
            _ => false,
        };
        if self.body.set_frame(frame).is_ok() && (!same || outgrown) {
            self.rebuild();
        }
    }

    fn focus(&mut self, lo: &Vec3, hi: &Vec3) {
        self.cloth = Some((*lo, *hi));
    }

    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        for (i, p) in points.iter_mut().enumerate() {
            let Some((d, grad)) = self.sample(p) else {
                continue;
            };
            if d >= self.thickness {
                continue;
            }
            let Some(n) = grad.try_normalize(1e-12) else {
                continue;
            };
            *p += n * (self.thickness - d);
            // Deep inside the field is only approximately a distance: step again from where we are.
            for _ in 0..3 {
                match self.sample(p) {
                    Some((d2, g2)) if d2 < self.thickness => match g2.try_normalize(1e-12) {
                        Some(n2) => *p += n2 * (self.thickness - d2),
                        None => break,
                    },
                    _ => break,
                }
            }
            let (face, bary) = match self.nearest_face(p) {
                Some(f) => {
                    let [a, b, c] = self.body.corners(f as usize);
                    (f, closest_point_on_triangle(p, &a, &b, &c).1)
                }
                None => (0, [1.0 / 3.0; 3]),
            };
            contacts.push(Contact {
                point: i as u32,
                face,
                bary,
                normal: n,
                depth: (-d).max(0.0),
                body_velocity: self.body.velocity_at(face as usize, bary),
            });
        }
    }

    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        Some(self.sample(p).map_or(Real::INFINITY, |(d, _)| d))
    }

    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        out.clear();
        out.extend(
            which
                .iter()
                .map(|&k| match self.sample(&points[k as usize]) {
                    Some((d, g)) => Probe {
                        distance: d,
                        normal: g.try_normalize(1e-12).unwrap_or(Vec3::zeros()),
                    },
                    None => Probe::FAR,
                }),
        );
    }
}
