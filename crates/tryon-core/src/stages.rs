//! The stage contracts: small object-safe traits over plain data. The caller owns the state; a stage
//! owns only scratch memory. Each trait has a trivial implementation so a stage can be tested alone.

use crate::frames::{BodyFrame, CoarseFrame, Contact, FineSurface, FineVertexSource, StepReport};
use crate::math::{Real, Vec3};
use crate::pose::Pose;

/// A motion: the pose at time t.
pub trait MotionSource: Send {
    /// Length of the clip (s).
    fn duration(&self) -> Real;
    /// Writes the pose at time `t` (clamped to the clip) into `out`.
    fn sample(&self, t: Real, out: &mut Pose);
}

/// A body that can be posed into a deformed mesh.
pub trait BodyModel: Send {
    /// Number of body vertices.
    fn vertex_count(&self) -> usize;
    /// Triangles of the body mesh (fixed for the model's lifetime).
    fn triangles(&self) -> &[[u32; 3]];
    /// Deforms the body into `pose`, writing positions (and velocities when it can) into `out`.
    fn pose(&mut self, pose: &Pose, out: &mut BodyFrame);
}

/// Collision between points and the body.
pub trait Collider: Send {
    /// Short name for reports.
    fn name(&self) -> &'static str;
    /// Takes the body's new shape. Called whenever the body moved.
    fn update(&mut self, body: &BodyFrame);
    /// Moves every point found inside the body onto its surface and appends one contact per moved
    /// point. The same point slice (same length, same order) is expected on every call.
    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>);
    /// Signed distance from `p` to the body surface (negative inside), if the collider can say.
    fn signed_distance(&self, p: &Vec3) -> Option<Real>;
    /// Probes the points listed in `which` (indices into `points`, which is the same slice on every
    /// call, as for `resolve`): one entry per listed point, in order, written to `out` (cleared
    /// first). The default works from `signed_distance` with a central-difference normal; colliders
    /// that track points override it.
    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        out.clear();
        let h = 1e-4;
        for &k in which {
            let p = points[k as usize];
            let Some(d) = self.signed_distance(&p) else {
                out.push(Probe::FAR);
                continue;
            };
            let mut g = Vec3::zeros();
            for a in 0..3 {
                let mut e = Vec3::zeros();
                e[a] = h;
                let (Some(f1), Some(f0)) = (
                    self.signed_distance(&(p + e)),
                    self.signed_distance(&(p - e)),
                ) else {
                    break;
                };
                g[a] = (f1 - f0) / (2.0 * h);
            }
            out.push(Probe {
                distance: d,
                normal: g
                    .try_normalize(1e-12)
                    .filter(crate::math::is_finite)
                    .unwrap_or(Vec3::zeros()),
            });
        }
    }
    /// As [`Collider::probe`], for a caller that only cares about points nearer than `reach`: a
    /// point at least `reach` outside may be given any distance >= `reach` (a cheaper bound). The
    /// default is `probe`.
    fn probe_near(&mut self, points: &[Vec3], which: &[u32], reach: Real, out: &mut Vec<Probe>) {
        let _ = reach;
        self.probe(points, which, out);
    }
}

/// What a collider says about one point: signed distance to the body (negative inside) and the
/// body's outward unit normal at the closest point (zero when unknown).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    pub distance: Real,
    pub normal: Vec3,
}

impl Probe {
    /// A point the collider knows nothing about: infinitely far outside.
    pub const FAR: Probe = Probe {
        distance: Real::INFINITY,
        normal: Vec3::new(0.0, 0.0, 0.0),
    };
}

/// One frame of coarse cloth dynamics against a collider.
pub trait ClothSolver: Send {
    /// Advances `frame` by `dt`, resolving collisions with `collider`. Never fails: non-finite or
    /// exploding state is retried smaller or rolled back, and reported.
    fn step_frame(
        &mut self,
        frame: &mut CoarseFrame,
        dt: Real,
        collider: &mut dyn Collider,
    ) -> StepReport;
}

/// Coarse surface -> fine surface. Topology is built once at construction.
pub trait Refiner: Send {
    /// Evaluates fine positions and normals from coarse positions and vertex normals.
    fn refine(&mut self, coarse_positions: &[Vec3], coarse_normals: &[Vec3], out: &mut FineSurface);
}

/// Fine detail on the refined surface (P1 section 4): penetration removal, wrinkles, normals.
pub trait DetailModel: Send {
    /// Adjusts the fine surface in place.
    fn apply(&mut self, coarse: &CoarseFrame, fine: &mut FineSurface, collider: &mut dyn Collider);
}

/// A motion that holds the rest pose.
#[derive(Clone, Debug)]
pub struct StillMotion {
    pub joints: usize,
    pub duration: Real,
}

impl MotionSource for StillMotion {
    fn duration(&self) -> Real {
        self.duration
    }
    fn sample(&self, t: Real, out: &mut Pose) {
        *out = Pose::rest(self.joints);
        out.time = t.clamp(0.0, self.duration);
    }
}

/// A body that never moves: the pose is ignored.
#[derive(Clone, Debug)]
pub struct StaticBody {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl BodyModel for StaticBody {
    fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    fn pose(&mut self, pose: &Pose, out: &mut BodyFrame) {
        out.time = pose.time;
        out.positions.clone_from(&self.positions);
        out.velocities.clear();
    }
}

/// No body: nothing collides.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoCollider;

impl Collider for NoCollider {
    fn name(&self) -> &'static str {
        "none"
    }
    fn update(&mut self, _body: &BodyFrame) {}
    fn resolve(&mut self, _points: &mut [Vec3], _contacts: &mut Vec<Contact>) {}
    fn signed_distance(&self, _p: &Vec3) -> Option<Real> {
        None
    }
}

/// A cloth that does not move (only its clock advances).
#[derive(Clone, Copy, Debug, Default)]
pub struct FrozenCloth;

impl ClothSolver for FrozenCloth {
    fn step_frame(
        &mut self,
        frame: &mut CoarseFrame,
        dt: Real,
        _collider: &mut dyn Collider,
    ) -> StepReport {
        frame.time += dt;
        StepReport {
            substeps: 1,
            min_substep: dt,
            ..StepReport::default()
        }
    }
}

/// Level-0 refinement: the fine surface is the coarse triangle mesh itself.
#[derive(Clone, Debug)]
pub struct FlatRefiner {
    pub triangles: Vec<[u32; 3]>,
}

impl Refiner for FlatRefiner {
    fn refine(
        &mut self,
        coarse_positions: &[Vec3],
        coarse_normals: &[Vec3],
        out: &mut FineSurface,
    ) {
        out.positions.clear();
        out.positions.extend_from_slice(coarse_positions);
        out.normals.clear();
        out.normals.extend_from_slice(coarse_normals);
        if out.triangles != self.triangles {
            out.triangles.clone_from(&self.triangles);
            out.segments = 1;
            out.coarse_triangles.clone_from(&self.triangles);
            out.lattice = self.triangles.iter().flatten().copied().collect();
            out.sources = vec![FineVertexSource::default(); coarse_positions.len()];
            for (fi, t) in self.triangles.iter().enumerate() {
                for (k, &v) in t.iter().enumerate() {
                    let mut bary = [0.0; 3];
                    bary[k] = 1.0;
                    out.sources[v as usize] = FineVertexSource {
                        face: fi as u32,
                        bary,
                        level: 0,
                    };
                }
            }
        }
    }
}

/// No detail: the refined surface is final.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoDetail;

impl DetailModel for NoDetail {
    fn apply(
        &mut self,
        _coarse: &CoarseFrame,
        _fine: &mut FineSurface,
        _collider: &mut dyn Collider,
    ) {
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trivial_stages_compose() {
        let motion = StillMotion {
            joints: 3,
            duration: 2.0,
        };
        let mut pose = Pose::default();
        motion.sample(5.0, &mut pose);
        assert_eq!(pose.time, 2.0);
        assert_eq!(pose.local_rotations.len(), 3);
        let mut body = StaticBody {
            positions: vec![Vec3::x(); 3],
            triangles: vec![[0, 1, 2]],
        };
        let mut frame = BodyFrame::default();
        body.pose(&pose, &mut frame);
        assert_eq!(frame.positions.len(), 3);
        let mut collider: Box<dyn Collider> = Box::new(NoCollider);
        collider.update(&frame);
        let mut pts = vec![Vec3::zeros()];
        let mut contacts = Vec::new();
        collider.resolve(&mut pts, &mut contacts);
        assert!(contacts.is_empty());
        let mut cloth = CoarseFrame::at_rest(vec![Vec3::zeros(), Vec3::x(), Vec3::y()]);
        let report = FrozenCloth.step_frame(&mut cloth, 0.5, collider.as_mut());
        assert_eq!(cloth.time, 0.5);
        assert_eq!(report.substeps, 1);
        let mut refiner = FlatRefiner {
            triangles: vec![[0, 1, 2]],
        };
        let mut fine = FineSurface::default();
        refiner.refine(&cloth.positions, &[Vec3::z(); 3], &mut fine);
        assert_eq!(fine.sources[2].bary, [0.0, 0.0, 1.0]);
        NoDetail.apply(&cloth, &mut fine, collider.as_mut());
        assert_eq!(fine.positions, cloth.positions);
    }
}
