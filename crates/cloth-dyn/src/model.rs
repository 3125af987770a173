//! The cloth model built once from a mesh: springs (structure-of-arrays), lumped masses, pins and
//! kinematic handles.

use crate::params::{ClothParams, ParamError};
use std::collections::HashSet;
use std::ops::Range;
use thiserror::Error;
use tryon_core::frames::CoarseFrame;
pub use tryon_core::interact::Handle;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::stages::ClothInfo;
use tryon_core::topology::{Csr, NO_FACE, Topology, TopologyError};

/// Which family a spring belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SpringKind {
    /// On mesh edges; asymmetric stiffness (P1 eq. 1).
    Structural,
    /// Across quad diagonals.
    Shear,
    /// Skipping one vertex across each interior edge (bending).
    Bend,
}

/// Springs as structure-of-arrays.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpringSet {
    pub i: Vec<u32>,
    pub j: Vec<u32>,
    pub rest: Vec<Real>,
    /// Stiffness when longer than rest (N/m).
    pub k_stretch: Vec<Real>,
    /// Stiffness when shorter than rest (N/m).
    pub k_compress: Vec<Real>,
    /// Viscous damping along the spring (N s/m).
    pub damping: Vec<Real>,
}

impl SpringSet {
    /// Number of springs.
    pub fn len(&self) -> usize {
        self.i.len()
    }

    /// True when there are no springs.
    pub fn is_empty(&self) -> bool {
        self.i.is_empty()
    }

    fn push(&mut self, a: u32, b: u32, rest: Real, ks: Real, kc: Real, c: Real) {
        self.i.push(a);
        self.j.push(b);
        self.rest.push(rest);
        self.k_stretch.push(ks);
        self.k_compress.push(kc);
        self.damping.push(c);
    }
}

/// One spring as the force loop reads it: both ends and every constant in one 40-byte record, with
/// the stiffnesses already divided by rest length (eq. 1 uses k / L).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PackedSpring {
    pub i: u32,
    pub j: u32,
    pub rest: Real,
    pub stretch_per_rest: Real,
    pub compress_per_rest: Real,
    pub damping: Real,
}

impl SpringSet {
    /// The springs packed for the force loop.
    pub fn packed(&self) -> Vec<PackedSpring> {
        (0..self.len())
            .map(|k| PackedSpring {
                i: self.i[k],
                j: self.j[k],
                rest: self.rest[k],
                stretch_per_rest: self.k_stretch[k] / self.rest[k],
                compress_per_rest: self.k_compress[k] / self.rest[k],
                damping: self.damping[k],
            })
            .collect()
    }
}

/// Why a cloth model could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum BuildClothError {
    #[error("cloth mesh: {0}")]
    Topology(#[from] TopologyError),
    #[error(transparent)]
    Param(#[from] ParamError),
    #[error("handle on particle {particle}, but the cloth has only {count} particles")]
    HandleOutOfRange { particle: u32, count: usize },
    #[error("handle on particle {particle} has an empty path")]
    EmptyHandlePath { particle: u32 },
    #[error("handle on particle {particle}: key {key} is not finite or its time goes backwards")]
    BadHandleKey { particle: u32, key: usize },
}

/// Everything about a cloth that does not change while it moves.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ClothModel {
    pub springs: SpringSet,
    /// Index ranges of each kind in `springs`: structural, shear, bend.
    pub structural: Range<usize>,
    pub shear: Range<usize>,
    pub bend: Range<usize>,
    pub mass: Vec<Real>,
    /// 0 for pinned and handled particles.
    pub inv_mass: Vec<Real>,
    /// Area lumped to each particle (m^2), for air drag.
    pub area: Vec<Real>,
    pub handles: Vec<Handle>,
    /// Particles handed to a path after the model was built ([`ClothModel::take_handle`]: a
    /// user's grab), the only handles [`ClothModel::release_handle`] lets go.
    #[serde(default)]
    pub grabbed: Vec<u32>,
    pub topology: Topology,
    /// Triangulated view of the cloth mesh.
    pub triangles: Vec<[u32; 3]>,
    pub rest_positions: Vec<Vec3>,
    /// Neighbours of each particle through structural and shear springs (the springs the strain
    /// limit acts on), with the rest length of each link in `limit_graph_rest`.
    pub limit_graph: Csr,
    pub limit_graph_rest: Vec<Real>,
    /// `springs` packed for the force loop (kept in step with `springs` by [`ClothModel::build`]).
    pub packed: Vec<PackedSpring>,
    /// Structural and shear springs packed for the strain limit.
    pub limit_springs: Vec<crate::strain::LimitSpring>,
    /// Bending springs packed for the bending limit.
    pub bend_limit_springs: Vec<crate::strain::LimitSpring>,
    /// Stretch-only constraints along straight lines, coarse scales first (see [`crate::lines`]).
    pub long_range_springs: Vec<crate::strain::LimitSpring>,
    /// Stencils of the quadratic bending model (empty unless `bending_rigidity > 0`).
    pub hinges: Vec<crate::hinges::Hinge>,
    /// Per particle, the garment it belongs to (0 for a cloth of one garment; see
    /// [`ClothModel::wear`]).
    pub garment: Vec<u16>,
    /// Per particle, its garment's layer (higher is worn over lower).
    pub layer: Vec<u32>,
    /// Per spring, its garment's stiffness as a multiple of the parameters' (the solvers that
    /// take stiffness from their own settings, VBD and XPBD, scale by it).
    pub spring_scale: Vec<Real>,
    /// The bend springs changed after building ([`ClothModel::change_bends`], P3's folds): each
    /// spring's index and the stiffness scale it was given.
    pub changed_bends: Vec<(usize, Real)>,
}

impl ClothModel {
    /// Builds springs and masses from `mesh` at its current shape (which is the rest shape).
    pub fn build(
        mesh: &PolyMesh,
        params: &ClothParams,
        handles: Vec<Handle>,
    ) -> Result<Self, BuildClothError> {
        Self::build_with_kinematic(mesh, params, handles, &[])
    }

    /// [`ClothModel::build`] with `kinematic` particles: infinitely heavy (inverse mass 0), so that
    /// forces do not move them and they do not limit the substep; the caller places them (e.g.
    /// pieces attached to the garment beneath).
    pub fn build_with_kinematic(
        mesh: &PolyMesh,
        params: &ClothParams,
        handles: Vec<Handle>,
        kinematic: &[u32],
    ) -> Result<Self, BuildClothError> {
        params.validate()?;
        if let Some(&k) = kinematic
            .iter()
            .find(|k| **k as usize >= mesh.positions.len())
        {
            return Err(BuildClothError::HandleOutOfRange {
                particle: k,
                count: mesh.positions.len(),
            });
        }
        let topology = Topology::build(mesh)?;
        let n = mesh.positions.len();
        for h in &handles {
            if h.particle as usize >= n {
                return Err(BuildClothError::HandleOutOfRange {
                    particle: h.particle,
                    count: n,
                });
            }
            if h.path.is_empty() {
                return Err(BuildClothError::EmptyHandlePath {
                    particle: h.particle,
                });
            }
            for (k, (t, p)) in h.path.iter().enumerate() {
                let backwards = k > 0 && *t < h.path[k - 1].0;
                if !t.is_finite() || !tryon_core::math::is_finite(p) || backwards {
                    return Err(BuildClothError::BadHandleKey {
                        particle: h.particle,
                        key: k,
                    });
                }
            }
        }
        let pos = &mesh.positions;
        let mut springs = SpringSet::default();
        let c = params.spring_damping;
        let add = |s: &mut SpringSet, a: u32, b: u32, ks: Real, kc: Real, scale: Real| {
            let rest = (pos[a as usize] - pos[b as usize]).norm() * scale;
            s.push(a, b, rest, ks, kc, c);
        };
        let r = params.rest_scale;
        for &[a, b] in &topology.edges {
            add(&mut springs, a, b, params.k_stretch, params.k_compress, r);
        }
        let structural = 0..springs.len();
        for f in &mesh.faces {
            if let Face::Quad([a, b, cc, d]) = *f {
                add(&mut springs, a, cc, params.k_shear, params.k_shear, r);
                add(&mut springs, b, d, params.k_shear, params.k_shear, r);
            }
        }
        let shear = structural.end..springs.len();
        // Flexion springs only when they do something: a stiffness or the bending limit.
        if params.k_bend > 0.0 || params.min_bend_ratio.is_some() {
            for (a, b) in bend_pairs(mesh, &topology) {
                add(&mut springs, a, b, params.k_bend, params.k_bend, 1.0);
            }
        }
        let bend = shear.end..springs.len();

        let (triangles, _) = mesh.triangulate();
        let mut area = vec![0.0; n];
        for t in &triangles {
            let [a, b, cc] = t.map(|v| pos[v as usize]);
            let third = 0.5 * (b - a).cross(&(cc - a)).norm() / 3.0;
            for &v in t {
                area[v as usize] += third;
            }
        }
        let mut mass: Vec<Real> = area.iter().map(|a| a * params.density).collect();
        if params.mass_floor > 0.0 && !mass.is_empty() {
            let mut sorted = mass.clone();
            sorted.sort_by(Real::total_cmp);
            let floor = params.mass_floor * sorted[sorted.len() / 2];
            // Particles without area (no face) stay massless, hence immobile.
            for m in mass.iter_mut().filter(|m| **m > 0.0) {
                *m = m.max(floor);
            }
        }
        let mut inv_mass: Vec<Real> = mass
            .iter()
            .map(|m| if *m > 0.0 { 1.0 / m } else { 0.0 })
            .collect();
        for h in &handles {
            inv_mass[h.particle as usize] = 0.0;
        }
        for &k in kinematic {
            inv_mass[k as usize] = 0.0;
        }
        let (limit_graph, limit_graph_rest) = spring_graph(&springs, 0..shear.end, n);
        let long_range_springs = if params.long_range {
            let scales = crate::lines::default_scales(n);
            crate::lines::long_range_pairs(mesh, &topology, &scales)
                .into_iter()
                .filter_map(|(i, j, rest)| crate::strain::LimitSpring::new(i, j, rest, &inv_mass))
                .collect()
        } else {
            Vec::new()
        };
        let hinges = crate::hinges::build_hinges(pos, &triangles, params.bending_rigidity);
        Ok(ClothModel {
            garment: vec![0; n],
            layer: vec![0; n],
            spring_scale: vec![1.0; springs.len()],
            changed_bends: Vec::new(),
            hinges,
            long_range_springs,
            limit_springs: crate::strain::limit_springs(&springs, 0..shear.end, &inv_mass),
            bend_limit_springs: crate::strain::limit_springs(&springs, bend.clone(), &inv_mass),
            packed: springs.packed(),
            limit_graph,
            limit_graph_rest,
            springs,
            structural,
            shear,
            bend,
            mass,
            inv_mass,
            area,
            handles,
            grabbed: Vec::new(),
            topology,
            triangles,
            rest_positions: pos.clone(),
        })
    }

    /// Number of particles.
    pub fn particle_count(&self) -> usize {
        self.mass.len()
    }

    /// Total mass (kg).
    pub fn total_mass(&self) -> Real {
        self.mass.iter().sum()
    }

    /// What a solver of this model reports: its `method`, `nominal_substep` and number of force
    /// `elements`, and the model's structural edges (stretch is judged on them) and masses.
    pub fn info(&self, method: &'static str, nominal_substep: Real, elements: usize) -> ClothInfo {
        let s = &self.springs;
        let structural = self.structural.clone();
        ClothInfo {
            method,
            nominal_substep,
            particles: self.particle_count(),
            springs: elements,
            edges: structural.clone().map(|k| [s.i[k], s.j[k]]).collect(),
            rest: structural.map(|k| s.rest[k]).collect(),
            masses: self.mass.clone(),
        }
    }

    /// The rest state, with handles at their path start.
    pub fn initial_frame(&self) -> CoarseFrame {
        let mut f = CoarseFrame::at_rest(self.rest_positions.clone());
        for h in &self.handles {
            f.positions[h.particle as usize] = h.position(0.0);
        }
        f
    }

    /// Makes `handle`'s particle kinematic, driven along its path. A particle taken before gets
    /// the new path (a drag moving on). Returns true when the particle was newly taken (the set of
    /// held particles changed); false, with nothing changed, for a particle out of range, an empty
    /// path, or a particle already held by the model's own pins, bands or kinematic set.
    pub fn take_handle(&mut self, handle: Handle) -> bool {
        let p = handle.particle as usize;
        if p >= self.particle_count() || handle.path.is_empty() {
            return false;
        }
        if self.grabbed.contains(&handle.particle) {
            if let Some(h) = self
                .handles
                .iter_mut()
                .rfind(|h| h.particle == handle.particle)
            {
                *h = handle;
            }
            return false;
        }
        if self.inv_mass[p] == 0.0 {
            return false;
        }
        self.inv_mass[p] = 0.0;
        self.grabbed.push(handle.particle);
        self.handles.push(handle);
        true
    }

    /// Lets go of a particle [`ClothModel::take_handle`] took: it answers to forces again from
    /// where it is. Returns false, with nothing changed, for a particle not taken so.
    pub fn release_handle(&mut self, particle: u32) -> bool {
        let Some(k) = self.grabbed.iter().position(|&g| g == particle) else {
            return false;
        };
        self.grabbed.remove(k);
        if let Some(h) = self.handles.iter().rposition(|h| h.particle == particle) {
            self.handles.remove(h);
        }
        let m = self.mass[particle as usize];
        self.inv_mass[particle as usize] = if m > 0.0 { 1.0 / m } else { 0.0 };
        true
    }

    /// Holds handles `first..` at `targets` from now on (non-finite targets are skipped).
    pub fn hold_handles(&mut self, first: usize, targets: &[Vec3]) {
        for (h, p) in self.handles.iter_mut().skip(first).zip(targets) {
            if tryon_core::math::is_finite(p) {
                h.path.clear();
                h.path.push((0.0, *p));
            }
        }
    }

    /// Sizes `frame` to the model and puts every non-finite particle back at rest; returns how
    /// many were.
    pub fn sanitize(&self, frame: &mut CoarseFrame) -> u32 {
        let n = self.particle_count();
        frame.positions.resize(n, Vec3::zeros());
        frame.velocities.resize(n, Vec3::zeros());
        let mut count = 0;
        for i in 0..n {
            let finite = tryon_core::math::is_finite;
            if !finite(&frame.positions[i]) || !finite(&frame.velocities[i]) {
                frame.positions[i] = self.rest_positions[i];
                frame.velocities[i] = Vec3::zeros();
                count += 1;
            }
        }
        count
    }
}

/// Adjacency of particles through the springs in `range`, with each link's rest length.
fn spring_graph(s: &SpringSet, range: Range<usize>, n: usize) -> (Csr, Vec<Real>) {
    let mut rows: Vec<Vec<(u32, Real)>> = vec![Vec::new(); n];
    for k in range {
        rows[s.i[k] as usize].push((s.j[k], s.rest[k]));
        rows[s.j[k] as usize].push((s.i[k], s.rest[k]));
    }
    let mut offsets = vec![0u32];
    let (mut items, mut rest) = (Vec::new(), Vec::new());
    for r in rows {
        for (v, l) in r {
            items.push(v);
            rest.push(l);
        }
        offsets.push(items.len() as u32);
    }
    (Csr { offsets, items }, rest)
}

/// Bending pairs: across each interior edge (a, b) with faces F and G, for each end v of the edge, the
/// neighbour of v in F other than the edge's other end is joined to the neighbour of v in G. On a
/// quad grid this is exactly Provot's flexion spring (i-1 to i+1); on triangles it joins the two
/// vertices opposite the edge.
fn bend_pairs(mesh: &PolyMesh, topo: &Topology) -> Vec<(u32, u32)> {
    let mut seen = HashSet::new();
    let mut out = Vec::new();
    for (e, &[a, b]) in topo.edges.iter().enumerate() {
        let [f, g] = topo.edge_faces[e];
        if g == NO_FACE {
            continue;
        }
        for (v, other) in [(a, b), (b, a)] {
            let p = neighbour_in_face(mesh.faces[f as usize].vertices(), v, other);
            let q = neighbour_in_face(mesh.faces[g as usize].vertices(), v, other);
            if let (Some(p), Some(q)) = (p, q)
                && p != q
                && seen.insert((p.min(q), p.max(q)))
            {
                out.push((p.min(q), p.max(q)));
            }
        }
    }
    out
}

/// The neighbour of `v` around `face` that is not `other`.
fn neighbour_in_face(face: &[u32], v: u32, other: u32) -> Option<u32> {
    let k = face.iter().position(|&x| x == v)?;
    let n = face.len();
    let (prev, next) = (face[(k + n - 1) % n], face[(k + 1) % n]);
    if prev == other {
        Some(next)
    } else {
        Some(prev)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;

    #[test]
    fn grid_springs_follow_provot() {
        let n = 4;
        let m = grid_xz(n, n, 1.0, 1.0, 0.0);
        let model = ClothModel::build(&m, &ClothParams::default(), vec![]).unwrap();
        assert_eq!(model.structural.len(), 2 * n * (n + 1));
        assert_eq!(model.shear.len(), 2 * n * n);
        // Flexion springs: every row and column, skipping one: 2 * (n+1) * (n-1).
        assert_eq!(model.bend.len(), 2 * (n + 1) * (n - 1));
        let h = 1.0 / n as Real;
        for s in model.bend.clone() {
            assert!(
                (model.springs.rest[s] - 2.0 * h).abs() < 1e-12,
                "bend spring {s} not 2h"
            );
        }
        assert!((model.total_mass() - 0.2).abs() < 1e-12);
    }

    #[test]
    fn handle_path_interpolates() {
        let h = Handle {
            particle: 0,
            path: vec![(0.0, Vec3::zeros()), (1.0, Vec3::new(2.0, 0.0, 0.0))],
        };
        assert_eq!(h.position(0.5), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(h.position(3.0), Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(h.velocity(0.5), Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(h.velocity(1.5), Vec3::zeros());
    }

    #[test]
    fn bad_handles_are_named() {
        let m = grid_xz(2, 2, 1.0, 1.0, 0.0);
        let p = ClothParams::default();
        let e = ClothModel::build(
            &m,
            &p,
            vec![Handle {
                particle: 99,
                path: vec![(0.0, Vec3::zeros())],
            }],
        );
        assert_eq!(
            e.unwrap_err(),
            BuildClothError::HandleOutOfRange {
                particle: 99,
                count: 9
            }
        );
        let bad = vec![Handle {
            particle: 1,
            path: vec![(1.0, Vec3::zeros()), (0.5, Vec3::zeros())],
        }];
        assert_eq!(
            ClothModel::build(&m, &p, bad).unwrap_err(),
            BuildClothError::BadHandleKey {
                particle: 1,
                key: 1
            }
        );
        let p = ClothParams {
            density: -1.0,
            ..ClothParams::default()
        };
        let msg = ClothModel::build(&m, &p, vec![]).unwrap_err().to_string();
        assert!(msg.contains("density") && msg.contains("-1"), "{msg}");
    }

    #[test]
    fn a_grab_is_taken_moved_on_and_let_go_but_a_pin_is_not() {
        let m = grid_xz(2, 2, 1.0, 1.0, 0.0);
        let pin = Handle {
            particle: 0,
            path: vec![(0.0, Vec3::zeros())],
        };
        let mut model = ClothModel::build(&m, &ClothParams::default(), vec![pin]).unwrap();
        let free = model.inv_mass[4];
        assert!(free > 0.0);
        let at = |x: Real| Handle {
            particle: 4,
            path: vec![(0.0, Vec3::new(x, 0.0, 0.0))],
        };
        assert!(model.take_handle(at(1.0)));
        assert_eq!((model.inv_mass[4], model.handles.len()), (0.0, 2));
        // Moving on replaces the path: still two handles, the new one last.
        assert!(!model.take_handle(at(2.0)));
        assert_eq!(model.handles.len(), 2);
        assert_eq!(model.handles[1].position(0.0), Vec3::new(2.0, 0.0, 0.0));
        // The pin keeps its particle: neither taken nor let go.
        assert!(!model.take_handle(Handle {
            particle: 0,
            ..at(3.0)
        }));
        assert!(!model.release_handle(0));
        assert_eq!(model.handles[0].particle, 0);
        assert!(model.release_handle(4));
        assert_eq!((model.inv_mass[4], model.handles.len()), (free, 1));
        assert!(!model.release_handle(4));
        assert!(!model.take_handle(Handle {
            particle: 99,
            ..at(0.0)
        }));
    }
}
