//! The exact referee: closest point on the whole body triangle mesh via parry3d-f64, with inside
//! tests by angle-weighted pseudo-normals. Slow but right; it judges every other collider.

use crate::body::{BodyError, BodyMesh};
use parry3d_f64::math::Point;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{TriMesh, TriMeshFlags, TrianglePointLocation};
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Probe};

/// Exact point-mesh collider (the referee).
#[derive(Clone)]
pub struct ExactCollider {
    pub body: BodyMesh,
    /// Distance the cloth keeps from the body surface (m).
    pub thickness: Real,
    shape: Option<TriMesh>,
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

impl ExactCollider {
    /// A referee for a body mesh in its current shape.
    pub fn new(mesh: &PolyMesh, thickness: Real) -> Result<Self, BodyError> {
        let mut c = ExactCollider {
            body: BodyMesh::new(mesh)?,
            thickness,
            shape: None,
        };
        c.rebuild();
        Ok(c)
    }

    fn rebuild(&mut self) {
        let pts: Vec<Point<Real>> = self
            .body
            .positions
            .iter()
            .map(|p| Point::from(*p))
            .collect();
        self.shape =
            TriMesh::with_flags(pts, self.body.triangles.clone(), TriMeshFlags::ORIENTED).ok();
    }

    /// Closest point on the body surface and signed distance (`None` for a non-finite point).
    pub fn project(&self, p: &Vec3) -> Option<Projection> {
        if !tryon_core::math::is_finite(p) {
            return None;
        }
        let shape = self.shape.as_ref()?;
        let (proj, (face, loc)) =
            shape.project_local_point_and_get_location(&Point::from(*p), false);
        let point = proj.point.coords;
        let d = (point - p).norm();
        let bary = match loc {
            TrianglePointLocation::OnVertex(i) => {
                let mut b = [0.0; 3];
                b[i as usize] = 1.0;
                b
            }
            TrianglePointLocation::OnEdge(i, [u, v]) => {
                let mut b = [0.0; 3];
                b[i as usize] = u;
                b[(i as usize + 1) % 3] = v;
                b
            }
            TrianglePointLocation::OnFace(_, b) => b,
            TrianglePointLocation::OnSolid => [1.0 / 3.0; 3],
        };
        Some(Projection {
            distance: if proj.is_inside { -d } else { d },
            point,
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
        if self.body.set_frame(frame).is_ok() {
            self.rebuild();
        }
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

    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        out.clear();
        for &k in which {
            let p = points[k as usize];
            out.push(match self.project(&p) {
                Some(pr) => Probe {
                    distance: pr.distance,
                    normal: if pr.distance.abs() > 1e-12 {
                        (p - pr.point) / pr.distance
                    } else {
                        self.body.face_normals[pr.face as usize]
                    },
                },
                None => Probe::FAR,
            });
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
