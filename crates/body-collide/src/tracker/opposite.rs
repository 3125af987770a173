//! The surface across a pinch ([`Collider::probe_opposite`]): where two body parts face each
//! other across a narrow gap (an arm pressed against the torso), the second of them. Held off
//! both, the cloth between is squeezed rather than pushed out of one part into the other.
//!
//! [`Collider::probe_opposite`]: tryon_core::stages::Collider::probe_opposite

use super::NearestVertexCollider;
use crate::body::BodyMesh;
use rayon::prelude::*;
use tryon_core::math::{Real, Vec3};
use tryon_core::stages::Probe;

/// Two surfaces face each other when their normals are at least this much opposed (cosine).
const FACING: Real = -0.5;

/// How far one surface may lie behind the other and still face it (m). Skinned parts overlap
/// where they meet (an armpit's arm dips millimetres into the torso); the far side of a thin limb
/// lies a few centimetres behind its near side, and must not count.
const OVERLAP: Real = 0.01;

/// Added to the reach when looking for the opposite surface's nearest vertex (m): the surface
/// can be nearer than any of its vertices.
const VERTEX_SLACK: Real = 0.01;

/// No vertex: nothing faces the point.
const NONE: u32 = u32::MAX;

/// Fewest points a thread takes at once.
const PAR_CHUNK: usize = 64;

/// Per point, the facing vertex found (or [`NONE`]), the body move count then and where the point
/// was: the body does not move between updates, so a point that has moved less than
/// [`super::RECHECK`] since keeps it without a new search.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub(super) struct Facing {
    vertex: u32,
    moves: u32,
    at: Vec3,
}

impl NearestVertexCollider {
    /// [`Collider::probe_opposite`]: each listed point's search runs in parallel (each reads
    /// only the body and its own cache entry), the caches are written after.
    ///
    /// [`Collider::probe_opposite`]: tryon_core::stages::Collider::probe_opposite
    pub(super) fn opposites(
        &mut self,
        points: &[Vec3],
        which: &[u32],
        first: &[Probe],
        reach: Real,
        out: &mut Vec<Probe>,
    ) {
        let stale = Facing {
            vertex: NONE,
            moves: u32::MAX,
            at: Vec3::zeros(),
        };
        self.facing.resize(points.len(), stale);
        let (m, (lo, hi)) = (self.cull_margin + self.thickness, self.bounds);
        let view = View {
            body: &self.body,
            facing: &self.facing,
            moves: self.moves,
            near: move |p: &Vec3| (0..3).all(|a| p[a] >= lo[a] - m && p[a] <= hi[a] + m),
        };
        let found: Vec<(Probe, Option<Facing>)> = which
            .par_iter()
            .zip(first.par_iter())
            .with_min_len(PAR_CHUNK)
            .map(|(&k, q)| view.opposite(k as usize, &points[k as usize], q, reach))
            .collect();
        out.clear();
        for (&k, (probe, fresh)) in which.iter().zip(found) {
            if let Some(f) = fresh {
                self.facing[k as usize] = f;
            }
            out.push(probe);
        }
    }
}

/// What the searches read: the body, the caches, the move count and the bounds test.
struct View<'a, F: Fn(&Vec3) -> bool + Sync> {
    body: &'a BodyMesh,
    facing: &'a [Facing],
    moves: u32,
    near: F,
}

impl<F: Fn(&Vec3) -> bool + Sync> View<'_, F> {
    /// The surface facing point `k` (at `p`) from the other side of its probed surface (`first`)
    /// within `reach`, as `p`'s height over the plane of the facing vertex's nearest face; with
    /// the point's new cache entry when it searched.
    fn opposite(&self, k: usize, p: &Vec3, first: &Probe, reach: Real) -> (Probe, Option<Facing>) {
        let n1 = first.normal;
        if !(first.distance < reach) || n1 == Vec3::zeros() || !(self.near)(p) {
            return (Probe::FAR, None);
        }
        let cached = self.facing[k];
        let (w, fresh) = if cached.moves == self.moves
            && (p - cached.at).norm_squared() < super::RECHECK * super::RECHECK
        {
            (cached.vertex, None)
        } else {
            let w = self.facing_vertex(p, first, reach);
            let entry = Facing {
                vertex: w,
                moves: self.moves,
                at: *p,
            };
            (w, Some(entry))
        };
        if w == NONE {
            return (Probe::FAR, fresh);
        }
        let (f, q, _) = self.body.closest_on_fan(p, w);
        let n2 = self.body.face_normal(f as usize);
        let d2 = (p - q).dot(&n2);
        let probe = if n2.dot(&n1) < 0.0 && d2 < reach {
            Probe {
                distance: d2,
                normal: n2,
            }
        } else {
            Probe::FAR
        };
        (probe, fresh)
    }

    /// The nearest body vertex within `reach` (and [`VERTEX_SLACK`]) of `p` whose normal opposes
    /// the surface `first` found, lying in front of it (up to [`OVERLAP`] behind), with that
    /// surface in front of it; or [`NONE`].
    fn facing_vertex(&self, p: &Vec3, first: &Probe, reach: Real) -> u32 {
        let n1 = first.normal;
        let c1 = p - n1 * first.distance;
        let body = self.body;
        let facing = |w: u32| {
            let nw = body.vertex_normal(w);
            let xw = body.positions[w as usize];
            nw.dot(&n1) < FACING && (xw - c1).dot(&n1) > -OVERLAP && (c1 - xw).dot(&nw) > -OVERLAP
        };
        body.grid()
            .nearest_within_where(&body.positions, p, reach + VERTEX_SLACK, facing)
            .map_or(NONE, |(w, _)| w)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::{Face, PolyMesh};
    use tryon_core::shapes::icosphere;
    use tryon_core::stages::Collider;

    /// Two spheres of radius `r` side by side on the x axis, centres at -c and +c.
    fn two_spheres(r: Real, c: Real) -> PolyMesh {
        let mut m = icosphere(r, 4, Vec3::new(-c, 0.0, 0.0));
        let b = icosphere(r, 4, Vec3::new(c, 0.0, 0.0));
        let base = m.positions.len() as u32;
        m.positions.extend_from_slice(&b.positions);
        m.faces.extend(b.faces.iter().map(|f| match f {
            Face::Tri(t) => Face::Tri(t.map(|v| v + base)),
            Face::Quad(q) => Face::Quad(q.map(|v| v + base)),
        }));
        m
    }

    /// The first probe and the opposite one of each point.
    fn probes(body: &PolyMesh, points: &[Vec3]) -> Vec<(Probe, Probe)> {
        let mut c = NearestVertexCollider::new(body, 0.002).unwrap();
        let which: Vec<u32> = (0..points.len() as u32).collect();
        let (mut first, mut second) = (Vec::new(), Vec::new());
        c.probe(points, &which, &mut first);
        c.probe_opposite(points, &which, &first, 0.03, &mut second);
        first.into_iter().zip(second).collect()
    }

    #[test]
    fn the_part_across_a_gap_or_an_overlap_is_found() {
        // 1 cm between the spheres, and then 1 cm of overlap; points on the axis between them.
        for (c, xs) in [(0.105, [-0.003, 0.0, 0.004]), (0.095, [-0.004, 0.0, 0.002])] {
            let points: Vec<Vec3> = xs.iter().map(|&x| Vec3::new(x, 0.001, 0.0)).collect();
            for (p, (first, second)) in points.iter().zip(probes(&two_spheres(0.1, c), &points)) {
                assert!(second.distance.is_finite(), "{p:?}: nothing found across");
                assert!(first.normal.dot(&second.normal) < -0.9, "{p:?}");
                // The other sphere: its centre on the side the second normal points away from.
                let centre = Vec3::new(-c * second.normal.x.signum(), 0.0, 0.0);
                let exact = (p - centre).norm() - 0.1;
                // The sphere is a mesh of 5 mm edges: its faces lie within 0.2 mm inside it.
                assert!(
                    (second.distance - exact).abs() < 3e-4,
                    "{p:?}: {second:?} against {exact}"
                );
            }
        }
    }

    #[test]
    fn a_lone_part_and_a_thin_parts_far_side_face_nothing() {
        // A point 5 mm outside a large sphere, and 3 mm over a 2 cm ball (its far side, 2 cm
        // behind, faces away but lies beyond the overlap any skinned joint makes).
        for (r, d) in [(0.3, 0.005), (0.01, 0.003)] {
            let body = icosphere(r, 4, Vec3::zeros());
            let p = Vec3::new(0.0, r + d, 0.0);
            let (first, second) = probes(&body, &[p])[0];
            assert!((first.distance - d).abs() < 1e-3, "{first:?}");
            assert_eq!(second, Probe::FAR, "r {r}");
        }
    }

    #[test]
    fn non_finite_points_and_probes_face_nothing_and_do_not_panic() {
        let body = two_spheres(0.1, 0.105);
        let nan = Vec3::new(Real::NAN, 0.0, 0.0);
        let mut c = NearestVertexCollider::new(&body, 0.002).unwrap();
        let first = [
            Probe {
                distance: 0.001,
                normal: Vec3::x(),
            },
            Probe {
                distance: Real::NAN,
                normal: Vec3::x(),
            },
        ];
        let points = [nan, Vec3::new(0.0, 0.001, 0.0)];
        let mut out = Vec::new();
        c.probe_opposite(&points, &[0, 1], &first, 0.03, &mut out);
        assert_eq!(out, vec![Probe::FAR, Probe::FAR]);
    }
}
