//! VBD's body contact: the contact energy (penalty and friction) of a vertex's planes, the plane
//! of the part facing a contact across a pinch, and the fail-safe after each step's solve.

use super::{Plane, VbdSim};
use tryon_core::math::{Mat3, Real, Vec3};
use tryon_core::stages::Collider;

/// Where a particle the swept test stopped on one body part ends behind another part's contact
/// plane (pinched where the body meets itself, as at an armpit whose skinned arm dips into the
/// torso), it goes this share of the way back to that plane: the middle of the overlap.
const PINCH_SHARE: Real = 0.5;

/// How far beyond the thickness a particle with a contact plane looks for a body part facing
/// that one across a pinch (m): an arm a step's travel away (2 m/s for 1/120 s is 17 mm).
const PINCH_REACH: Real = 0.02;

/// The contact penalty is at least this many times the summed stiffness of a vertex's springs.
const CONTACT_OVER_SPRINGS: Real = 1.0;

impl VbdSim {
    /// For every particle with a contact plane, the plane of the part facing it across a pinch
    /// (`opposite`), from the collider's [`Collider::probe_opposite`] within [`PINCH_REACH`]
    /// of it (positions `x` are those at the step's start).
    pub(super) fn pinches(&mut self, x: &[Vec3], collider: &mut dyn Collider) {
        self.opposite.iter_mut().for_each(|o| *o = None);
        self.near.clear();
        self.near_probes.clear();
        for (i, pl) in self.planes.iter().enumerate() {
            if pl.is_some() {
                self.near.push(i as u32);
                self.near_probes.push(self.probes[i]);
            }
        }
        let reach = self.thickness + PINCH_REACH;
        let mut found = std::mem::take(&mut self.probes);
        collider.probe_opposite(x, &self.near, &self.near_probes, reach, &mut found);
        for (&i, q) in self.near.iter().zip(&found) {
            if q.distance < reach && q.normal != Vec3::zeros() {
                let xi = x[i as usize];
                self.opposite[i as usize] = Some(Plane {
                    point: xi - q.normal * q.distance,
                    normal: q.normal,
                });
            }
        }
        self.probes = found;
    }

    /// Particle `i`'s contact penalty (N/m). It must dominate the springs the vertex hangs from,
    /// or stiff cloth is dragged through the body: never softer than their summed stiffness.
    pub(super) fn penalty(&self, i: usize) -> Real {
        self.vbd
            .contact
            .max(self.spring_sum[i] * CONTACT_OVER_SPRINGS)
    }

    /// Adds to vertex `i`'s force and Hessian (at `xi`) the contact energy of plane `pl`: a
    /// quadratic penalty holding it a thickness outside, and IPC's lagged friction bounded by the
    /// penalty's force.
    pub(super) fn contact(
        &self,
        pl: &Plane,
        i: usize,
        xi: Vec3,
        h: Real,
        f: &mut Vec3,
        hess: &mut Mat3,
    ) {
        let gap = pl.normal.dot(&(xi - pl.point)) - self.thickness;
        if gap >= 0.0 {
            return;
        }
        let kc = self.penalty(i);
        *f -= pl.normal * (kc * gap);
        *hess += pl.normal * pl.normal.transpose() * kc;
        let mu = self.params.friction;
        let lambda = -kc * gap;
        let slip = xi - self.prev[i];
        let u = slip - pl.normal * slip.dot(&pl.normal);
        let ul = u.norm();
        let eps = self.vbd.stick_speed * h;
        if mu > 0.0 && lambda > 0.0 {
            let tangent = Mat3::identity() - pl.normal * pl.normal.transpose();
            let scale = mu * lambda / ul.max(eps);
            *f -= u * scale;
            *hess += tangent * scale;
        }
    }

    /// The fail-safe after the solve. First the swept test, where the collider has one: a
    /// particle whose path crosses the body inward (the body as the collider's last update left
    /// it: the frame's steps do not move it) is stopped on the surface it hit, on the side it came
    /// from (`stopped`), unless it started inside or is kinematic. Then a particle that had a contact plane for the step
    /// keeps the side of it it came from (projected back onto the plane if the solve left it
    /// behind, so it is never pushed through to another body part); one that started inside is
    /// left to the contact energy; only the others (far from the body at the start) get the
    /// collider's projection. Projected onto whichever part was nearest, particles caught where
    /// two parts meet (armpits) tore the cloth there: makehuman-dress-walk's armholes reached 6.4
    /// times their rest length.
    pub(super) fn fail_safe(
        &mut self,
        x: &mut [Vec3],
        span: [Real; 2],
        collider: &mut dyn Collider,
    ) {
        self.solved.clone_from_slice(x);
        self.contacts.clear();
        self.stopped.clear();
        self.stopped.resize(x.len(), false);
        self.held.iter_mut().for_each(|h| *h = None);
        if self.vbd.swept && self.sweep_moved(span, collider) {
            // Kinematic particles (bands, grabs) go where they are led.
            let (inv_mass, solved) = (&self.model.inv_mass, &mut self.solved);
            let (planes, prev) = (&self.planes, &self.prev);
            self.contacts.retain(|c| {
                let i = c.point as usize;
                let outside =
                    planes[i].is_none_or(|pl| pl.normal.dot(&(prev[i] - pl.point)) >= 0.0);
                let free = inv_mass[i] != 0.0 && outside;
                if !free {
                    solved[i] = x[i];
                }
                free
            });
            for c in &self.contacts {
                let i = c.point as usize;
                self.stopped[i] = true;
                self.held[i] = Some(Plane {
                    point: self.solved[i] - c.normal * self.thickness,
                    normal: c.normal,
                });
            }
        }
        let swept = self.contacts.len();
        collider.resolve(x, &mut self.contacts);
        let stopped = &self.stopped;
        let mut k = 0;
        self.contacts.retain(|c| {
            k += 1;
            k <= swept || !stopped[c.point as usize]
        });
        for i in 0..x.len() {
            let Some(pl) = self.planes[i] else {
                if self.stopped[i] {
                    x[i] = self.solved[i];
                }
                continue;
            };
            x[i] = self.solved[i];
            if let Some(op) = self.opposite[i] {
                x[i] = between(x[i], self.prev[i], &pl, &op);
                continue;
            }
            let start = pl.normal.dot(&(self.prev[i] - pl.point));
            let gap = pl.normal.dot(&(x[i] - pl.point));
            if start >= 0.0 && gap < 0.0 {
                // Stopped by one part behind another's plane: pinched where the body meets itself.
                x[i] -= pl.normal * (gap * if self.stopped[i] { PINCH_SHARE } else { 1.0 });
            }
        }
    }
}

impl VbdSim {
    /// The swept test of the step's paths (`prev` to `solved`), into `contacts`. While the body
    /// stands still through the step (`span` [1, 1]: it moved at the frame's start) and the
    /// collider's probes give true distances (`exact_distance`), a particle whose path is
    /// shorter than its distance from the body at the start (less [`SWEEP_MARGIN`]) cannot reach
    /// it, and only the others are tested: the same stops, for a fraction of the paths
    /// (docs/decisions, *swept test of the paths that can reach*).
    fn sweep_moved(&mut self, span: [Real; 2], collider: &mut dyn Collider) -> bool {
        if span != [1.0, 1.0] || !collider.capabilities().exact_distance {
            return collider.sweep(&self.prev, &mut self.solved, span, &mut self.contacts);
        }
        let (start, end, who) = &mut self.swept_sub;
        start.clear();
        end.clear();
        who.clear();
        for (i, (p, x)) in self.prev.iter().zip(&self.solved).enumerate() {
            if (x - p).norm() + SWEEP_MARGIN >= self.clear[i] {
                start.push(*p);
                end.push(*x);
                who.push(i as u32);
            }
        }
        let first = self.contacts.len();
        if !collider.sweep(start, end, span, &mut self.contacts) {
            return false;
        }
        for c in &mut self.contacts[first..] {
            c.point = who[c.point as usize];
        }
        for (k, &i) in who.iter().enumerate() {
            self.solved[i as usize] = end[k];
        }
        true
    }
}

/// A path must be this much shorter than its start's distance from the body to go untested
/// (m): far above the rounding of the distance and of the crossing test.
const SWEEP_MARGIN: Real = 1e-6;

/// `x` (which was at `from` at the step's start) moved along the bisector of two facing planes'
/// normals, as little as it takes to be on the outer side of both. Where they overlap and no
/// point is, it keeps the outer side of the one it started outside, or, having started inside
/// both, goes to the middle. Unmoved when outside both.
fn between(x: Vec3, from: Vec3, a: &Plane, b: &Plane) -> Vec3 {
    let (ha, hb) = (a.normal.dot(&(x - a.point)), b.normal.dot(&(x - b.point)));
    if ha >= 0.0 && hb >= 0.0 {
        return x;
    }
    let Some(u) = (a.normal - b.normal).try_normalize(1e-9) else {
        return x;
    };
    // Heights change as ha + s ca and hb + s cb along u, with ca > 0 > cb for facing planes.
    let (ca, cb) = (a.normal.dot(&u), b.normal.dot(&u));
    if !(ca > 1e-6 && cb < -1e-6) {
        return x;
    }
    let (lo, hi) = (-ha / ca, hb / -cb);
    let s = if lo <= hi {
        lo.max(0.0).min(hi)
    } else {
        // The planes overlap (skinned parts dipping into each other): no point is outside both.
        // Keep the side it came from; from inside both, the middle of the overlap.
        let (fa, fb) = (
            a.normal.dot(&(from - a.point)),
            b.normal.dot(&(from - b.point)),
        );
        if fa >= 0.0 {
            lo.max(0.0)
        } else if fb >= 0.0 {
            hi.min(0.0)
        } else {
            (hb - ha) / (ca - cb)
        }
    };
    x + u * s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(x: Real, nx: Real) -> Plane {
        Plane {
            point: Vec3::new(x, 0.0, 0.0),
            normal: Vec3::new(nx, 0.0, 0.0),
        }
    }

    #[test]
    fn between_two_facing_planes_moves_as_little_as_it_takes() {
        // Surfaces at x = 0 (facing +x) and x = 0.01 (facing -x): room between them.
        let (a, b) = (plane(0.0, 1.0), plane(0.01, -1.0));
        let at = |x: Real| Vec3::new(x, 0.3, -0.2);
        assert_eq!(between(at(0.004), at(0.004), &a, &b), at(0.004));
        assert_eq!(between(at(-0.003), at(0.002), &a, &b), at(0.0));
        assert_eq!(between(at(0.012), at(0.002), &a, &b), at(0.01));
    }

    #[test]
    fn overlapping_planes_keep_the_side_the_point_came_from_or_split_the_overlap() {
        // The second part dips 4 mm into the first: outside one is inside the other.
        let (a, b) = (plane(0.0, 1.0), plane(-0.004, -1.0));
        let at = |x: Real| Vec3::new(x, 0.0, 0.0);
        // Came from outside a (x > 0): stays on a's surface, however deep into b.
        assert_eq!(between(at(-0.001), at(0.003), &a, &b), at(0.0));
        // Came from outside b (x < -0.004): stays on b's surface.
        assert_eq!(between(at(-0.001), at(-0.006), &a, &b), at(-0.004));
        // Started inside both: the middle of the overlap.
        let mid = between(at(-0.0035), at(-0.001), &a, &b);
        assert!((mid.x + 0.002).abs() < 1e-12, "{mid:?}");
    }

    #[test]
    fn planes_that_do_not_face_each_other_leave_the_point() {
        let (a, b) = (plane(0.0, 1.0), plane(0.0, 1.0));
        let p = Vec3::new(-0.001, 0.0, 0.0);
        assert_eq!(between(p, p, &a, &b), p);
    }
}
