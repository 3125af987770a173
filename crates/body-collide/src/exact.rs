//! The exact referee: the closest point on the whole body triangle mesh, found through a bounding
//! volume hierarchy of the triangles ([`FaceTree`]: eight-wide, f32 boxes padded outward, f64
//! triangle tests), with inside tests by angle-weighted pseudo-normals at the closest feature
//! (Baerentzen and Aanaes 2005), made for the corner a query lands on rather than for every vertex
//! at every update. It judges every other collider. The hierarchy is built once and refitted to
//! each new shape. Its answers are checked against parry's own oriented `TriMesh` queries (tests).
//!
//! A caller that needs only the surface within some distance (`probe_near` within the solver's
//! reach, `resolve` within the thickness) gets a search that goes no farther
//! ([`ExactCollider::search`]); what it finds nearer is the whole search's answer.
//!
//! Queries over a point set (`probe`, `resolve`, `signed_distances`) run in parallel and remember
//! what they found: a point asked again where it was, on the same shape of the body, gets the same
//! answer without a search, and any other point starts its search from the face found for it last
//! time. A nearest point on an edge is always taken from the edge's face of lower index, so an
//! answer does not depend on where its search started, to the last bit (test
//! `a_nearest_point_on_an_edge_is_the_same_bits_from_any_starting_face`).
//!
//! As a scene's collider (`body_collision = "exact"`) it also gives the swept test
//! ([`Collider::sweep`], the same [`SweptBody`] as the nearest-vertex collider's), so a particle a
//! fast limb would carry through is stopped. It has no pinch search (`probe_opposite`): one was
//! built and measured, and it stretched the real garments more (docs/decisions, *collider: exact on real scenes*).

mod memo;

pub use memo::Near;

use crate::body::{BodyError, BodyMesh};
use crate::facetree::FaceTree;
use crate::swept::SweptBody;
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3, closest_point_on_triangle, is_finite};
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Poke, Probe};

/// Fewest points a thread probes at once.
const PAR_CHUNK: usize = 64;

/// No face: a border edge's missing neighbour, or no starting face for [`ExactCollider::project_from`].
pub const NONE: u32 = u32::MAX;

/// Exact point-mesh collider (the referee).
#[derive(Clone, serde::Serialize, serde::Deserialize)]
pub struct ExactCollider {
    pub body: BodyMesh,
    /// Distance the cloth keeps from the body surface (m).
    pub thickness: Real,
    tree: FaceTree,
    /// Per triangle, the triangle across each edge (edge k joins corners k and k + 1), or [`NONE`].
    across: Vec<[u32; 3]>,
    /// The body's last move, for the swept test.
    swept: SweptBody,
    /// What was found for recent point sets.
    memos: Vec<memo::Memo>,
    /// Counts the body's changes of shape.
    shape: u64,
}

impl std::fmt::Debug for ExactCollider {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExactCollider")
            .field("triangles", &self.body.triangles.len())
            .finish()
    }
}

/// Result of an exact query.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Projection {
    /// Signed distance (negative inside).
    pub distance: Real,
    pub point: Vec3,
    pub face: u32,
    pub bary: [Real; 3],
}

/// A face's nearest point to a query: squared distance, the point, its barycentric coordinates.
pub(super) type Nearest = (Real, (Vec3, [Real; 3]));

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
        Ok(ExactCollider {
            tree: FaceTree::new(&body.positions, &body.triangles),
            across: neighbours(&body.triangles),
            swept: SweptBody::default(),
            memos: Vec::new(),
            shape: 0,
            body,
            thickness,
        })
    }

    /// Vertex `v`'s angle-weighted pseudo-normal (not unit) for the current shape: its faces'
    /// normals weighted by their corner angles at `v`, summed in face order. Made when a query's
    /// nearest point is that corner, not for every vertex at every update (the angles' `acos`
    /// calls were a tenth of the MakeHuman frame).
    fn vertex_pseudo_normal(&self, v: u32) -> Vec3 {
        let body = &self.body;
        let mut n = Vec3::zeros();
        for &f in body.vertex_faces.row(v as usize) {
            let t = body.triangles[f as usize];
            let c = body.corners(f as usize);
            for k in 0..3 {
                if t[k] != v {
                    continue;
                }
                let angle = (c[(k + 1) % 3] - c[k]).angle(&(c[(k + 2) % 3] - c[k]));
                if angle.is_finite() {
                    n += body.face_normals[f as usize] * angle;
                }
            }
        }
        n
    }

    /// The outward pseudo-normal at the feature of triangle `f` that `bary` lies on: a corner's
    /// vertex, an edge (the sum of its two faces' normals) or the face.
    fn pseudo_normal(&self, f: u32, bary: [Real; 3]) -> Vec3 {
        let t = self.body.triangles[f as usize];
        let normal = self.body.face_normals[f as usize];
        let on = [bary[0] > 0.0, bary[1] > 0.0, bary[2] > 0.0];
        match on.iter().filter(|&&b| b).count() {
            // One corner: its vertex.
            1 => self.vertex_pseudo_normal(t[on.iter().position(|&b| b).unwrap_or(0)]),
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

    /// A nearest point on an edge is found on either face of the edge, by rounding at slightly
    /// different places; it is always taken from the face of lower index, so the answer does not
    /// depend on where the search started or on the hierarchy's order. (On a corner the point
    /// is the vertex itself, whichever face found it.)
    fn on_lower_face(
        &self,
        face: u32,
        found: Nearest,
        closest: impl Fn(u32) -> Nearest,
    ) -> (u32, Nearest) {
        let bary = found.1.1;
        let on = bary.map(|b| b > 0.0);
        if on.iter().filter(|&&b| b).count() != 2 {
            return (face, found);
        }
        let off = on.iter().position(|&b| !b).unwrap_or(0);
        match self.across[face as usize][(off + 1) % 3] {
            g if g != NONE && g < face => {
                let other = closest(g);
                if other.0.is_finite() {
                    (g, other)
                } else {
                    (face, found)
                }
            }
            _ => (face, found),
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
        match self.search(p, hint, Real::INFINITY) {
            Near::Found(pr) => Some(pr),
            _ => None,
        }
    }

    /// [`ExactCollider::project_from`] for a caller that only needs the surface nearer than
    /// `cutoff`: the hierarchy is searched that far first. A point with nothing within `cutoff`
    /// is searched in full, since only its nearest feature's pseudo-normal tells its side: it
    /// is [`Near::Beyond`] when outside, found when inside (so a point deep inside is found
    /// whatever its hint). The answer is the whole search's, with outside points farther than
    /// `cutoff` reported as beyond it (callers skip far points by the memo's bound first).
    pub fn search(&self, p: &Vec3, hint: u32, cutoff: Real) -> Near {
        if !is_finite(p) {
            return Near::Invalid;
        }
        let closest = |f: u32| self.nearest_on(p, f);
        // A hint that gives no finite distance (a face collapsed by the pose) is no start.
        let start = ((hint as usize) < self.body.triangles.len())
            .then(|| (hint, closest(hint)))
            .filter(|(_, (d2, _))| d2.is_finite());
        let hint_d2 = start.map_or(Real::INFINITY, |(_, (d2, _))| d2);
        let bound = hint_d2.min(cutoff * cutoff);
        let found = self.tree.nearest(p, bound, closest);
        let best = found.or(start.filter(|_| hint_d2 < cutoff * cutoff));
        let Some((face, nearest)) = best else {
            // Nothing within the cutoff: the side is known only from the nearest feature (a
            // pseudo-normal says which side a point is on only at the point's nearest feature;
            // the hint's face, from where the point was, said "outside" for a refined kimono
            // vertex 32 mm inside the body), so the whole body is searched.
            if !cutoff.is_finite() {
                return Near::Invalid;
            }
            return match self.search(p, hint, Real::INFINITY) {
                Near::Found(pr) if pr.distance >= cutoff => Near::Beyond(cutoff),
                other => other,
            };
        };
        Near::Found(self.finish(p, face, nearest))
    }

    /// Face `f`'s nearest point to `p`: squared distance, the point, its barycentric coordinates.
    pub(super) fn nearest_on(&self, p: &Vec3, f: u32) -> Nearest {
        let [a, b, c] = self.body.corners(f as usize);
        let (q, w) = closest_point_on_triangle(p, &a, &b, &c);
        ((q - p).norm_squared(), (q, w))
    }

    /// The projection of `p` whose nearest face is `face`: the edge's lower face taken, and the
    /// sign from the pseudo-normal at the feature.
    pub(super) fn finish(&self, p: &Vec3, face: u32, nearest: Nearest) -> Projection {
        let closest = |f: u32| self.nearest_on(p, f);
        let (face, (d2, (q, bary))) = self.on_lower_face(face, nearest, closest);
        let d = d2.sqrt();
        let inside = d > 0.0 && (p - q).dot(&self.pseudo_normal(face, bary)) < 0.0;
        Projection {
            distance: if inside { -d } else { d },
            point: q,
            face,
            bary,
        }
    }
}

impl Collider for ExactCollider {
    tryon_core::whole_state!();
    fn name(&self) -> &'static str {
        "exact"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities {
            sweep: true,
            pokes: true,
            exact_distance: true,
            ..tryon_core::stages::Capabilities::NONE
        }
    }

    fn update(&mut self, frame: &BodyFrame) {
        if frame.positions.len() == self.body.positions.len() {
            let still = frame.positions == self.body.positions;
            self.swept.moved(&self.body.positions, still);
        }
        // A new shape, even if taking it fails part-way: nothing found before is reused.
        self.shape += 1;
        if self.body.set_frame(frame).is_err() {
            return;
        }
        self.tree.refit(&self.body.positions, &self.body.triangles);
    }

    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        // Only points nearer than the thickness move: the search goes no farther.
        let found = self.project_all(points, None, self.thickness);
        for (i, (p, near)) in points.iter_mut().zip(found).enumerate() {
            let Near::Found(pr) = near else {
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

    /// The walk of the nearest-vertex collider's `pokes`, started for each corner from the
    /// corner of the face found for it at its last probe that is nearest to it (nothing for a
    /// point never probed).
    fn pokes(
        &mut self,
        points: &[Vec3],
        triangles: &[[u32; 3]],
        which: &[u32],
        limits: (Real, Real),
        out: &mut Vec<Poke>,
    ) {
        let memo = self.take_memo(points.len());
        let nearest: Vec<u32> = memo
            .found
            .iter()
            .map(|pr| match pr {
                Some(pr) => {
                    let k = (0..3).fold(0, |a, k| if pr.bary[k] > pr.bary[a] { k } else { a });
                    self.body.triangles[pr.face as usize][k]
                }
                None => NONE,
            })
            .collect();
        let cloth = (points, triangles, which);
        crate::tracker::pokes::pokes_from(&self.body, &nearest, cloth, limits, out);
        self.put_memo(memo);
    }

    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        self.probe_near(points, which, Real::INFINITY, out);
    }

    /// Each point on its own, in parallel, from the face found for it last time, searched no
    /// farther than `reach` ([`ExactCollider::search`]); collected in order, and the faces kept
    /// for next time. A point with no surface within `reach` gets `reach` as its distance.
    fn probe_near(&mut self, points: &[Vec3], which: &[u32], reach: Real, out: &mut Vec<Probe>) {
        let found = self.project_all(points, Some(which), reach);
        out.clear();
        out.extend(which.iter().zip(found).map(|(&k, near)| match near {
            Near::Found(pr) => Probe {
                distance: pr.distance,
                normal: if pr.distance.abs() > 1e-12 {
                    (points[k as usize] - pr.point) / pr.distance
                } else {
                    self.body.face_normals[pr.face as usize]
                },
            },
            Near::Beyond(d) => Probe {
                distance: d,
                normal: Vec3::zeros(),
            },
            Near::Invalid => Probe::FAR,
        }));
    }
}

/// How deep each point is inside the body by the referee (0 outside).
pub fn penetration_depths(referee: &ExactCollider, points: &[Vec3]) -> Vec<Real> {
    points
        .iter()
        .map(|p| referee.signed_distance(p).map_or(0.0, |d| (-d).max(0.0)))
        .collect()
}
