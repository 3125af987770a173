//! P4's collider: the body rendered from six cameras (+x, -x, +y, -y, +z, -z) into depth and normal
//! buffers, on the CPU.
//!
//! Each camera is orthographic and looks at the body's bounds along one axis; a pixel keeps the
//! surface point nearest the camera (its coordinate along the axis), the normal of the triangle seen
//! there (a face's plane supports a convex body, so one push along it gets a point out), and the triangle and barycentric coordinates (for contacts). A point is inside when, on
//! all three axes, it lies between the surfaces the two opposite cameras see through its pixel (a
//! pixel that sees nothing means outside). An inside point is moved out along the stored normal of
//! the view whose tangent plane is nearest, as P4 does. The buffers are re-rendered at every
//! [`Collider::update`] (once for a static object).
//!
//! What six depth maps cannot see, they cannot resolve: a pocket hidden from all six directions
//! (between an arm and the torso, under the chin) counts as inside. The report measures this.

use crate::body::{BodyError, BodyMesh};
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Probe};

/// One orthographic view along an axis.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
struct View {
    /// Axis looked along (0 = x, 1 = y, 2 = z).
    axis: usize,
    /// +1: the camera sits on the +axis side (keeps the largest coordinate); -1: the -axis side.
    side: Real,
    /// Coordinate along the axis of the visible surface (NaN where nothing is seen).
    depth: Vec<Real>,
    normal: Vec<Vec3>,
    face: Vec<u32>,
    bary: Vec<[Real; 3]>,
}

/// Six-view depth-map collider (P4).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct DepthMapCollider {
    pub body: BodyMesh,
    /// Distance the cloth keeps from the body surface (m).
    pub thickness: Real,
    /// Pixels along the longest side of the body's bounds.
    pub resolution: usize,
    origin: Vec3,
    pixel: Real,
    /// Pixels along x, y and z (each view uses the two axes other than its own).
    size: [usize; 3],
    views: [View; 6],
}

/// The two image axes of a view along `axis`.
#[inline]
fn image_axes(axis: usize) -> (usize, usize) {
    ((axis + 1) % 3, (axis + 2) % 3)
}

/// One view's answer for a point: the visible surface along the pixel's ray.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct Hit {
    depth: Real,
    normal: Vec3,
    face: u32,
    bary: [Real; 3],
}

impl DepthMapCollider {
    /// Pixels along the body's longest side unless a scene says otherwise.
    pub const DEFAULT_RESOLUTION: usize = 256;

    /// Six views of `resolution` pixels along the body's longest side.
    pub fn new(mesh: &PolyMesh, thickness: Real, resolution: usize) -> Result<Self, BodyError> {
        let mut views: [View; 6] = Default::default();
        for (v, view) in views.iter_mut().enumerate() {
            view.axis = v / 2;
            view.side = if v % 2 == 0 { 1.0 } else { -1.0 };
        }
        let mut c = DepthMapCollider {
            body: BodyMesh::new(mesh)?,
            thickness,
            resolution: resolution.max(8),
            origin: Vec3::zeros(),
            pixel: 1.0,
            size: [0; 3],
            views,
        };
        c.render();
        Ok(c)
    }

    /// Edge length of a pixel (m).
    pub fn pixel_size(&self) -> Real {
        self.pixel
    }

    fn render(&mut self) {
        let (lo, hi) = self.body.bounds();
        let extent = (hi - lo).max().max(1e-6);
        self.pixel = extent / self.resolution as Real;
        self.origin = lo - Vec3::repeat(self.pixel);
        self.size = [0, 1, 2].map(|a| ((hi[a] - lo[a]) / self.pixel).ceil() as usize + 2);
        for v in 0..6 {
            let (ua, va) = image_axes(self.views[v].axis);
            let n = self.size[ua] * self.size[va];
            let view = &mut self.views[v];
            view.depth.clear();
            view.depth.resize(n, Real::NAN);
            view.normal.clear();
            view.normal.resize(n, Vec3::zeros());
            view.face.clear();
            view.face.resize(n, u32::MAX);
            view.bary.clear();
            view.bary.resize(n, [0.0; 3]);
            self.rasterise(v);
        }
    }

    /// Z-buffers every body triangle into view `v`, sampling at pixel centres.
    fn rasterise(&mut self, v: usize) {
        let axis = self.views[v].axis;
        let side = self.views[v].side;
        let (ua, va) = image_axes(axis);
        let (w, h) = (self.size[ua], self.size[va]);
        let inv = 1.0 / self.pixel;
        for f in 0..self.body.triangles.len() {
            let p = self.body.corners(f);
            // Pixel coordinates (continuous; pixel (i, j) has its centre at i + 0.5, j + 0.5).
            let uv = p.map(|q| {
                (
                    (q[ua] - self.origin[ua]) * inv,
                    (q[va] - self.origin[va]) * inv,
                )
            });
            let area = (uv[1].0 - uv[0].0) * (uv[2].1 - uv[0].1)
                - (uv[2].0 - uv[0].0) * (uv[1].1 - uv[0].1);
            if area.abs() < 1e-12 {
                continue;
            }
            let umin = uv.iter().map(|q| q.0).fold(Real::INFINITY, Real::min);
            let umax = uv.iter().map(|q| q.0).fold(Real::NEG_INFINITY, Real::max);
            let vmin = uv.iter().map(|q| q.1).fold(Real::INFINITY, Real::min);
            let vmax = uv.iter().map(|q| q.1).fold(Real::NEG_INFINITY, Real::max);
            let i0 = (umin - 0.5).ceil().max(0.0) as usize;
            let i1 = ((umax - 0.5).floor().max(-1.0) + 1.0) as usize;
            let j0 = (vmin - 0.5).ceil().max(0.0) as usize;
            let j1 = ((vmax - 0.5).floor().max(-1.0) + 1.0) as usize;
            let inv_area = 1.0 / area;
            for j in j0..j1.min(h) {
                let y = j as Real + 0.5;
                for i in i0..i1.min(w) {
                    let x = i as Real + 0.5;
                    let edge = |a: usize, b: usize| {
                        (uv[b].0 - uv[a].0) * (y - uv[a].1) - (uv[b].1 - uv[a].1) * (x - uv[a].0)
                    };
                    let b0 = edge(1, 2) * inv_area;
                    let b1 = edge(2, 0) * inv_area;
                    let b2 = edge(0, 1) * inv_area;
                    if b0 < 0.0 || b1 < 0.0 || b2 < 0.0 {
                        continue;
                    }
                    let d = p[0][axis] * b0 + p[1][axis] * b1 + p[2][axis] * b2;
                    let px = i + w * j;
                    let view = &mut self.views[v];
                    let old = view.depth[px];
                    if old.is_nan() || (d - old) * side > 0.0 {
                        view.depth[px] = d;
                        view.normal[px] = self.body.face_normals[f];
                        view.face[px] = f as u32;
                        view.bary[px] = [b0, b1, b2];
                    }
                }
            }
        }
    }

    /// What view `v` sees through the pixel containing `p`.
    #[inline]
    fn look(&self, v: usize, p: &Vec3) -> Option<Hit> {
        let view = &self.views[v];
        let (ua, va) = image_axes(view.axis);
        let x = (p[ua] - self.origin[ua]) / self.pixel;
        let y = (p[va] - self.origin[va]) / self.pixel;
        if !(x >= 0.0 && y >= 0.0) {
            return None;
        }
        let (i, j) = (x as usize, y as usize);
        if i >= self.size[ua] || j >= self.size[va] {
            return None;
        }
        let px = i + self.size[ua] * j;
        let depth = view.depth[px];
        (!depth.is_nan()).then(|| Hit {
            depth,
            normal: view.normal[px],
            face: view.face[px],
            bary: view.bary[px],
        })
    }

    /// Signed distance estimate, outward normal and the hit it came from.
    fn query(&self, p: &Vec3) -> Option<(Real, Vec3, Hit)> {
        let mut inside = true;
        let mut hits: [Option<Hit>; 6] = [None; 6];
        for a in 0..3 {
            let front = self.look(2 * a, p);
            let back = self.look(2 * a + 1, p);
            match (front, back) {
                (Some(f), Some(b)) if p[a] <= f.depth && p[a] >= b.depth => {}
                _ => inside = false,
            }
            hits[2 * a] = front;
            hits[2 * a + 1] = back;
        }
        // Distance to each seen surface's tangent plane: |n_axis| times the gap along the axis.
        let mut best: Option<(Real, Vec3, Hit)> = None;
        for (v, hit) in hits.iter().enumerate() {
            let Some(h) = hit else { continue };
            let view = &self.views[v];
            let gap = (p[view.axis] - h.depth) * view.side; // > 0: in front of the surface
            if inside == (gap > 0.0) {
                continue;
            }
            let plane = gap.abs() * h.normal[view.axis].abs();
            if best.is_none_or(|b| plane < b.0.abs()) {
                let d = if inside { -plane } else { plane };
                best = Some((d, h.normal, *h));
            }
        }
        best
    }
}

impl Collider for DepthMapCollider {
    tryon_core::whole_state!();
    fn name(&self) -> &'static str {
        "depth_maps"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities::NONE
    }

    fn update(&mut self, frame: &BodyFrame) {
        if self.body.set_frame(frame).is_ok() {
            self.render();
        }
    }

    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        for (i, p) in points.iter_mut().enumerate() {
            let Some((d, n, hit)) = self.query(p) else {
                continue;
            };
            if d >= self.thickness {
                continue;
            }
            *p += n * (self.thickness - d);
            // A tangent plane seen at a grazing angle can under-estimate the depth: look again.
            for _ in 0..3 {
                match self.query(p) {
                    Some((d2, n2, _)) if d2 < self.thickness => *p += n2 * (self.thickness - d2),
                    _ => break,
                }
            }
            contacts.push(Contact {
                point: i as u32,
                face: hit.face,
                bary: hit.bary,
                normal: n,
                depth: (-d).max(0.0),
                body_velocity: self.body.velocity_at(hit.face as usize, hit.bary),
            });
        }
    }

    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        Some(self.query(p).map_or(Real::INFINITY, |q| q.0))
    }

    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        out.clear();
        out.extend(
            which
                .iter()
                .map(|&k| match self.query(&points[k as usize]) {
                    Some((d, n, _)) => Probe {
                        distance: d,
                        normal: n,
                    },
                    None => Probe::FAR,
                }),
        );
    }
}
