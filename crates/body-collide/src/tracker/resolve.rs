//! The nearest-vertex collider's projection (`Collider::resolve`), one point at a time: each
//! point reads only its own cache entries and the body, so the points are resolved in parallel
//! and their results written back in order (the same for any number of threads).

use super::{Hit, MAX_CLEARANCE, NearestVertexCollider, RESOLVE_ROUNDS};
use tryon_core::frames::Contact;
use tryon_core::math::{Real, Vec3};

/// One point after its projection: where it is, its new cache entries, and its contact.
pub(super) struct Resolved {
    pub p: Vec3,
    pub nearest: u32,
    /// Its nearest vertex on each further piece of the body (empty for a body in one piece).
    pub more: Vec<u32>,
    /// Its clearance, where it was found outside, and at which vertex.
    pub clear: (Real, Vec3, u32),
    pub contact: Option<Contact>,
}

impl NearestVertexCollider {
    /// P1's test and push for point `i` at `p`: up to [`RESOLVE_ROUNDS`] rounds of tracking its
    /// nearest vertex, testing it there and moving it out, skipped when it is within its
    /// clearance of where it was last found outside at the same vertex.
    pub(super) fn resolve_point(&self, i: usize, mut p: Vec3) -> Resolved {
        let k = self.extra_pieces.len();
        let mut nearest = self.nearest[i];
        let mut more = self.nearest_more[i * k..(i + 1) * k].to_vec();
        let mut entry = (self.clearance[i], self.clear_at[i], self.clear_vertex[i]);
        let mut contact: Option<(u32, Real, Vec3)> = None;
        let mut clear = MAX_CLEARANCE;
        for round in 0..RESOLVE_ROUNDS {
            // Track the nearest vertex from where the point is now (after round 0: moved onto
            // one face's plane, the point may still be inside a neighbouring fold).
            nearest = self.body.climb(&p, nearest);
            more.iter_mut().for_each(|m| *m = self.body.climb(&p, *m));
            // Same vertex, and within its clearance of where it was last found outside: the
            // test would say outside again.
            let c = entry.0;
            if round == 0
                && k == 0
                && c > 0.0
                && nearest == entry.2
                && (p - entry.1).norm_squared() < c * c
            {
                break;
            }
            // Inside any piece (the shallowest hit when in several).
            let mut hit: Option<Hit> = None;
            for v in std::iter::once(nearest).chain(more.iter().copied()) {
                match self.inside_any(&p, v, self.thickness) {
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
                    entry = (clear.max(0.0), p, nearest);
                }
                break;
            };
            entry.0 = 0.0;
            p = h.target;
            // The contact keeps the first (deepest) test's depth and the last face and normal.
            let depth = contact.map_or((-h.height).max(0.0), |c| c.1);
            contact = Some((h.face, depth, h.normal));
            if h.settled && k == 0 {
                break;
            }
        }
        let contact = contact.map(|(f, depth, n)| {
            let bary = self.bary(f, &p);
            Contact {
                point: i as u32,
                face: f,
                bary,
                normal: n,
                depth,
                body_velocity: self.body.velocity_at(f as usize, bary),
            }
        });
        Resolved {
            p,
            nearest,
            more,
            clear: entry,
            contact,
        }
    }
}
