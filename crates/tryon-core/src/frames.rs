//! The plain-data frames passed between stages: public fields, no behaviour beyond small helpers.

use crate::math::{Real, Vec3};

/// The body at one instant: deformed vertex positions and velocities (same order as the body mesh the
/// collider was built with).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BodyFrame {
    pub time: Real,
    pub positions: Vec<Vec3>,
    /// Vertex velocities (m/s); empty means a body at rest.
    pub velocities: Vec<Vec3>,
}

/// One resolved contact between a point and the body.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Contact {
    /// Index of the point (cloth particle or fine vertex).
    pub point: u32,
    /// Body triangle the point was projected onto.
    pub face: u32,
    /// Barycentric coordinates of the contact on that triangle.
    pub bary: [Real; 3],
    /// Outward unit normal of the body at the contact.
    pub normal: Vec3,
    /// How deep the point was inside before it was moved out (m, >= 0).
    pub depth: Real,
    /// Velocity of the body surface at the contact (m/s).
    pub body_velocity: Vec3,
}

/// What happened while stepping one frame. Stepping never fails; problems are counted here.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StepReport {
    /// Accepted substeps.
    pub substeps: u32,
    /// Substeps rejected (non-finite or exploding state) and retried at half the step.
    pub retries: u32,
    /// Particles rolled back to their last good state because even the smallest step failed.
    pub rollbacks: u32,
    /// Non-finite values detected (in rejected substeps or rolled-back particles).
    pub non_finite_events: u32,
    /// Smallest substep used (s).
    pub min_substep: Real,
    /// Contacts at the end of the frame.
    pub contacts: u32,
    /// Sub-frames the body moved in (set by the pipeline; the most over accumulated reports).
    pub body_parts: u32,
}

impl StepReport {
    /// Adds another report's counts into this one.
    pub fn accumulate(&mut self, o: &StepReport) {
        self.substeps += o.substeps;
        self.retries += o.retries;
        self.rollbacks += o.rollbacks;
        self.non_finite_events += o.non_finite_events;
        self.min_substep = if self.min_substep == 0.0 {
            o.min_substep
        } else {
            self.min_substep.min(o.min_substep)
        };
        self.contacts = o.contacts;
        self.body_parts = self.body_parts.max(o.body_parts);
    }
}

/// The coarse cloth after a frame of dynamics.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoarseFrame {
    pub time: Real,
    pub positions: Vec<Vec3>,
    pub velocities: Vec<Vec3>,
    /// Net spring (elastic) force on each particle at the end of the frame (N); the wrinkle stage uses it.
    pub elastic_force: Vec<Vec3>,
    pub contacts: Vec<Contact>,
}

impl CoarseFrame {
    /// A frame at rest at the given positions.
    pub fn at_rest(positions: Vec<Vec3>) -> Self {
        let n = positions.len();
        CoarseFrame {
            time: 0.0,
            positions,
            velocities: vec![Vec3::zeros(); n],
            elastic_force: vec![Vec3::zeros(); n],
            contacts: Vec::new(),
        }
    }
}

/// Where a fine vertex comes from on the coarse mesh.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FineVertexSource {
    /// Coarse triangle (in the coarse mesh's triangulated view).
    pub face: u32,
    pub bary: [Real; 3],
    /// Subdivision level at which the vertex first appears (0 = a coarse vertex).
    pub level: u8,
}

/// The fine surface built from the coarse cloth.
///
/// Layout: every coarse triangle `(a, b, c)` (the coarse mesh's triangulated view) carries a
/// triangular lattice of `segments` steps per side. Lattice point `(i, j)`, `i + j <= segments`, has
/// barycentric weights `((n - i - j) / n, i / n, j / n)` on `(a, b, c)`, so `(0, 0)` is `a`, `(n, 0)`
/// is `b` and `(0, n)` is `c`; its fine vertex is `lattice[t * lattice_len(n) + lattice_index(n, i, j)]`.
/// Fine vertices `0..coarse count` are the coarse vertices themselves; a vertex on a coarse edge
/// exists once and is shared by the lattices of both triangles along that edge.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FineSurface {
    pub positions: Vec<Vec3>,
    /// Unit normals (the refiner's interpolated normals until a detail model blends them).
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub sources: Vec<FineVertexSource>,
    /// Lattice steps along each coarse edge (1 = the coarse mesh itself).
    pub segments: u32,
    /// The coarse triangles the lattices are laid on.
    pub coarse_triangles: Vec<[u32; 3]>,
    /// Fine vertex of every lattice point of every coarse triangle (see the type's docs).
    pub lattice: Vec<u32>,
}

/// Number of points in a triangular lattice of `n` steps per side.
pub fn lattice_len(n: u32) -> usize {
    let n = n as usize;
    (n + 1) * (n + 2) / 2
}

/// Position of lattice point `(i, j)` (`i + j <= n`) in a lattice's point list: rows of constant `j`,
/// each running over `i = 0..=n - j`.
pub fn lattice_index(n: u32, i: u32, j: u32) -> usize {
    let (n, i, j) = (n as usize, i as usize, j as usize);
    j * (n + 1) - j * j.saturating_sub(1) / 2 + i
}
