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

/// How far a point moves before its nearest vertex is checked against the spatial hash again (m).
const RECHECK: Real = 0.005;

/// A neighbour this little in front of a face's plane (relative to its distance) still counts as
/// on the plane when judging whether a fan is convex.
const FLAT: Real = 1e-4;

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
#[derive(Clone, Copy)]
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
#[derive(Clone, Copy)]
struct Highest(u32, Real);
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
    /// One vertex of each connected piece of the body when it has more than one (an object on a
    /// table): a hill-climb cannot cross from one piece to another, so each point also keeps a
    /// nearest vertex on every piece (`nearest_more`, pieces fastest).
    extra_pieces: Vec<u32>,
    nearest_more: Vec<u32>,
    /// Index in `extra_pieces` of each vertex's piece (`u32::MAX` for a vertex in no face).
    piece_of: Vec<u32>,
    /// Per body vertex: 0 not yet known, 1 convex fan, 2 not (reset when the body moves).
    fan_convex: Vec<std::cell::Cell<u8>>,
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
    /// climb (docs/decisions.md, 2026-11-23: projected onto the true nearest part, cloth caught
    /// at an armpit tore).
    moves: u32,
    probe_checked: Vec<(u32, Vec3)>,
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
            fan_convex: vec![std::cell::Cell::new(0); body.positions.len()],
            clear_at: Vec::new(),
            clear_vertex: Vec::new(),
            clearance: Vec::new(),
            moves: 0,
            probe_checked: Vec::new(),
            body,
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

    /// P1's inside test at vertex `v` (offset by the thickness): inside when behind every face of
    /// the fan (with the face whose plane the point is nearest behind and its height over it),
    /// outside for sure when in front of every face, and undecided when behind some and in front
    /// of others (a convex fan says outside then; a concave one needs the crease test).
    #[inline]
    fn fan_test(&self, p: &Vec3, v: u32) -> FanTest {
        let rel = p - self.body.positions[v as usize];
        let mut best = (u32::MAX, Real::NEG_INFINITY);
        let mut top = Highest(u32::MAX, Real::NEG_INFINITY);
        let mut front = 0usize;
        let mut lowest = Real::INFINITY;
        let faces = self.body.vertex_faces.row(v as usize);
        for &f in faces {
            let h = rel.dot(&self.body.face_normals[f as usize]);
            if h > top.1 {
                top = Highest(f, h);
            }
            lowest = lowest.min(h);
            if h >= self.thickness {
                front += 1;
            } else if h > best.1 {
                best = (f, h);
            }
        }
        if front == 0 && best.0 != u32::MAX {
            FanTest::Inside(best.0, best.1)
        } else if front == faces.len() {
            FanTest::Front(top, lowest)
        } else {
            FanTest::Mixed(top)
        }
    }

    /// Whether the fan of faces around `v` bounds a convex cone (every neighbour on or behind
    /// every face's plane), cached until the body moves. Behind part of a convex fan is outside.
    fn fan_is_convex(&self, v: u32) -> bool {
        let cell = &self.fan_convex[v as usize];
        match cell.get() {
            1 => return true,
            2 => return false,
            _ => {}
        }
        let x = self.body.positions[v as usize];
        let convex = self.body.vertex_faces.row(v as usize).iter().all(|&f| {
            let n = self.body.face_normals[f as usize];
            self.body.ring.row(v as usize).iter().all(|&w| {
                let r = self.body.positions[w as usize] - x;
                r.dot(&n) <= FLAT * r.norm()
            })
        });
        cell.set(if convex { 1 } else { 2 });
        convex
    }

    /// P1's test, with the crease test where the fan is not convex: whether `p` is inside near
    /// vertex `v`, and where to move it. Over a convex fan P1's push along the nearest plane's
    /// normal is exact; in a fold it can land the point behind the fold's other side, so there the
    /// point goes to the closest point of the fan, `skin` out along the pseudo-normal.
    ///
    /// A point found outside gets `Err(clearance)`: a lower bound of its distance to the fan less
    /// `skin` (0 when unknown).
    #[inline]
    fn inside_any(&self, p: &Vec3, v: u32, skin: Real) -> Result<Hit, Real> {
        match self.fan_test(p, v) {
            FanTest::Inside(f, h) => {
                let n = self.body.face_normals[f as usize];
                let convex = self.fan_is_convex(v);
                let p1 = Hit {
                    face: f,
                    height: h,
                    normal: n,
                    target: p + n * (skin - h),
                    settled: convex,
                };
                if convex {
                    Ok(p1)
                } else {
                    Ok(self.inside_crease(p, v, skin).ok().unwrap_or(p1))
                }
            }
            // Over a convex fan the height over the highest plane bounds the distance from below;
            // over any fan, the height over the lowest (the point is in front of every face).
            FanTest::Front(top, lowest) => Err(if self.fan_is_convex(v) {
                top.1 - skin
            } else {
                lowest - skin
            }),
            FanTest::Mixed(top) if self.fan_is_convex(v) => Err(top.1 - skin),
            // Moved less than `top.1 - skin`, the point stays in front of that plane (so never
            // behind every face), and less than its distance to the fan less `skin`, it keeps
            // clear of the fan.
            FanTest::Mixed(top) => self
                .inside_crease(p, v, skin)
                .map_err(|c| c.min(top.1 - skin)),
        }
    }

    /// The crease test: P1's test misses points inside a concave crease (shoulder against neck,
    /// arm against torso), where a point can be behind some faces of the fan and in front of
    /// others. Such a point is inside when it is behind the closest point of the fan, judged by the
    /// pseudo-normal there (the face normal, or the mean of the faces sharing the closest edge or
    /// vertex). Returns the face and the point's height over the closest point along that normal.
    ///
    /// Outside, `Err` holds the point's distance to the fan less `skin` (0 when not known).
    fn inside_crease(&self, p: &Vec3, v: u32, skin: Real) -> Result<Hit, Real> {
        match self.crease(p, v, skin) {
            Crease::Inside(h) => Ok(h),
            Crease::Outside { clear, .. } => Err(clear),
            Crease::Unknown => Err(0.0),
        }
    }

    /// [`Self::inside_crease`], keeping the closest point of the fan when it was found.
    fn crease(&self, p: &Vec3, v: u32, skin: Real) -> Crease {
        if (p - self.body.positions[v as usize]).norm_squared() > CREASE_REACH * CREASE_REACH {
            return Crease::Unknown;
        }
        let (f, q, bary) = self.body.closest_on_fan(p, v);
        if f == u32::MAX {
            return Crease::Unknown;
        }
        let outside = |clear| Crease::Outside {
            face: f,
            closest: q,
            clear,
        };
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
            n = match n.try_normalize(1e-12) {
                Some(n) => n,
                None => return outside(0.0),
            };
        }
        let h = (p - q).dot(&n);
        if h < skin {
            Crease::Inside(Hit {
                face: f,
                height: h,
                normal: n,
                target: q + n * skin,
                settled: false,
            })
        } else {
            outside(d2.sqrt() - skin)
        }
    }

    /// Whether `p` projects along face `f`'s normal into the face (its edges included).
    fn projects_into(&self, f: u32, p: &Vec3) -> bool {
        let [a, b, c] = self.body.corners(f as usize);
        let n = self.body.face_normals[f as usize];
        let inside_edge = |u: &Vec3, w: &Vec3| (w - u).cross(&(p - u)).dot(&n) >= 0.0;
        inside_edge(&a, &b) && inside_edge(&b, &c) && inside_edge(&c, &a)
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
        // A body that did not move keeps its shape-derived caches.
        let same_shape = frame.positions == self.body.positions;
        if self.body.set_frame(frame).is_err() {
            self.rejected_frames += 1;
            return;
        }
        if !same_shape {
            self.bounds = self.body.bounds();
            self.moves = self.moves.wrapping_add(1) % u32::MAX;
            self.fan_convex.iter().for_each(|c| c.set(0));
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
        for (i, p) in points.iter_mut().enumerate() {
            if !self.near_bounds(p) {
                continue;
            }
            let mut contact: Option<(u32, Real, Vec3)> = None;
            let mut clear = MAX_CLEARANCE;
            for round in 0..RESOLVE_ROUNDS {
                // Track the nearest vertex from where the point is now (after round 0: moved onto
                // one face's plane, the point may still be inside a neighbouring fold).
                self.nearest[i] = self.body.climb(p, self.nearest[i]);
                for j in i * k..(i + 1) * k {
                    self.nearest_more[j] = self.body.climb(p, self.nearest_more[j]);
                }
                // Same vertex, and within its clearance of where it was last found outside: the
                // test would say outside again.
                let c = self.clearance[i];
                if round == 0
                    && k == 0
                    && c > 0.0
                    && self.nearest[i] == self.clear_vertex[i]
                    && (*p - self.clear_at[i]).norm_squared() < c * c
                {
                    break;
                }
                // Inside any piece (the shallowest hit when in several).
                let mut hit: Option<Hit> = None;
                for v in self.candidates(i) {
                    match self.inside_any(p, v, self.thickness) {
                        Ok(h) => {
                            if hit.is_none_or(|b| h.height > b.height) {
                                hit = Some(h);
                            }
                        }
                        Err(c) => clear = clear.min(c),
                    }
                }
                let Some(h) = hit else {
                    if round == 0 {
                        self.clearance[i] = clear.max(0.0);
                        self.clear_at[i] = *p;
                        self.clear_vertex[i] = self.nearest[i];
                    }
                    break;
                };
                self.clearance[i] = 0.0;
                *p = h.target;
                // The contact keeps the first (deepest) test's depth and the last face and normal.
                let depth = contact.map_or((-h.height).max(0.0), |c| c.1);
                contact = Some((h.face, depth, h.normal));
                if h.settled && k == 0 {
                    break;
                }
            }
            let Some((f, depth, n)) = contact else {
                continue;
            };
            let bary = self.bary(f, p);
            contacts.push(Contact {
                point: i as u32,
                face: f,
                bary,
                normal: n,
                depth,
                body_velocity: self.body.velocity_at(f as usize, bary),
            });
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
        for &k in which {
            let p = &points[k as usize];
            if !self.near_bounds(p) {
                out.push(Probe::FAR);
                continue;
            }
            let mut checked = self.probe_checked[k as usize];
            let v = self.follow_nearest(p, self.probe_nearest[k as usize], &mut checked);
            self.probe_checked[k as usize] = checked;
            self.probe_nearest[k as usize] = v;
            let mut closest_found: Option<(u32, Vec3)> = None;
            let top = match self.fan_test(p, v) {
                FanTest::Inside(f, h) => {
                    out.push(Probe {
                        distance: h,
                        normal: self.body.face_normals[f as usize],
                    });
                    continue;
                }
                FanTest::Front(top, _) => top,
                FanTest::Mixed(top) => {
                    if !self.fan_is_convex(v) {
                        match self.crease(p, v, 0.0) {
                            Crease::Inside(h) => {
                                out.push(Probe {
                                    distance: h.height,
                                    normal: h.normal,
                                });
                                continue;
                            }
                            // Outside: the crease test found the fan's closest point already.
                            Crease::Outside { face, closest, .. } => {
                                closest_found = Some((face, closest));
                            }
                            Crease::Unknown => {}
                        }
                    }
                    top
                }
            };
            // Over a convex fan the height over the highest plane bounds the distance from below,
            // and is the distance when the point projects into that face.
            if top.0 != u32::MAX
                && self.fan_is_convex(v)
                && (top.1 >= reach || self.projects_into(top.0, p))
            {
                out.push(Probe {
                    distance: top.1,
                    normal: self.body.face_normals[top.0 as usize],
                });
                continue;
            }
            let (f, q) = closest_found.unwrap_or_else(|| {
                let (f, q, _) = self.body.closest_on_fan(p, v);
                (f, q)
            });
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
