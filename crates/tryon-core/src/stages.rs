//! The stage contracts: small object-safe traits over plain data. The caller owns the state; a stage
//! owns only scratch memory. Each trait has a trivial implementation so a stage can be tested alone.
//!
//! The frame loop (tryon-pipeline) holds one object per seam: a [`MotionSource`] and a
//! [`BodyModel`] (the body), a [`Follower`] (P1.3.4), a [`Collider`], a [`ClothSolver`] and an
//! ordered list of [`SurfaceStage`]s (P1 section 4), and calls nothing else per frame but the
//! garment's attachments.

pub use crate::capabilities::Capabilities;
use crate::frames::{BodyFrame, CoarseFrame, Contact, FineSurface, FineVertexSource, StepReport};
use crate::interact::Handle;
pub use crate::length::{LengthJudgement, RESTORED_WITHIN};
use crate::math::{Real, Vec3};
use crate::pose::{Pose, Skeleton};

/// A motion: the pose at time t.
pub trait MotionSource: Send {
    /// Length of the clip (s).
    fn duration(&self) -> Real;
    /// Writes the pose at time `t` (clamped to the clip) into `out`.
    fn sample(&self, t: Real, out: &mut Pose);
}

/// A body that can be posed into a deformed mesh (the vertices of the rest mesh it was built from,
/// in the same order).
pub trait BodyModel: Send {
    /// Deforms the body into `pose`, writing positions (and velocities when it can) into `out`.
    fn pose(&mut self, pose: &Pose, out: &mut BodyFrame);
    /// The body's positions in `pose`, leaving the model's state (its velocity estimate) alone: for
    /// exports and pictures of recorded frames.
    fn shape_at(&self, pose: &Pose, out: &mut Vec<Vec3>);
    /// `shape_at` for the pose the body is posed in next (the pipeline asks where a frame ends
    /// before moving the body there): a model may keep the shape, and a following `pose` with the
    /// same joints and root takes it instead of deforming the body again.
    fn shape_next(&mut self, pose: &Pose, out: &mut Vec<Vec3>) {
        self.shape_at(pose, out);
    }
    /// The skeleton and skin weights, when the body is skinned (exports write a skinned mesh; the
    /// follower carries the cloth with the root joint).
    fn rig(&self) -> Option<Rig<'_>> {
        None
    }
    /// The offsets of the rest mesh's vertices (index, offset) that, skinned with `pose`, give
    /// what the model adds after skinning (its press): an export's per-frame morph of a skinned
    /// body. Empty when it adds nothing.
    fn skin_offsets_at(&self, _pose: &Pose, out: &mut Vec<(u32, Vec3)>) {
        out.clear();
    }
    /// What the model changed after skinning (parts pressed apart where skinning passed them into
    /// each other), over the poses so far; `None` when it changes nothing.
    fn corrections(&self) -> Option<BodyCorrections> {
        None
    }
    /// The state this stage carries from one frame into the next, for a checkpoint; `None`
    /// when it cannot be checkpointed (`crate::state`).
    fn save_state(&self) -> Option<Vec<u8>> {
        None
    }
    /// Takes back a state [`save_state`](Self::save_state) gave, on a stage built the same way.
    fn restore_state(&mut self, _state: &[u8]) -> Result<(), crate::state::StateError> {
        Err(crate::state::StateError::Unsupported)
    }
}

/// A body model's changes after skinning, over the poses it has made.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyCorrections {
    /// Poses made.
    pub poses: usize,
    /// Vertices moved, summed over the poses.
    pub moved: usize,
    /// The deepest overlap of two parts found (m), before it was pressed out.
    pub deepest: Real,
}

/// A skinned body's rig, borrowed: rest mesh, skeleton, global rest joint positions and four
/// (joint, weight) influences per vertex.
#[derive(Clone, Copy, Debug)]
pub struct Rig<'a> {
    pub rest_positions: &'a [Vec3],
    pub skeleton: &'a Skeleton,
    pub joint_rest: &'a [Vec3],
    pub joints: &'a [[u16; 4]],
    pub weights: &'a [[Real; 4]],
}

impl Rig<'_> {
    /// The root joint (the first without a parent; 0 for an empty skeleton) and its rest position.
    pub fn root(&self) -> (usize, Vec3) {
        let root = self
            .skeleton
            .parents
            .iter()
            .position(|p| p.is_none())
            .unwrap_or(0);
        (root, self.joint_rest.get(root).copied().unwrap_or_default())
    }
}

/// P1.3.4, body following: cloth near the body is carried with it when the body moves, before the
/// cloth is stepped against the body's new shape.
pub trait Follower: Send {
    /// Starts following: the body at time 0 (in `pose`) and the cloth as it starts.
    fn start(&mut self, pose: &Pose, body: &BodyFrame, cloth: &[Vec3]);
    /// The body moved to `body` (in `pose`) over `dt`: carries the cloth's positions and
    /// velocities with it, and writes into `body.velocities` the body's velocities in the frame
    /// the cloth is now simulated in.
    fn carry(&mut self, pose: &Pose, body: &mut BodyFrame, cloth: &mut CoarseFrame, dt: Real);
    /// Records the cloth against the body after the step.
    fn record(&mut self, cloth: &[Vec3]);
    /// The state this stage carries from one frame into the next, for a checkpoint; `None`
    /// when it cannot be checkpointed (`crate::state`).
    fn save_state(&self) -> Option<Vec<u8>> {
        None
    }
    /// Takes back a state [`save_state`](Self::save_state) gave, on a stage built the same way.
    fn restore_state(&mut self, _state: &[u8]) -> Result<(), crate::state::StateError> {
        Err(crate::state::StateError::Unsupported)
    }
}

/// Collision between points and the body.
pub trait Collider: Send {
    /// Short name for reports.
    fn name(&self) -> &'static str;
    /// Which optional methods (focus, pinch, sweep, pokes) it implements; the rest do nothing.
    fn capabilities(&self) -> Capabilities;
    /// Takes the body's new shape. Called whenever the body moved.
    fn update(&mut self, body: &BodyFrame);
    /// The bounds of the cloth (`lo` to `hi`), given before each [`Collider::update`]: a collider
    /// may leave out of its work the body farther from them than the cloth can move in a frame.
    /// The default ignores them.
    fn focus(&mut self, _lo: &Vec3, _hi: &Vec3) {}
    /// Moves every point found inside the body onto its surface and appends one contact per moved
    /// point. The same point slice (same length, same order) is expected on every call.
    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>);
    /// Signed distance from `p` to the body surface (negative inside), if the collider can say.
    fn signed_distance(&self, p: &Vec3) -> Option<Real>;
    /// The state this stage carries from one frame into the next, for a checkpoint; `None`
    /// when it cannot be checkpointed (`crate::state`).
    fn save_state(&self) -> Option<Vec<u8>> {
        None
    }
    /// Takes back a state [`save_state`](Self::save_state) gave, on a stage built the same way.
    fn restore_state(&mut self, _state: &[u8]) -> Result<(), crate::state::StateError> {
        Err(crate::state::StateError::Unsupported)
    }
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
    /// The body surface across a pinch. For each listed point (as in [`Collider::probe`]) with
    /// `first[k]` its probe (the nearest surface), the nearest surface within `reach` of it that
    /// faces that one from the other side, as a probe of its own (signed distance, outward
    /// normal), or [`Probe::FAR`] when there is none: where an arm is pressed against the torso, a
    /// point whose probe found the torso gets the arm. Held off both, the cloth between is
    /// squeezed instead of being pushed out of one part into the other. The default knows no
    /// second surface.
    fn probe_opposite(
        &mut self,
        points: &[Vec3],
        which: &[u32],
        first: &[Probe],
        reach: Real,
        out: &mut Vec<Probe>,
    ) {
        let _ = (points, first, reach);
        out.clear();
        out.resize(which.len(), Probe::FAR);
    }
    /// Continuous collision: `end` holds where the points `start` moved to over a step during
    /// which the body went through the fraction `span` of its last move (0 = its shape before the
    /// last [`Collider::update`], 1 = the shape that call gave it). Every point whose path crosses
    /// the body's surface inward is stopped: put where the surface point it hit is at the step's
    /// end, the collider's thickness out along the normal there, with a contact appended to
    /// `contacts`. Returns whether the collider tested the paths; the default cannot, and changes
    /// nothing.
    fn sweep(
        &mut self,
        start: &[Vec3],
        end: &mut [Vec3],
        span: [Real; 2],
        contacts: &mut Vec<Contact>,
    ) -> bool {
        let _ = (start, end, span, contacts);
        false
    }
    /// Body vertices under cloth triangles. For each triangle listed in `which` (indices into
    /// `triangles`, whose corners index `points`, the slice [`Collider::probe`] was given), the
    /// body vertices whose projection along the triangle's normal falls inside it, with the
    /// cloth's height over them along their outward normal, `s = n . (q - v)` (q the projection),
    /// in [-`depth`, `reach`): features narrower than the cloth's triangles (a nipple, a
    /// shoulder's tip, a knuckle) poke through between particles that are all outside, where
    /// no test of the particles can see them. Written to `out` (cleared first) in the order of
    /// `which`. The default knows no vertices and finds none.
    fn pokes(
        &mut self,
        points: &[Vec3],
        triangles: &[[u32; 3]],
        which: &[u32],
        (reach, depth): (Real, Real),
        out: &mut Vec<Poke>,
    ) {
        let _ = (points, triangles, which, reach, depth);
        out.clear();
    }
}

/// A body vertex under a cloth triangle ([`Collider::pokes`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Poke {
    /// The cloth triangle (index into the triangles the caller gave).
    pub triangle: u32,
    /// Barycentric coordinates of the triangle's point over the vertex.
    pub bary: [Real; 3],
    /// The body vertex and its outward unit normal.
    pub point: Vec3,
    pub normal: Vec3,
}

/// What a collider says about one point: signed distance to the body (negative inside) and the
/// body's outward unit normal at the closest point (zero when unknown).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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

/// What a cloth solver is, for reports and metrics.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClothInfo {
    /// The method's name (the integrator), as stats.json reports it.
    pub method: &'static str,
    /// The substep used when nothing goes wrong (s).
    pub nominal_substep: Real,
    pub particles: usize,
    /// Force elements (springs), for reports.
    pub springs: usize,
    /// Structural edges (particle pairs) and their rest lengths: stretch is judged on these.
    pub edges: Vec<[u32; 2]>,
    pub rest: Vec<Real>,
    /// Mass of every particle (kg), for energies.
    pub masses: Vec<Real>,
}

/// What a solver with contact between layers of cloth did to the starting shape before its
/// first step: layers modelled crossing or touching pulled apart.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Untangled {
    /// Crossing triangle pairs before and after.
    pub crossings_before: usize,
    pub crossings_after: usize,
    /// Pairs nearer than nine tenths of the gap after.
    pub near_after: usize,
    /// Vertices moved, and the farthest move (m).
    pub moved: usize,
    pub farthest: Real,
}

/// One frame of coarse cloth dynamics against a collider.
pub trait ClothSolver: Send {
    /// What the solver is (constant over its life but for the grabbed particles).
    fn info(&self) -> ClothInfo;
    /// The cloth's state before the first frame: at rest, handles at their paths' starts.
    fn initial_frame(&self) -> CoarseFrame;
    /// Advances `frame` by `dt`, resolving collisions with `collider`. Never fails: non-finite or
    /// exploding state is retried smaller or rolled back, and reported.
    fn step_frame(
        &mut self,
        frame: &mut CoarseFrame,
        dt: Real,
        collider: &mut dyn Collider,
    ) -> StepReport;
    /// Holds the kinematic handles `first..first + targets.len()` (in the order the solver was
    /// built with) at `targets` from now on, as elastic bands bound to the moving body are.
    /// Handles it does not have and non-finite targets are ignored.
    fn hold_handles(&mut self, first: usize, targets: &[Vec3]);
    /// Draws each of `particles` toward its point of `targets` by a spring of `stiffness` (N/m)
    /// from now on (0 lets it go): a soft hold, which yields where contact disagrees. Solvers
    /// without soft holds ignore it.
    fn anchor(&mut self, particles: &[u32], targets: &[Vec3], stiffness: Real) {
        let _ = (particles, targets, stiffness);
    }
    /// Hands `handle.particle` to a scripted path from now on (a user grabbing the cloth). A
    /// particle it does not have, or an empty path, is ignored.
    fn grab(&mut self, handle: Handle);
    /// Lets go of a particle [`grab`](Self::grab) took (the user letting go of the cloth): it
    /// moves freely again from where it is. A particle not grabbed is ignored.
    fn release(&mut self, particle: u32) {
        let _ = particle;
    }
    /// What untangling the starting shape did, once the first step ran (solvers with contact
    /// between layers of cloth; `None` for the others).
    fn untangled(&self) -> Option<Untangled> {
        None
    }
    /// A copy of the solver in its present state, where it can make one: a benchmark replays one
    /// frame from the same state, which includes what the solver remembers between frames (VBD's
    /// last frame end, from which self-contact judges the carry). `None` by default.
    fn boxed_clone(&self) -> Option<Box<dyn ClothSolver>> {
        None
    }
    /// The state this stage carries from one frame into the next, for a checkpoint; `None`
    /// when it cannot be checkpointed (`crate::state`).
    fn save_state(&self) -> Option<Vec<u8>> {
        None
    }
    /// Takes back a state [`save_state`](Self::save_state) gave, on a stage built the same way.
    fn restore_state(&mut self, _state: &[u8]) -> Result<(), crate::state::StateError> {
        Err(crate::state::StateError::Unsupported)
    }
}

/// Where a surface stage's work is timed: `work` runs once, its wall time counted under `part`.
pub trait Clock {
    fn time(&mut self, part: &'static str, work: &mut dyn FnMut());
}

/// A clock that only runs the work.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Untimed;

impl Clock for Untimed {
    fn time(&mut self, _part: &'static str, work: &mut dyn FnMut()) {
        work()
    }
}

/// What the surface stages read: the coarse frame just stepped, and the body when it moved.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInput<'a> {
    pub coarse: &'a CoarseFrame,
    pub body: Option<&'a BodyFrame>,
}

/// One stage of the detailed surface (P1 section 4: refinement, wrinkles, fine collision, normal
/// blending), run in order on the pipeline's [`FineSurface`] after each coarse frame.
pub trait SurfaceStage: Send {
    /// Names of the timed parts this stage runs, in order: what `tryon check` lists and
    /// stats.json times. A stage that would do nothing is not assembled.
    fn parts(&self) -> Vec<&'static str>;
    /// Updates `surface` from `input`, timing each part on `clock`.
    fn run(&mut self, input: &SurfaceInput<'_>, surface: &mut FineSurface, clock: &mut dyn Clock);
    /// How far `surface` gives back the length the coarse cloth lost, if this stage can judge it.
    fn length_error(&self, _surface: &FineSurface) -> Option<LengthJudgement> {
        None
    }
    /// The state this stage carries from one frame into the next, for a checkpoint; `None`
    /// when it cannot be checkpointed (`crate::state`).
    fn save_state(&self) -> Option<Vec<u8>> {
        None
    }
    /// Takes back a state [`save_state`](Self::save_state) gave, on a stage built the same way.
    fn restore_state(&mut self, _state: &[u8]) -> Result<(), crate::state::StateError> {
        Err(crate::state::StateError::Unsupported)
    }
}

/// A motion that holds the rest pose.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
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
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct StaticBody {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl BodyModel for StaticBody {
    crate::whole_state!();
    fn pose(&mut self, pose: &Pose, out: &mut BodyFrame) {
        out.time = pose.time;
        out.positions.clone_from(&self.positions);
        out.velocities.clear();
    }
    fn shape_at(&self, _pose: &Pose, out: &mut Vec<Vec3>) {
        out.clone_from(&self.positions);
    }
}

/// No body: nothing collides.
#[derive(Clone, Copy, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct NoCollider;

impl Collider for NoCollider {
    crate::whole_state!();
    fn name(&self) -> &'static str {
        "none"
    }
    fn capabilities(&self) -> Capabilities {
        Capabilities::NONE
    }
    fn update(&mut self, _body: &BodyFrame) {}
    fn resolve(&mut self, _points: &mut [Vec3], _contacts: &mut Vec<Contact>) {}
    fn signed_distance(&self, _p: &Vec3) -> Option<Real> {
        None
    }
}

/// A cloth that does not move (only its clock advances).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct FrozenCloth {
    pub rest: Vec<Vec3>,
}

impl ClothSolver for FrozenCloth {
    crate::whole_state!();
    fn info(&self) -> ClothInfo {
        ClothInfo {
            method: "frozen",
            particles: self.rest.len(),
            ..ClothInfo::default()
        }
    }
    fn initial_frame(&self) -> CoarseFrame {
        CoarseFrame::at_rest(self.rest.clone())
    }
    fn hold_handles(&mut self, _first: usize, _targets: &[Vec3]) {}
    fn grab(&mut self, _handle: Handle) {}
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

/// Level-0 refinement: the fine surface is the coarse triangle mesh itself, with its vertex normals.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct FlatRefiner {
    pub triangles: Vec<[u32; 3]>,
    normals: Vec<Vec3>,
}

impl FlatRefiner {
    pub fn new(triangles: Vec<[u32; 3]>) -> Self {
        FlatRefiner {
            triangles,
            normals: Vec::new(),
        }
    }
}

impl SurfaceStage for FlatRefiner {
    crate::whole_state!();
    fn parts(&self) -> Vec<&'static str> {
        vec!["refine"]
    }
    fn run(&mut self, input: &SurfaceInput<'_>, out: &mut FineSurface, clock: &mut dyn Clock) {
        let coarse_positions = &input.coarse.positions;
        clock.time("refine", &mut || {
            crate::math::vertex_normals(coarse_positions, &self.triangles, &mut self.normals);
            self.flatten(coarse_positions, out);
        });
    }
}

impl FlatRefiner {
    fn flatten(&self, coarse_positions: &[Vec3], out: &mut FineSurface) {
        let coarse_normals = &self.normals;
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
        let mut solver = FrozenCloth {
            rest: vec![Vec3::zeros(), Vec3::x(), Vec3::y()],
        };
        let mut cloth = solver.initial_frame();
        let report = solver.step_frame(&mut cloth, 0.5, collider.as_mut());
        assert_eq!(cloth.time, 0.5);
        assert_eq!(report.substeps, 1);
        assert_eq!(solver.info().particles, 3);
        let mut refiner = FlatRefiner::new(vec![[0, 1, 2]]);
        assert_eq!(refiner.parts(), ["refine"]);
        let mut fine = FineSurface::default();
        let input = SurfaceInput {
            coarse: &cloth,
            body: None,
        };
        refiner.run(&input, &mut fine, &mut Untimed);
        assert_eq!(fine.sources[2].bary, [0.0, 0.0, 1.0]);
        assert_eq!(fine.positions, cloth.positions);
        // The triangle lies in z = 0, wound counter-clockwise seen from +z.
        assert_eq!(fine.normals, vec![Vec3::z(); 3]);
    }
}
