//! P1 section 3.3: collision by nearest-vertex tracking (after Igarashi & Hughes). Every point keeps
//! its nearest body vertex, refreshed each call by a hill-climb from last call's vertex. A point is
//! inside when it is behind every face around that vertex (with a skin of `thickness`), and is then
//! moved onto the nearest of those faces, `thickness` out along its normal. Only points are
//! resolved, never edges (P1: resolving coarse edges distorts the final surface).

use crate::body::{BodyError, BodyMesh};
use crate::swept::SweptBody;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU8, Ordering};
use tryon_core::frames::{BodyFrame, Contact};
use tryon_core::math::{Real, Vec3};

/// How far from its nearest body vertex a point can be and still be tested for being inside a
/// concave crease (m).
const CREASE_REACH: Real = 0.05;

/// How far a point moves before its nearest vertex is checked against the spatial hash again (m).
const RECHECK: Real = 0.005;

/// A neighbour this little in front of a face's plane (relative to its distance) still counts as
/// on the plane when judging whether a fan is convex. A fan that concave is treated as convex, so
/// a point resolved onto it can be left up to about this times its longest edge inside (2.5 um
/// for 2.5 cm edges; CI found 1.05 um). At 1e-6 the real runs' figures moved by the runs' chaos
/// (elegant suit under 10_04: stretch 2.07 -> 3.51, under 131_01: 20 -> 33 mm); the product keeps
/// cloth a thickness (mm) off the body, where micrometres do not show.
pub(crate) const FLAT: Real = 1e-4;

/// Fewest points a thread probes at once.
const PAR_CHUNK: usize = 64;

/// How many times a point is tested and moved out in one `resolve` (folds can need more than one).
const RESOLVE_ROUNDS: usize = 3;

/// Largest clearance a point keeps between `resolve` calls (m).
const MAX_CLEARANCE: Real = 0.01;

/// What P1's test says at one vertex.
enum FanTest {
    /// Behind every face: the face the point is nearest behind and its height over it.
    Inside(u32, Real),
    /// In front of every face: outside whatever the fan's shape. The second value is the height
    /// over the lowest face plane, a lower bound of the distance to the fan.
    Front(Highest, Real),
    /// Behind some faces, in front of others.
    Mixed(Highest),
}

/// A point found inside: the face it is judged against, its height over the surface there
/// (negative inside), the outward normal, and where it goes to be outside.
#[derive(Clone, Copy, serde::Serialize, serde::Deserialize)]
struct Hit {
    face: u32,
    height: Real,
    normal: Vec3,
    target: Vec3,
    /// Moved out of a convex fan: in front of one of its planes, so outside for good.
    settled: bool,
}

/// What the crease test found: inside, outside (with the fan's closest point, and a lower bound
/// of the distance to the fan less the skin, 0 when not known), or nothing (too far from the
/// vertex to judge, or no face).
enum Crease {
    Inside(Hit),
    Outside {
        face: u32,
        closest: Vec3,
        clear: Real,
    },
    Unknown,
}

/// The face whose plane a point is highest above, and that height. Over a convex fan no point of
/// the fan is nearer than this.
#[derive(Clone, Copy, serde::Serialize, serde::Deserialize)]
struct Highest(u32, Real);
use tryon_core::mesh::PolyMesh;
use tryon_core::stages::{Collider, Poke, Probe};

mod fan;
mod opposite;
pub(crate) mod pokes;
mod resolve;

/// Per body vertex whether its fan is convex: 0 not yet known, 1 convex, 2 not. Atomic so that
/// points probed in parallel share it: two threads judging the same fan find the same answer, so
/// the result does not depend on which writes first.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
struct ConvexCache(Vec<AtomicU8>);

impl ConvexCache {
    fn new(n: usize) -> Self {
        ConvexCache((0..n).map(|_| AtomicU8::new(0)).collect())
    }
    fn get(&self, v: u32) -> u8 {
        self.0[v as usize].load(Ordering::Relaxed)
    }
    fn set(&self, v: u32, state: u8) {
        self.0[v as usize].store(state, Ordering::Relaxed);
    }
    fn clear(&mut self) {
        self.0.iter_mut().for_each(|c| *c.get_mut() = 0);
    }
}

impl Clone for ConvexCache {
    fn clone(&self) -> Self {
        ConvexCache(
            self.0
                .iter()
                .map(|c| AtomicU8::new(c.load(Ordering::Relaxed)))
                .collect(),
        )
    }
}

/// P1's nearest-vertex tracking collider.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
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
    /// One vertex of each connected piece of the body when it has more than one (an object on a
    /// table): a hill-climb cannot cross from one piece to another, so each point also keeps a
    /// nearest vertex on every piece (`nearest_more`, pieces fastest).
    extra_pieces: Vec<u32>,
    nearest_more: Vec<u32>,
    /// Index in `extra_pieces` of each vertex's piece (`u32::MAX` for a vertex in no face).
    piece_of: Vec<u32>,
    /// Per body vertex: 0 not yet known, 1 convex fan, 2 not (reset when the body moves).
    fan_convex: ConvexCache,
    /// Per point: where it was last found outside, at which nearest vertex, and its clearance
    /// there: how far it can move with P1's test at that vertex still saying outside (0 = test it
    /// next time). The body does not move between `update`s, so a point whose nearest vertex is
    /// the same and that has moved less than its clearance is still outside, and `resolve` skips
    /// its test. Reset when the body moves; not used on a body in several pieces.
    clear_at: Vec<Vec3>,
    clear_vertex: Vec<u32>,
    clearance: Vec<Real>,
    /// Counts the body's moves. In `probe_near` a point's nearest vertex is checked against the
    /// body's spatial hash ([`BodyMesh::nearest_vertex`]) when the body or the point has moved
    /// since the last check (its climb can stop on another limb only then), else followed by the
    /// climb alone: the hash on every call took the demo's cloth step from 2.4 to 4.2 ms. Per
    /// point: the move count and where the point was at its last check. `resolve` keeps P1's
    /// climb (docs/decisions, *collider: nearest vertex*: projected onto the true nearest part, cloth caught
    /// at an armpit tore).
    moves: u32,
    probe_checked: Vec<(u32, Vec3)>,
    /// The body's last move, for swept collision.
    swept: SweptBody,
    /// Per point, the vertex facing its nearest part across a pinch (`probe_opposite`).
    facing: Vec<opposite::Facing>,
}

impl NearestVertexCollider {
    /// A collider for a body mesh in its current shape.
    pub fn new(mesh: &PolyMesh, thickness: Real) -> Result<Self, BodyError> {
        let body = BodyMesh::new(mesh)?;
        let bounds = body.bounds();
        // A body in several pieces: a track on every piece, since the main track (from the
        // brute-force nearest vertex) can start on any of them.
        let (all, piece_of) = body.pieces();
        let extra_pieces = if all.len() > 1 { all } else { Vec::new() };
        Ok(NearestVertexCollider {
            thickness,
            nearest: Vec::new(),
            cull_margin: 0.05,
            rejected_frames: 0,
            probe_nearest: Vec::new(),
            bounds,
            extra_pieces,
            nearest_more: Vec::new(),
            piece_of,
            fan_convex: ConvexCache::new(body.positions.len()),
            clear_at: Vec::new(),
            clear_vertex: Vec::new(),
            clearance: Vec::new(),
            moves: 0,
            probe_checked: Vec::new(),
            swept: SweptBody::default(),
            facing: Vec::new(),
            body,
        })
    }

    /// The nearest vertex to `p` from `start`: checked against the spatial hash when the body
    /// has moved or the point has gone [`RECHECK`] since its last check (`checked`, updated),
    /// else the climb alone.
    fn follow_nearest(&self, p: &Vec3, start: u32, checked: &mut (u32, Vec3)) -> u32 {
        if checked.0 == self.moves && (p - checked.1).norm_squared() < RECHECK * RECHECK {
            self.body.climb(p, start)
        } else {
            *checked = (self.moves, *p);
            self.body.nearest_vertex(p, start)
        }
    }

    /// Refreshes every point's nearest vertex (hill-climb, or brute force the first time).
    pub fn track(&mut self, points: &[Vec3]) {
        let k = self.extra_pieces.len();
        if self.nearest.len() != points.len() {
            self.nearest = points
                .iter()
                .map(|p| self.body.nearest_vertex_brute(p))
                .collect();
            // Every piece's track starts at the point's nearest vertex on that piece (a climb from
            // some vertex of a non-convex piece can stop on its far side, where the point would
            // look inside).
            self.nearest_more.clear();
            if k > 0 {
                let mut best = vec![(0u32, Real::INFINITY); k];
                for p in points {
                    best.iter_mut().for_each(|b| *b = (0, Real::INFINITY));
                    for (v, q) in self.body.positions.iter().enumerate() {
                        let piece = self.piece_of[v] as usize;
                        let d = (q - p).norm_squared();
                        if piece < k && d < best[piece].1 {
                            best[piece] = (v as u32, d);
                        }
                    }
                    self.nearest_more.extend(best.iter().map(|b| b.0));
                }
            }
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
}

impl Collider for NearestVertexCollider {
    tryon_core::whole_state!();
    fn name(&self) -> &'static str {
        "nearest_vertex"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities {
            pinch: true,
            sweep: true,
            pokes: true,
            ..tryon_core::stages::Capabilities::NONE
        }
    }

    fn update(&mut self, frame: &BodyFrame) {
        // A body that did not move keeps its shape-derived caches.
        let same_shape = frame.positions == self.body.positions;
        if frame.positions.len() == self.body.positions.len() {
            self.swept.moved(&self.body.positions, same_shape);
        }
        if self.body.set_frame(frame).is_err() {
            self.rejected_frames += 1;
            return;
        }
        if !same_shape {
            self.bounds = self.body.bounds();
            self.moves = self.moves.wrapping_add(1) % u32::MAX;
            self.fan_convex.clear();
            self.clearance.iter_mut().for_each(|c| *c = 0.0);
        }
    }

    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        let k = self.extra_pieces.len();
        if self.nearest.len() != points.len() {
            self.track(points);
            self.clearance.clear();
        }
        self.clearance.resize(points.len(), 0.0);
        self.clear_at.resize(points.len(), Vec3::zeros());
        self.clear_vertex.resize(points.len(), u32::MAX);
        let this = &*self;
        let resolved: Vec<Option<resolve::Resolved>> = points
            .par_iter()
            .enumerate()
            .with_min_len(PAR_CHUNK)
            .map(|(i, p)| this.near_bounds(p).then(|| this.resolve_point(i, *p)))
            .collect();
        for (i, r) in resolved.into_iter().enumerate() {
            let Some(r) = r else { continue };
            points[i] = r.p;
            self.nearest[i] = r.nearest;
            self.nearest_more[i * k..(i + 1) * k].copy_from_slice(&r.more);
            (self.clearance[i], self.clear_at[i], self.clear_vertex[i]) = r.clear;
            contacts.extend(r.contact);
        }
    }

    /// `probe_near` with no reach: every outside point gets its distance to its vertex's fan.
    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        self.probe_near(points, which, Real::INFINITY, out);
    }

    /// Tracks each listed point's nearest vertex (hill-climb from its last one), then P1's inside
    /// test there (and the crease test); outside points get their distance to the vertex's fan,
    /// or over a convex fan, when already the height over one of its planes is `reach` or more,
    /// that height (no point of the fan is nearer).
    fn probe_near(&mut self, points: &[Vec3], which: &[u32], reach: Real, out: &mut Vec<Probe>) {
        out.clear();
        if self.probe_nearest.len() != points.len() {
            self.probe_nearest = points
                .iter()
                .map(|p| self.body.nearest_vertex_brute(p))
                .collect();
            self.probe_checked = points.iter().map(|p| (self.moves, *p)).collect();
        }
        // Each point on its own (in parallel), its cache entries written back in order.
        let this = &*self;
        let found: Vec<(Probe, u32, (u32, Vec3))> = which
            .par_iter()
            .with_min_len(PAR_CHUNK)
            .map(|&k| {
                let (k, p) = (k as usize, &points[k as usize]);
                let mut checked = this.probe_checked[k];
                if !this.near_bounds(p) {
                    return (Probe::FAR, this.probe_nearest[k], checked);
                }
                let v = this.follow_nearest(p, this.probe_nearest[k], &mut checked);
                (this.probe_at(p, v, reach), v, checked)
            })
            .collect();
        for (&k, (probe, v, checked)) in which.iter().zip(found) {
            self.probe_nearest[k as usize] = v;
            self.probe_checked[k as usize] = checked;
            out.push(probe);
        }
    }

    fn probe_opposite(
        &mut self,
        points: &[Vec3],
        which: &[u32],
        first: &[Probe],
        reach: Real,
        out: &mut Vec<Probe>,
    ) {
        self.opposites(points, which, first, reach, out);
    }

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

    fn pokes(
        &mut self,
        points: &[Vec3],
        triangles: &[[u32; 3]],
        which: &[u32],
        limits: (Real, Real),
        out: &mut Vec<Poke>,
    ) {
        self.find_pokes(points, triangles, which, limits, out);
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
            || self.inside_crease(p, v, 0.0).is_ok();
        Some(if behind_all { -d } else { d })
    }
}
