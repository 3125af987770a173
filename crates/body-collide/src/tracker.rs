//! P1 section 3.3: collision by nearest-vertex tracking (after Igarashi & Hughes). Every point keeps
//! its nearest body vertex, refreshed each call by a hill-climb from last call's vertex. A point is
//! inside when it is behind every face around that vertex (with a skin of `thickness`), and is then
//! moved onto the nearest of those faces, `thickness` out along its normal. Only points are
//! resolved, never edges (P1: resolving coarse edges distorts the final surface).

use crate::body::{BodyError, BodyMesh};
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3, closest_point_on_triangle};

/// How far from its nearest body vertex a point can be and still be tested for being inside a
/// concave crease (m).
const CREASE_REACH: Real = 0.05;
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Probe};

/// P1's nearest-vertex tracking collider.
#[derive(Clone, Debug)]
pub struct NearestVertexCollider {
    pub body: BodyMesh,
    /// Distance the cloth keeps from the body surface (m).
    pub thickness: Real,
    /// Last known nearest body vertex of each point (empty until the first call).
    pub nearest: Vec<u32>,
    /// Points farther than this outside the body's bounding box are skipped (m).
    pub cull_margin: Real,
    /// Body shape updates rejected for a wrong vertex count.
    pub rejected_frames: u32,
    /// Nearest body vertex of each probed point (`probe` keeps its own cache).
    pub probe_nearest: Vec<u32>,
    bounds: (Vec3, Vec3),
    /// One vertex of each connected piece of the body beyond the first (an object on a table):
    /// a hill-climb cannot cross from one piece to another, so each point also keeps a nearest
    /// vertex on each of these pieces (`nearest_more`, pieces fastest).
    extra_pieces: Vec<u32>,
    nearest_more: Vec<u32>,
}

impl NearestVertexCollider {
    /// A collider for a body mesh in its current shape.
    pub fn new(mesh: &PolyMesh, thickness: Real) -> Result<Self, BodyError> {
        let body = BodyMesh::new(mesh)?;
        let bounds = body.bounds();
        let extra_pieces = pieces(&body).into_iter().skip(1).collect();
        Ok(NearestVertexCollider {
            body,
            thickness,
            nearest: Vec::new(),
            cull_margin: 0.05,
            rejected_frames: 0,
            probe_nearest: Vec::new(),
            bounds,
            extra_pieces,
            nearest_more: Vec::new(),
        })
    }

    /// The nearest vertex of point `i` on each piece: its main track and its other pieces' tracks.
    fn candidates(&self, i: usize) -> impl Iterator<Item = u32> + '_ {
        let k = self.extra_pieces.len();
        std::iter::once(self.nearest[i]).chain(
            self.nearest_more
                .get(i * k..(i + 1) * k)
                .into_iter()
                .flatten()
                .copied(),
        )
    }

    /// Refreshes every point's nearest vertex (hill-climb, or brute force the first time).
    pub fn track(&mut self, points: &[Vec3]) {
        let k = self.extra_pieces.len();
        if self.nearest.len() != points.len() {
            self.nearest = points
                .iter()
                .map(|p| self.body.nearest_vertex_brute(p))
                .collect();
            // The other pieces start from their seed vertex and climb.
            self.nearest_more = points
                .iter()
                .flat_map(|p| {
                    self.extra_pieces
                        .iter()
                        .map(|&s| self.body.climb(p, s))
                        .collect::<Vec<_>>()
                })
                .collect();
            return;
        }
        for (i, p) in points.iter().enumerate() {
            if self.near_bounds(p) {
                self.nearest[i] = self.body.climb(p, self.nearest[i]);
                for j in i * k..(i + 1) * k {
                    self.nearest_more[j] = self.body.climb(p, self.nearest_more[j]);
                }
            }
        }
    }

    #[inline]
    fn near_bounds(&self, p: &Vec3) -> bool {
        let m = self.cull_margin + self.thickness;
        let (lo, hi) = &self.bounds;
        p.x >= lo.x - m
            && p.y >= lo.y - m
            && p.z >= lo.z - m
            && p.x <= hi.x + m
            && p.y <= hi.y + m
            && p.z <= hi.z + m
    }

    /// P1's inside test: behind every face around vertex `v` (offset by the thickness). Returns the
    /// face whose plane the point is nearest behind and the point's height over that plane.
    #[inline]
    fn inside(&self, p: &Vec3, v: u32) -> Option<(u32, Real)> {
        let rel = p - self.body.positions[v as usize];
        let mut best = (u32::MAX, Real::NEG_INFINITY);
        for &f in self.body.vertex_faces.row(v as usize) {
            let h = rel.dot(&self.body.face_normals[f as usize]);
            if h >= self.thickness {
                return None;
            }
            if h > best.1 {
                best = (f, h);
            }
        }
        (best.0 != u32::MAX).then_some(best)
    }

    /// The crease test: P1's test misses points inside a concave crease (shoulder against neck,
    /// arm against torso), where a point can be behind some faces of the fan and in front of
    /// others. Such a point is inside when it is behind the closest point of the fan, judged by the
    /// pseudo-normal there (the face normal, or the mean of the faces sharing the closest edge or
    /// vertex). Returns the face and the point's height over the closest point along that normal.
    fn inside_crease(&self, p: &Vec3, v: u32, skin: Real) -> Option<(u32, Real, Vec3)> {
        if (p - self.body.positions[v as usize]).norm_squared() > CREASE_REACH * CREASE_REACH {
            return None;
        }
        let (f, q, bary) = self.body.closest_on_fan(p, v);
        if f == u32::MAX {
            return None;
        }
        let d2 = (p - q).norm_squared();
        let mut n = self.body.face_normals[f as usize];
        if bary.iter().any(|&b| b < 1e-9) {
            n = Vec3::zeros();
            for &g in self.body.vertex_faces.row(v as usize) {
                let [a, b, c] = self.body.corners(g as usize);
                let (qg, _) = closest_point_on_triangle(p, &a, &b, &c);
                if (p - qg).norm_squared() <= d2 * (1.0 + 1e-9) + 1e-24 {
                    n += self.body.face_normals[g as usize];
                }
            }
            n = n.try_normalize(1e-12)?;
        }
        let h = (p - q).dot(&n);
        (h < skin).then_some((f, h, n))
    }

    /// Barycentric coordinates of `q` (on or near the plane of triangle `f`), clamped into the triangle.
    fn bary(&self, f: u32, q: &Vec3) -> [Real; 3] {
        let [a, b, c] = self.body.corners(f as usize);
        let (e1, e2, r) = (b - a, c - a, q - a);
        let (d11, d12, d22, r1, r2) = (
            e1.dot(&e1),
            e1.dot(&e2),
            e2.dot(&e2),
            r.dot(&e1),
            r.dot(&e2),
        );
        let det = d11 * d22 - d12 * d12;
        if !(det > 0.0) {
            return [1.0 / 3.0; 3];
        }
        let v = ((d22 * r1 - d12 * r2) / det).clamp(0.0, 1.0);
        let w = ((d11 * r2 - d12 * r1) / det).clamp(0.0, 1.0 - v);
        [1.0 - v - w, v, w]
    }
}

impl Collider for NearestVertexCollider {
    fn name(&self) -> &'static str {
        "nearest_vertex"
    }

    fn update(&mut self, frame: &BodyFrame) {
        if self.body.set_frame(frame).is_err() {
            self.rejected_frames += 1;
        }
        self.bounds = self.body.bounds();
    }

    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        self.track(points);
        for (i, p) in points.iter_mut().enumerate() {
            if !self.near_bounds(p) {
                continue;
            }
            // Inside any piece (the shallowest hit when in several).
            let mut hit: Option<(u32, Real, Vec3)> = None;
            for v in self.candidates(i) {
                let h = match self.inside(p, v) {
                    Some((f, h)) => Some((f, h, self.body.face_normals[f as usize])),
                    None => self.inside_crease(p, v, self.thickness),
                };
                if let Some(h) = h
                    && hit.is_none_or(|b| h.1 > b.1)
                {
                    hit = Some(h);
                }
            }
            let Some((f, height, n)) = hit else {
                continue;
            };
            *p += n * (self.thickness - height);
            let bary = self.bary(f, p);
            contacts.push(Contact {
                point: i as u32,
                face: f,
                bary,
                normal: n,
                depth: (-height).max(0.0),
                body_velocity: self.body.velocity_at(f as usize, bary),
            });
        }
    }

    /// Tracks each listed point's nearest vertex (hill-climb from its last one), then P1's inside
    /// test there (and the crease test); outside points get their distance to the vertex's fan.
    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        out.clear();
        if self.probe_nearest.len() != points.len() {
            self.probe_nearest = points
                .iter()
                .map(|p| self.body.nearest_vertex_brute(p))
                .collect();
        }
        for &k in which {
            let p = &points[k as usize];
            if !self.near_bounds(p) {
                out.push(Probe::FAR);
                continue;
            }
            let v = self.body.climb(p, self.probe_nearest[k as usize]);
            self.probe_nearest[k as usize] = v;
            if let Some((f, h)) = self.inside(p, v) {
                out.push(Probe {
                    distance: h,
                    normal: self.body.face_normals[f as usize],
                });
            } else if let Some((_, h, n)) = self.inside_crease(p, v, 0.0) {
                out.push(Probe {
                    distance: h,
                    normal: n,
                });
            } else {
                let (f, q, _) = self.body.closest_on_fan(p, v);
                let d = p - q;
                let n = d.norm();
                out.push(Probe {
                    distance: n,
                    normal: if n > 1e-12 {
                        d / n
                    } else {
                        self.body.face_normals[f as usize]
                    },
                });
            }
        }
    }

    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        let v = self.body.climb(p, self.body.nearest_vertex_brute(p));
        let (_, q, _) = self.body.closest_on_fan(p, v);
        let d = (p - q).norm();
        let x = self.body.positions[v as usize];
        let behind_all = self
            .body
            .vertex_faces
            .row(v as usize)
            .iter()
            .all(|&f| (p - x).dot(&self.body.face_normals[f as usize]) < 0.0)
            || self.inside_crease(p, v, 0.0).is_some();
        Some(if behind_all { -d } else { d })
    }
}

/// One vertex of each connected piece of the body (by the vertex graph), largest piece first.
fn pieces(body: &BodyMesh) -> Vec<u32> {
    let n = body.positions.len();
    let mut seen = vec![false; n];
    let mut found: Vec<(usize, u32)> = Vec::new();
    for start in 0..n {
        if seen[start] || body.vertex_faces.row(start).is_empty() {
            continue;
        }
        seen[start] = true;
        let mut stack = vec![start as u32];
        let mut size = 0;
        while let Some(v) = stack.pop() {
            size += 1;
            for &w in body.ring.row(v as usize) {
                if !seen[w as usize] {
                    seen[w as usize] = true;
                    stack.push(w);
                }
            }
        }
        found.push((size, start as u32));
    }
    found.sort_by_key(|p| std::cmp::Reverse(p.0));
    found.into_iter().map(|(_, v)| v).collect()
}
