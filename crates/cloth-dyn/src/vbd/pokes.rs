//! Body vertices under cloth triangles, held behind the cloth inside the solve. The particles'
//! contact planes keep every particle outside, yet a body feature narrower than the cloth's
//! triangles (a nipple, a shoulder's tip) pokes through between them: on makehuman-dress-walk
//! 99 body vertices a frame were in front of the jacket (48 by more than 1 mm) while the referee,
//! which judges particles, read 0. Each body vertex the collider finds under a triangle
//! ([`Collider::pokes`]) is an energy on the triangle's three particles: with `q = sum w_j x_j` the
//! triangle's point over the vertex `p` (barycentric `w`) and `n` the body's normal there,
//! `E = k/2 (g - n . (q - p))^2` while the cloth is nearer than the gap `g`. A vertex's Newton
//! step takes its share: force `k w_i (g - s) n`, Hessian `k w_i^2 n n^T`. A triangle's corners
//! are never in one colour.
//!
//! The gap is 1 mm, not the cloth's thickness: the thickness is kept at the particles, and held
//! over every vertex under a coarse triangle it lifts the cloth off convex parts (the demo's strap
//! stretched 1.06 -> 1.30 over the shoulder). The stiffness is the particle's contact penalty
//! (nine times as stiff cut the frames' pokes from 6 to 2-4 but stretched the demo 1.11).

use tryon_core::math::{Real, Vec3};
use tryon_core::stages::{Collider, Poke};

/// Poke stiffness over the particle's contact penalty (see the module's notes).
pub const POKE_OVER_CONTACT: Real = 1.0;

/// How far in front of a body vertex under it the cloth is held (m).
pub const POKE_GAP: Real = 0.001;

/// Body vertices nearer the cloth than the gap plus this (m) when found are kept for the frame's
/// steps (the body holds still during them; the cloth moves a few millimetres).
pub const POKE_MARGIN: Real = 0.004;

/// A poke lapses when the triangle's point over its vertex has slid sideways off it by more than
/// this (m): the stiff hard case, stepped once a frame, slid its cloth off the mannequin (26% of
/// it more than 10 cm away) when the triangles kept being pushed along the normals of vertices
/// they had left.
pub const POKE_SLIDE: Real = 0.005;

/// Vertices more than this behind the cloth (m) are taken for another part's far side.
pub const POKE_DEPTH: Real = 0.01;

/// Least cosine between a body vertex's normal and the mean contact normal of the triangle's
/// corners. A vertex of another part (the chin over a collar, an arm over the chest) faces
/// otherwise; held behind the cloth, such vertices crumpled the elegant suit's front between chin
/// and chest (makehuman-dress-walk from 3 s: stretch 5.0, p99 1.3 mm).
pub const SAME_SIDE: Real = 0.7;

/// The pokes of a frame and, per particle, the pokes it shares (CSR).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Pokes {
    pub list: Vec<Poke>,
    offsets: Vec<u32>,
    refs: Vec<(u32, u8)>,
    /// Scratch: the triangles asked about.
    which: Vec<u32>,
}

impl Pokes {
    /// Asks `collider` for the body vertices under the triangles with a corner near the body
    /// (`plane(k)`: particle k's contact normal, if it has a plane), and keeps those that face
    /// the way the corners' contact planes face on average.
    pub fn find(
        &mut self,
        collider: &mut dyn Collider,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        plane: impl Fn(usize) -> Option<Vec3>,
    ) {
        self.which.clear();
        for (t, tri) in triangles.iter().enumerate() {
            if tri.iter().any(|&k| plane(k as usize).is_some()) {
                self.which.push(t as u32);
            }
        }
        let limits = (POKE_GAP + POKE_MARGIN, POKE_DEPTH);
        collider.pokes(x, triangles, &self.which, limits, &mut self.list);
        self.list.retain(|p| {
            let m: Vec3 = triangles[p.triangle as usize]
                .iter()
                .filter_map(|&k| plane(k as usize))
                .sum();
            p.normal.dot(&m) > SAME_SIDE * m.norm()
        });
        let mut counts = vec![0u32; x.len() + 1];
        for p in &self.list {
            for &k in &triangles[p.triangle as usize] {
                counts[k as usize + 1] += 1;
            }
        }
        for i in 0..x.len() {
            counts[i + 1] += counts[i];
        }
        self.refs.clear();
        self.refs.resize(counts[x.len()] as usize, (0, 0));
        let mut fill = counts.clone();
        for (n, p) in self.list.iter().enumerate() {
            for (role, &k) in triangles[p.triangle as usize].iter().enumerate() {
                self.refs[fill[k as usize] as usize] = (n as u32, role as u8);
                fill[k as usize] += 1;
            }
        }
        self.offsets = counts;
    }

    /// The pokes' force on particle `i` at positions `x` (stiffness `k`, gap `d`), added
    /// to `f`, and their Hessian, added to the symmetric outer part `o` (xx, xy, xz, yy, yz, zz).
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &self,
        x: &[Vec3],
        triangles: &[[u32; 3]],
        i: usize,
        (k, d): (Real, Real),
        f: &mut Vec3,
        o: &mut [Real; 6],
    ) {
        if i + 1 >= self.offsets.len() {
            return;
        }
        for &(n, role) in &self.refs[self.offsets[i] as usize..self.offsets[i + 1] as usize] {
            let p = &self.list[n as usize];
            let tri = triangles[p.triangle as usize];
            let q: Vec3 = (0..3).map(|j| x[tri[j] as usize] * p.bary[j]).sum();
            let r = q - p.point;
            let s = p.normal.dot(&r);
            let gap = d - s;
            // The barycentric place was found at the frame's start; a triangle that has slid
            // off the vertex since no longer covers it.
            if gap <= 0.0 || (r - p.normal * s).norm_squared() > POKE_SLIDE * POKE_SLIDE {
                continue;
            }
            let w = p.bary[role as usize];
            *f += p.normal * (k * w * gap);
            super::add_outer(o, k * w * w, &p.normal);
        }
    }
}
