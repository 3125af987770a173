//! How the cloth is held and moved from outside the solver: kinematic handles on scripted paths
//! (pins, elastic bands, P4's user dragging the cloth) and a grab still to happen.

use crate::math::{Real, Vec3};

/// A particle that follows a scripted path (piecewise linear in time), as when P4's user drags the cloth.
/// A path with a single key is a pin.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Handle {
    pub particle: u32,
    /// (time s, position m), times ascending.
    pub path: Vec<(Real, Vec3)>,
}

impl Handle {
    /// Position on the path at time t (held constant before the first and after the last key).
    pub fn position(&self, t: Real) -> Vec3 {
        let p = &self.path;
        if t <= p[0].0 {
            return p[0].1;
        }
        for w in p.windows(2) {
            let ((t0, a), (t1, b)) = (w[0], w[1]);
            if t <= t1 {
                let s = if t1 > t0 { (t - t0) / (t1 - t0) } else { 1.0 };
                return a + (b - a) * s;
            }
        }
        p[p.len() - 1].1
    }

    /// Velocity on the path at time t (the slope of the segment holding t).
    pub fn velocity(&self, t: Real) -> Vec3 {
        for w in self.path.windows(2) {
            let ((t0, a), (t1, b)) = (w[0], w[1]);
            if t >= t0 && t < t1 {
                return (b - a) / (t1 - t0);
            }
        }
        Vec3::zeros()
    }
}

/// A grab still to happen (P4's user dragging the cloth): once the clock reaches the first key's
/// time, the particle then nearest the first point is handed to the path's displacements.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Grab {
    /// Keys (time s, position m), times rising.
    pub path: Vec<(Real, Vec3)>,
}

impl Grab {
    /// The handle this grab becomes at time `t` over the cloth `positions`, or `None` while it is
    /// not yet due (or when there is no key or no particle). The particle keeps its own position
    /// and moves by the path's displacements from the first key.
    pub fn handle_at(&self, t: Real, positions: &[Vec3]) -> Option<Handle> {
        let &(t0, start) = self.path.first()?;
        if t0 > t {
            return None;
        }
        let d2 = |p: &Vec3| (p - start).norm_squared();
        let (particle, at) = positions
            .iter()
            .enumerate()
            .min_by(|a, b| d2(a.1).total_cmp(&d2(b.1)))?;
        Some(Handle {
            particle: particle as u32,
            path: self
                .path
                .iter()
                .map(|(k, p)| (*k, at + (p - start)))
                .collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grab_takes_the_nearest_particle_once_due_and_moves_it_by_the_displacements() {
        let grab = Grab {
            path: vec![
                (1.0, Vec3::new(1.0, 0.0, 0.0)),
                (2.0, Vec3::new(1.0, 1.0, 0.0)),
            ],
        };
        let cloth = [
            Vec3::zeros(),
            Vec3::new(0.9, 0.0, 0.1),
            Vec3::new(3.0, 0.0, 0.0),
        ];
        assert_eq!(grab.handle_at(0.5, &cloth), None);
        let h = grab.handle_at(1.0, &cloth).unwrap();
        assert_eq!(h.particle, 1);
        assert_eq!(h.path[0], (1.0, Vec3::new(0.9, 0.0, 0.1)));
        assert_eq!(h.path[1], (2.0, Vec3::new(0.9, 1.0, 0.1)));
        assert_eq!(h.position(1.5), Vec3::new(0.9, 0.5, 0.1));
        assert_eq!(grab.handle_at(5.0, &[]), None);
        assert_eq!(Grab { path: vec![] }.handle_at(5.0, &cloth), None);
    }
}
