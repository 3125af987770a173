//! The exact referee: the closest point on the whole body triangle mesh, found through a bounding
//! volume hierarchy of the triangles (parry3d-f64's `Bvh`), with inside tests by angle-weighted
//! pseudo-normals at the closest feature (Baerentzen and Aanaes 2005). Slow but right; it judges
//! every other collider. The hierarchy is built once and refitted to each new shape (its leaves'
//! boxes updated, its tree kept): rebuilding it every frame was a fifth of the demo's wall time.
//! Its answers are checked against parry's own oriented `TriMesh` queries (tests).
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
use tryon_core::stages::{Collider, Poke, Probe};

/// Fewest points a thread probes at once.
const PAR_CHUNK: usize = 64;

/// No face: a border edge's missing neighbour, or no starting face for [`ExactCollider::project_from`].
pub const NONE: u32 = u32::MAX;

/// What was found is kept for this many point sets (told apart by their length): a scene probes
/// its coarse particles and its fine vertices in turn, and each keeps its own.
const MEMO_SETS: usize = 4;

/// What was found for the points of one set: per point, where it was queried, on which shape of
/// the body ([`ExactCollider::shape`]), and the projection. A point queried again where it was,
/// on the same shape, gets the same answer without a search (the cloth solver probes its
/// particles where the last step's fail-safe left them); any other starts its search from the
/// face found last time.
#[derive(Clone, Default, serde::Serialize, serde::Deserialize)]
struct Memo {
    at: Vec<Vec3>,
    shape: Vec<u64>,
    found: Vec<Option<Projection>>,
}

impl Memo {
    fn new(n: usize) -> Self {
        Memo {
            at: vec![Vec3::repeat(Real::NAN); n],
            shape: vec![u64::MAX; n],
            found: vec![None; n],
        }
    }
}

/// Exact point-mesh collider (the referee).
#[derive(Clone, serde::Serialize, serde::Deserialize)]
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
    /// What was found for recent point sets.
    memos: Vec<Memo>,
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
type Nearest = (Real, (Vec3, [Real; 3]));

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
            memos: Vec::new(),
            shape: 0,
            body,
            thickness,
        };
        c.pseudo_normals();
        Ok(c)
    }

    /// The vertices' angle-weighted pseudo-normals for the current shape: each face's corner
    /// angles found in parallel, summed into the vertices in face order (the same sums on any
    /// thread count).
    fn pseudo_normals(&mut self) {
        let body = &self.body;
        let angles: Vec<[Real; 3]> = (0..body.triangles.len())
            .into_par_iter()
            .with_min_len(PAR_CHUNK * 4)
            .map(|f| {
                let c = body.corners(f);
                std::array::from_fn(|k| (c[(k + 1) % 3] - c[k]).angle(&(c[(k + 2) % 3] - c[k])))
            })
            .collect();
        let n = &mut self.vertex_normals;
        n.clear();
        n.resize(body.positions.len(), Vec3::zeros());
        for ((t, normal), angle) in body.triangles.iter().zip(&body.face_normals).zip(angles) {
            for k in 0..3 {
                if angle[k].is_finite() {
                    n[t[k] as usize] += normal * angle[k];
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
        let (face, (d2, (q, bary))) = self.on_lower_face(face, (d2, (q, bary)), closest);
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

impl ExactCollider {
    /// The memo of point sets of `n` points, taken out (put back with `put_memo`); a new set
    /// has none, and the oldest is dropped when [`MEMO_SETS`] are kept.
    fn take_memo(&mut self, n: usize) -> Memo {
        match self.memos.iter().position(|m| m.at.len() == n) {
            Some(k) => self.memos.remove(k),
            None => Memo::new(n),
        }
    }

    fn put_memo(&mut self, memo: Memo) {
        if self.memos.len() >= MEMO_SETS {
            self.memos.remove(0);
        }
        self.memos.push(memo);
    }

    /// Each listed point's projection (all points for `None`), in parallel: the memo's answer for
    /// a point queried at the same place on the same shape, else a search from the face found
    /// for it last time (the same answer from any start, to the bit: `on_lower_face`).
    fn project_all(&mut self, points: &[Vec3], which: Option<&[u32]>) -> Vec<Option<Projection>> {
        let mut memo = self.take_memo(points.len());
        let (this, m) = (&*self, &memo);
        let one = |k: usize| {
            let p = &points[k];
            let same =
                m.shape[k] == this.shape && (0..3).all(|a| p[a].to_bits() == m.at[k][a].to_bits());
            if same {
                m.found[k]
            } else {
                this.project_from(p, m.found[k].map_or(NONE, |f| f.face))
            }
        };
        let found: Vec<Option<Projection>> = match which {
            Some(w) => w
                .par_iter()
                .with_min_len(PAR_CHUNK)
                .map(|&k| one(k as usize))
                .collect(),
            None => (0..points.len())
                .into_par_iter()
                .with_min_len(PAR_CHUNK)
                .map(one)
                .collect(),
        };
        for (j, pr) in found.iter().enumerate() {
            let k = which.map_or(j, |w| w[j] as usize);
            (memo.at[k], memo.shape[k], memo.found[k]) = (points[k], self.shape, *pr);
        }
        self.put_memo(memo);
        found
    }

    /// Signed distances of all `points` (`None` where there is none), as
    /// [`Collider::signed_distance`] gives them, found from the faces of the last call for a set
    /// of this length: the referee's per-frame query.
    pub fn signed_distances(&mut self, points: &[Vec3]) -> Vec<Option<Real>> {
        self.project_all(points, None)
            .into_iter()
            .map(|pr| pr.map(|pr| pr.distance))
            .collect()
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
        for f in 0..self.body.triangles.len() {
            let b = triangle_box(self.body.corners(f));
            self.bvh.insert_or_update_partially(b, f as u32, 0.0);
        }
        self.bvh.refit_without_opt();
        self.pseudo_normals();
    }

    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        let found = self.project_all(points, None);
        for (i, (p, pr)) in points.iter_mut().zip(found).enumerate() {
            let Some(pr) = pr else {
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
        // Each point on its own, in parallel, from the face found for it last time; collected
        // in order, and the faces kept for next time.
        let found = self.project_all(points, Some(which));
        out.clear();
        out.extend(which.iter().zip(found).map(|(&k, pr)| match pr {
            Some(pr) => Probe {
                distance: pr.distance,
                normal: if pr.distance.abs() > 1e-12 {
                    (points[k as usize] - pr.point) / pr.distance
                } else {
                    self.body.face_normals[pr.face as usize]
                },
            },
            None => Probe::FAR,
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
