//! P1 section 3.4, following the body: after a step each point near the body records its
//! coordinates in the frame of its nearest body face (two edge coordinates and a height along the
//! unit normal); after the body moves, the point is put back at the same face coordinates. The
//! decomposition is affine, so a rigid motion of the body moves followed points by exactly that motion.

use crate::body::{BodyError, BodyMesh};
use tryon_core::frames::BodyFrame;
use tryon_core::math::{Real, Vec3};

/// How far from the body points follow it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FollowParams {
    /// Points within this distance of the body follow it fully (m).
    pub near: Real,
    /// Following fades linearly to nothing at this distance (m).
    pub far: Real,
}

impl Default for FollowParams {
    fn default() -> Self {
        FollowParams {
            near: 0.01,
            far: 0.03,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
struct Attachment {
    face: u32,
    /// p = v0 + a (v1 - v0) + b (v2 - v0) + c n.
    abc: [Real; 3],
    weight: Real,
}

/// Records points relative to the body and puts them back after the body moves.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct BodyFollower {
    pub body: BodyMesh,
    pub params: FollowParams,
    nearest: Vec<u32>,
    attached: Vec<Option<Attachment>>,
    /// The root joint the whole cloth rides with (see `carry.rs`).
    pub carry: crate::carry::RootCarry,
    /// The cloth's edges, kept from tearing by the carry (`carry_edges.rs`); `None` carries each
    /// point by itself, as P1 does.
    pub edges: Option<crate::carry_edges::CarryEdges>,
}

fn frame_of(body: &BodyMesh, f: usize) -> (Vec3, Vec3, Vec3, Vec3) {
    let [v0, v1, v2] = body.corners(f);
    (v0, v1 - v0, v2 - v0, body.face_normal(f))
}

/// Closest point on the faces around `v`, and when that lands on the fan's rim, on the faces around
/// its neighbours too (the two-ring), which finds the right face even where long triangles put the
/// closest point outside the nearest vertex's fan.
fn closest_near(body: &BodyMesh, p: &Vec3, v: u32) -> (u32, Vec3) {
    let (mut f, mut q, bary) = body.closest_on_fan(p, v);
    let on_rim = body
        .triangles
        .get(f as usize)
        .and_then(|t| t.iter().position(|&c| c == v))
        .is_none_or(|k| bary[k] <= 1e-12);
    if !on_rim {
        return (f, q);
    }
    let mut best = (q - p).norm_squared();
    for &w in body.ring.row(v as usize) {
        let (f2, q2, _) = body.closest_on_fan(p, w);
        let d = (q2 - p).norm_squared();
        if d < best {
            (f, q, best) = (f2, q2, d);
        }
    }
    (f, q)
}

/// `p`'s coordinates in face `f`'s frame: two edge coordinates and a height along the unit normal.
fn coordinates(body: &BodyMesh, p: &Vec3, f: usize) -> Option<[Real; 3]> {
    let (v0, e1, e2, n) = frame_of(body, f);
    let r = p - v0;
    let c = r.dot(&n);
    let r = r - n * c;
    let (g11, g12, g22) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
    let det = g11 * g22 - g12 * g12;
    if !(det > 0.0) {
        return None;
    }
    let (r1, r2) = (r.dot(&e1), r.dot(&e2));
    Some([(r1 * g22 - r2 * g12) / det, (r2 * g11 - r1 * g12) / det, c])
}

/// The point at face coordinates `abc` of face `f` on the body's current shape.
fn place(body: &BodyMesh, f: u32, abc: [Real; 3]) -> Vec3 {
    let (v0, e1, e2, n) = frame_of(body, f as usize);
    v0 + e1 * abc[0] + e2 * abc[1] + n * abc[2]
}

/// A point fixed to the body's surface for good (a garment's elastic band sewn in place): its
/// nearest face and its coordinates there, recorded once.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfaceBinding {
    pub face: u32,
    /// p = v0 + a (v1 - v0) + b (v2 - v0) + c n.
    pub abc: [Real; 3],
}

impl SurfaceBinding {
    /// Binds `p` to its nearest face on the body's current shape (`None` on a degenerate face).
    pub fn bind(body: &BodyMesh, p: &Vec3) -> Option<Self> {
        let v = body.nearest_vertex_brute(p);
        let (face, _) = closest_near(body, p, v);
        coordinates(body, p, face as usize).map(|abc| SurfaceBinding { face, abc })
    }

    /// Where the bound point is on the body's current shape.
    pub fn position(&self, body: &BodyMesh) -> Vec3 {
        place(body, self.face, self.abc)
    }
}

impl BodyFollower {
    /// A follower for a body mesh (given in its current shape).
    pub fn new(body: BodyMesh, params: FollowParams) -> Self {
        BodyFollower {
            body,
            params,
            nearest: Vec::new(),
            attached: Vec::new(),
            carry: crate::carry::RootCarry::default(),
            edges: None,
        }
    }

    /// The same follower keeping the edges of the cloth's triangles `tris` from tearing in the
    /// carry (`carry_edges.rs`).
    pub fn with_edges(mut self, tris: &[[u32; 3]]) -> Self {
        self.edges = Some(crate::carry_edges::CarryEdges::of_triangles(tris));
        self
    }

    /// The same follower carrying the cloth with joint `root`, whose rest position is `root_rest`.
    pub fn with_root(mut self, root: usize, root_rest: Vec3) -> Self {
        self.carry = crate::carry::RootCarry::new(root, root_rest);
        self
    }

    /// Records each point's face coordinates on the current body (call after a step).
    pub fn record(&mut self, points: &[Vec3]) {
        if self.nearest.len() != points.len() {
            self.nearest = points
                .iter()
                .map(|p| self.body.nearest_vertex_brute(p))
                .collect();
        }
        self.attached.clear();
        for (i, p) in points.iter().enumerate() {
            let v = self.body.climb(p, self.nearest[i]);
            self.nearest[i] = v;
            let (f, q) = closest_near(&self.body, p, v);
            let dist = (p - q).norm();
            let weight = if dist <= self.params.near {
                1.0
            } else if dist < self.params.far {
                (self.params.far - dist) / (self.params.far - self.params.near)
            } else {
                0.0
            };
            self.attached.push(if weight > 0.0 {
                coordinates(&self.body, p, f as usize).map(|abc| Attachment {
                    face: f,
                    abc,
                    weight,
                })
            } else {
                None
            });
        }
    }

    /// The follow weight of each recorded point (1 = follows fully, 0 = not attached).
    pub fn weights(&self) -> Vec<Real> {
        self.attached
            .iter()
            .map(|a| a.map_or(0.0, |a| a.weight))
            .collect()
    }

    /// Takes the body's new shape and moves every recorded point to its face coordinates there
    /// (by its weight), the moves kept from tearing the cloth's `edges` when it has them.
    /// Returns how many points moved.
    pub fn apply(&mut self, frame: &BodyFrame, points: &mut [Vec3]) -> Result<usize, BodyError> {
        // Only the faces points are attached to need their normals.
        self.body.set_shape(frame)?;
        let mut moved = 0;
        let mut d = vec![Vec3::zeros(); points.len()];
        for ((p, a), d) in points.iter().zip(&self.attached).zip(&mut d) {
            let Some(a) = a else { continue };
            let target = place(&self.body, a.face, a.abc);
            if tryon_core::math::is_finite(&target) {
                *d = (target - *p) * a.weight;
                moved += 1;
            }
        }
        if let Some(e) = &self.edges {
            e.limit(points, &mut d);
        }
        for (p, d) in points.iter_mut().zip(&d) {
            *p += d;
        }
        Ok(moved)
    }
}
