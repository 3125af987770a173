//! The exact referee: the closest point on the whole body triangle mesh, found through a bounding
//! volume hierarchy of the triangles (parry3d-f64's `Bvh`), with inside tests by angle-weighted
//! pseudo-normals at the closest feature (Baerentzen and Aanaes 2005). Slow but right; it judges
//! every other collider. The hierarchy is built once and refitted to each new shape (its leaves'
//! boxes updated, its tree kept): rebuilding it every frame was a fifth of the demo's wall time.
//! Its answers are checked against parry's own oriented `TriMesh` queries (tests).
//!
//! As a scene's collider (`body_collision = "exact"`) it also gives the swept test
//! ([`Collider::sweep`], the same [`SweptBody`] as the nearest-vertex collider's), so a particle a
//! fast limb would carry through is stopped. It has no pinch search (`probe_opposite`): one was
//! built and measured, and it stretched the real garments more (docs/decisions.md, session 44).

use crate::body::{BodyError, BodyMesh};
use crate::swept::SweptBody;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Point;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use parry3d_f64::query::PointQuery;
use rayon::prelude::*;
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3, closest_point_on_triangle, is_finite};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Probe};

/// Fewest points a thread probes at once.
const PAR_CHUNK: usize = 64;

/// No face: a border edge's missing neighbour, or no starting face for [`ExactCollider::project_from`].
pub const NONE: u32 = u32::MAX;

/// Exact point-mesh collider (the referee).
#[derive(Clone)]
pub struct ExactCollider {
    pub body: BodyMesh,
    /// Distance the cloth keeps from the body surface (m).
    pub thickness: Real,
    bvh: Bvh,
    /// Per triangle, the triangle across each edge (edge k joins corners k and k + 1), or [`NONE`].
    across: Vec<[u32; 3]>,
    /// Angle-weighted pseudo-normal of each vertex for the current shape (not unit).
    vertex_normals: Vec<Vec3>,
    /// The body's last move, for the swept test.
    swept: SweptBody,
    /// Per probed point, the face found for it last time ([`NONE`] before the first).
    hints: Vec<u32>,
}

impl std::fmt::Debug for ExactCollider {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExactCollider")
            .field("triangles", &self.body.triangles.len())
            .finish()
    }
}

/// Result of an exact query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Signed distance (negative inside).
    pub distance: Real,
    pub point: Vec3,
    pub face: u32,
    pub bary: [Real; 3],
}

/// The box of a triangle (empty for non-finite corners, so it is never visited).
fn triangle_box([a, b, c]: [Vec3; 3]) -> Aabb {
    if !(is_finite(&a) && is_finite(&b) && is_finite(&c)) {
        return Aabb::new_invalid();
    }
    Aabb::new(
        Point::from(a.inf(&b).inf(&c)),
        Point::from(a.sup(&b).sup(&c)),
    )
}

/// For every triangle, the triangle across each of its edges (the first other one found).
fn neighbours(triangles: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut edges: std::collections::HashMap<(u32, u32), (u32, usize)> =
        std::collections::HashMap::with_capacity(triangles.len() * 3);
    let mut across = vec![[NONE; 3]; triangles.len()];
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            match edges.get(&key) {
                Some(&(g, e)) if across[g as usize][e] == NONE => {
                    across[g as usize][e] = f as u32;
                    across[f][k] = g;
                }
                Some(_) => {}
                None => {
                    edges.insert(key, (f as u32, k));
                }
            }
        }
    }
    across
}

impl ExactCollider {
    /// A referee for a body mesh in its current shape.
    pub fn new(mesh: &PolyMesh, thickness: Real) -> Result<Self, BodyError> {
        let body = BodyMesh::new(mesh)?;
        let boxes: Vec<Aabb> = (0..body.triangles.len())
            .map(|f| triangle_box(body.corners(f)))
            .collect();
        let mut c = ExactCollider {
            bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes),
            across: neighbours(&body.triangles),
            vertex_normals: Vec::new(),
            swept: SweptBody::default(),
            hints: Vec::new(),
            body,
            thickness,
        };
        c.pseudo_normals();
        Ok(c)
    }

    /// The vertices' angle-weighted pseudo-normals for the current shape.
    fn pseudo_normals(&mut self) {
        let n = &mut self.vertex_normals;
        n.clear();
        n.resize(self.body.positions.len(), Vec3::zeros());
        for (f, t) in self.body.triangles.iter().enumerate() {
            let c = self.body.corners(f);
            let normal = self.body.face_normals[f];
            for k in 0..3 {
                let (u, v) = (c[(k + 1) % 3] - c[k], c[(k + 2) % 3] - c[k]);
                let angle = u.angle(&v);
                if angle.is_finite() {
                    n[t[k] as usize] += normal * angle;
                }
            }
        }
    }

    /// The outward pseudo-normal at the feature of triangle `f` that `bary` lies on: a corner's
    /// vertex, an edge (the sum of its two faces' normals) or the face.
    fn pseudo_normal(&self, f: u32, bary: [Real; 3]) -> Vec3 {
        let t = self.body.triangles[f as usize];
        let normal = self.body.face_normals[f as usize];
        let on = [bary[0] > 0.0, bary[1] > 0.0, bary[2] > 0.0];
        match on.iter().filter(|&&b| b).count() {
            // One corner: its vertex.
            1 => self.vertex_normals[t[on.iter().position(|&b| b).unwrap_or(0)] as usize],
            // An edge: the corner off it is the zero one; edge k joins corners k and k + 1.
            2 => {
                let off = on.iter().position(|&b| !b).unwrap_or(0);
                match self.across[f as usize][(off + 1) % 3] {
                    NONE => normal,
                    g => normal + self.body.face_normals[g as usize],
                }
            }
            _ => normal,
        }
    }

    /// Closest point on the body surface and signed distance (`None` for a non-finite point or
    /// a body with no triangle).
    pub fn project(&self, p: &Vec3) -> Option<Projection> {
        self.project_from(p, NONE)
    }

    /// [`ExactCollider::project`] starting from face `hint` (a face near `p`, such as the one
    /// found for it last time, or [`NONE`]): the hierarchy is searched only for faces nearer than
    /// that one, which is much of the search when the point has hardly moved.
    pub fn project_from(&self, p: &Vec3, hint: u32) -> Option<Projection> {
        if !is_finite(p) {
            return None;
        }
        let point = Point::from(*p);
        let closest = |f: u32| {
            let [a, b, c] = self.body.corners(f as usize);
            let (q, w) = closest_point_on_triangle(p, &a, &b, &c);
            ((q - p).norm_squared(), (q, w))
        };
        // A hint that gives no finite distance (a face collapsed by the pose) is no start.
        let start = ((hint as usize) < self.body.triangles.len())
            .then(|| (hint, closest(hint)))
            .filter(|(_, (d2, _))| d2.is_finite());
        let bound = start.map_or(Real::INFINITY, |(_, (d2, _))| d2);
        let found = self.bvh.find_best(
            bound,
            |node, _| {
                let d = node.aabb().distance_to_local_point(&point, true);
                d * d
            },
            |f, _| Some(closest(f)),
        );
        let (face, (d2, (q, bary))) = found.or(start)?;
        let d = d2.sqrt();
        let inside = d > 0.0 && (p - q).dot(&self.pseudo_normal(face, bary)) < 0.0;
        Some(Projection {
            distance: if inside { -d } else { d },
            point: q,
            face,
            bary,
        })
    }
}

impl Collider for ExactCollider {
    fn name(&self) -> &'static str {
        "exact"
    }

    fn update(&mut self, frame: &BodyFrame) {
        if frame.positions.len() == self.body.positions.len() {
            let still = frame.positions == self.body.positions;
            self.swept.moved(&self.body.positions, still);
        }
        if self.body.set_frame(frame).is_err() {
            return;
        }
        for f in 0..self.body.triangles.len() {
            let b = triangle_box(self.body.corners(f));
            self.bvh.insert_or_update_partially(b, f as u32, 0.0);
        }
        self.bvh.refit_without_opt();
        self.pseudo_normals();
    }

    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        for (i, p) in points.iter_mut().enumerate() {
            let Some(pr) = self.project(p) else {
                continue;
            };
            if pr.distance >= self.thickness {
                continue;
            }
            let face_n = self.body.face_normals[pr.face as usize];
            let n = if pr.distance < -1e-12 {
                (pr.point - *p) / -pr.distance
            } else if pr.distance > 1e-12 {
                (*p - pr.point) / pr.distance
            } else {
                face_n
            };
            *p = pr.point + n * self.thickness;
            contacts.push(Contact {
                point: i as u32,
                face: pr.face,
                bary: pr.bary,
                normal: n,
                depth: (-pr.distance).max(0.0),
                body_velocity: self.body.velocity_at(pr.face as usize, pr.bary),
            });
        }
    }

    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        self.project(p).map(|pr| pr.distance)
    }

    /// The swept test of [`SweptBody`] against the body's last move.
    fn sweep(
        &mut self,
        start: &[Vec3],
        end: &mut [Vec3],
        span: [Real; 2],
        contacts: &mut Vec<Contact>,
    ) -> bool {
        let skin = self.thickness;
        self.swept
            .sweep(&self.body, start, end, span, skin, contacts);
        true
    }

    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        // Each point on its own, in parallel, from the face found for it last time; collected
        // in order, and the faces kept for next time.
        if self.hints.len() != points.len() {
            self.hints.clear();
            self.hints.resize(points.len(), NONE);
        }
        let this = &*self;
        let found: Vec<(Probe, u32)> = which
            .par_iter()
            .with_min_len(PAR_CHUNK)
            .map(|&k| {
                let p = points[k as usize];
                match this.project_from(&p, this.hints[k as usize]) {
                    Some(pr) => (
                        Probe {
                            distance: pr.distance,
                            normal: if pr.distance.abs() > 1e-12 {
                                (p - pr.point) / pr.distance
                            } else {
                                this.body.face_normals[pr.face as usize]
                            },
                        },
                        pr.face,
                    ),
                    None => (Probe::FAR, NONE),
                }
            })
            .collect();
        out.clear();
        for (&k, (probe, face)) in which.iter().zip(found) {
            self.hints[k as usize] = face;
            out.push(probe);
        }
    }
}

/// How deep each point is inside the body by the referee (0 outside).
pub fn penetration_depths(referee: &ExactCollider, points: &[Vec3]) -> Vec<Real> {
    points
        .iter()
        .map(|p| referee.signed_distance(p).map_or(0.0, |d| (-d).max(0.0)))
        .collect()
}
