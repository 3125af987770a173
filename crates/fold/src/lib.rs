//! P3 (../shared/PAPERS.md, P3): folds added to a cloth model from lines a user draws where a
//! fold's ridge or valley should run. Algorithm 1 of the paper, step by step:
//!
//! 1. the line, landed on the garment from the picture it is drawn on (`land`), snapped to the garment's surface and followed across it (`path`);
//! 2. mass points added where it crosses the mesh's edges and the faces it crosses subdivided,
//!    so the line becomes a chain of mesh edges (`split`; the mesh stays conforming and manifold),
//!    the new points then moved along the normal, out for a ridge and in for a valley, easing to
//!    nothing over each end's fifth of the line ([`taper`]): a spiky fold (`displace`);
//! 3. local Laplacian smoothing of the new points and their neighbourhood, repeated as often as
//!    asked, each round with or without Taubin's hierarchical constraint (new points see only new
//!    points, so the ridge is smoothed along its length and not pulled back into the surface)
//!    (`smooth`);
//! 4. the parameters: mass per unit area uniform again (the cloth model lumps each particle's
//!    mass from its faces' areas, so it is by construction), and the bend springs that cross the
//!    line shortened and stiffened ([`BendEdit`]);
//! 5. the simulation (the pipeline's cloth solver); how much of the fold it keeps is measured by
//!    [`fold_height`] (the paper's open problem: the simulation drifting from the drawn shape).
//!
//! The paper works on a grid of quads; here the faces a line crosses are split into triangles
//! first, the rest of the mesh is left as it was.

mod height;
pub mod land;
mod path;
mod smooth;
mod split;
#[cfg(test)]
mod tests;

pub use height::{fold_height, fold_retention};
pub use land::{Miss, land};
pub use smooth::{Round, smooth_round};

use thiserror::Error;
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_core::mesh::PolyMesh;
use tryon_core::topology::{Topology, TopologyError};

/// Which way a fold stands out of the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FoldKind {
    /// Out along the surface normal (the front side's).
    Ridge,
    /// In, against the normal.
    Valley,
}

/// One drawn fold: a polyline of points on (or near) the garment's surface.
#[derive(Clone, Debug, PartialEq)]
pub struct FoldLine {
    pub kind: FoldKind,
    /// The line's points in order (m); each is snapped to the nearest surface point.
    pub points: Vec<Vec3>,
    /// How far the ridge stands out of the surface, or the valley in (m, > 0).
    pub height: Real,
}

/// How the folds are shaped and held.
#[derive(Clone, Debug, PartialEq)]
pub struct FoldParams {
    /// Smoothing rounds in order, each plain or under Taubin's constraint.
    pub rounds: Vec<Round>,
    /// Each round moves a vertex this fraction of the way to its neighbours' mean.
    pub lambda: Real,
    /// How many rings of old vertices around the new ones are smoothed.
    pub rings: u32,
    /// Farthest a line's point may be from the surface (m).
    pub snap: Real,
    /// Rest length of the bend springs crossing a line, as a multiple of their folded length.
    pub bend_shorten: Real,
    /// Their stiffness, as a multiple of the other bend springs'.
    pub bend_stiffen: Real,
    /// Which bend springs are changed.
    pub hold: Hold,
}

/// Which bend springs a fold changes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Hold {
    /// P3's rule: the springs crossing the drawn line (those spanning an edge of the ridge).
    #[default]
    Line,
    /// Every spring spanning an edge of the smoothed fold (both ends of the edge in the smoothed
    /// region), so the fold's whole cross-section is held, not only its crest.
    Fold,
}

impl Default for FoldParams {
    fn default() -> Self {
        FoldParams {
            rounds: vec![Round::Constrained; 4],
            lambda: 0.5,
            rings: 2,
            snap: 0.05,
            bend_shorten: 0.9,
            bend_stiffen: 10.0,
            hold: Hold::Line,
        }
    }
}

/// A bend spring to change: the one joining `a` and `b` (a < b), the two vertices opposite an
/// edge of a fold's ridge.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BendEdit {
    pub a: u32,
    pub b: u32,
    pub rest_scale: Real,
    pub stiffness_scale: Real,
}

/// One fold as built.
#[derive(Clone, Debug, PartialEq)]
pub struct Fold {
    /// The vertices along the line, in order: the ridge (or valley) line.
    pub ridge: Vec<u32>,
    /// The drawn height, signed: positive for a ridge, negative for a valley (m).
    pub drawn: Real,
}

/// A mesh with folds.
#[derive(Clone, Debug, PartialEq)]
pub struct Folded {
    /// The subdivided mesh: the original vertices keep their indices, new ones follow.
    pub mesh: PolyMesh,
    pub folds: Vec<Fold>,
    /// Per vertex, whether it is on a line: added there, or an old vertex the line passed
    /// within 15% of an edge's length of (the line then takes it).
    pub is_new: Vec<bool>,
    /// Per vertex, whether smoothing may move it (new vertices and `rings` rings around them,
    /// less the mesh's open boundary).
    pub region: Vec<bool>,
    /// Per added vertex (in order, from the first index past the original mesh's), the original
    /// edge `(a, b)` it was made on and where along it (`t`, from `a`), before it was moved.
    pub made_on: Vec<(u32, u32, Real)>,
}

impl Folded {
    /// Where each vertex was before the fold moved it, for the original mesh's vertices
    /// `original` (the added ones on their edges): with [`Folded::carried`], the fold's shape
    /// moved onto another shape of the same garment.
    pub fn unmoved(&self, original: &[Vec3]) -> Vec<Vec3> {
        let mut out = original.to_vec();
        out.extend(self.made_on.iter().map(|&(a, b, t)| {
            let (xa, xb) = (original[a as usize], original[b as usize]);
            xa + (xb - xa) * t
        }));
        out
    }

    /// The folded mesh's positions carried onto `other`, another shape of the original mesh
    /// the fold was made on (`original`): each vertex moved from its place on `other` as the fold
    /// moved it from its place on `original`, the move turned as the surface turned there (the
    /// least rotation taking the one shape's vertex normal to the other's), so a fold made on a
    /// wrinkled drape stands out of a smooth modelled shape the same way. `None` when the counts
    /// differ.
    pub fn carried(&self, original: &[Vec3], other: &[Vec3]) -> Option<Vec<Vec3>> {
        let n0 = self.mesh.positions.len().checked_sub(self.made_on.len())?;
        if original.len() != n0 || other.len() != n0 {
            return None;
        }
        let (before, base) = (self.unmoved(original), self.unmoved(other));
        let (tris, _) = self.mesh.triangulate();
        let (mut nb, mut no) = (Vec::new(), Vec::new());
        vertex_normals(&before, &tris, &mut nb);
        vertex_normals(&base, &tris, &mut no);
        Some(
            (self.mesh.positions.iter().enumerate())
                .map(|(v, x)| {
                    let turn = tryon_core::math::UnitQuat::rotation_between(&nb[v], &no[v])
                        .unwrap_or_else(tryon_core::math::UnitQuat::identity);
                    base[v] + turn * (x - before[v])
                })
                .collect(),
        )
    }
}

/// Why a fold could not be made. Folds are counted from 0 in the order given.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FoldError {
    #[error("fold {fold}: a line needs at least two points, it has {count}")]
    TooFewPoints { fold: usize, count: usize },
    #[error("fold {fold}: point {point} is not finite ({value:?})")]
    NonFinitePoint {
        fold: usize,
        point: usize,
        value: [Real; 3],
    },
    #[error(
        "fold {fold}: height {height} is not allowed (a finite height above 0 and at most 1 m)"
    )]
    BadHeight { fold: usize, height: Real },
    #[error(
        "fold {fold}: point {point} is {distance:.3} m from the garment (at most {allowed} m is snapped to it)"
    )]
    OffGarment {
        fold: usize,
        point: usize,
        distance: Real,
        allowed: Real,
    },
    #[error("fold {fold}: the line leaves the garment over its edge between points {segment} and {}", segment + 1)]
    LeavesGarment { fold: usize, segment: usize },
    #[error(
        "fold {fold}: the line crosses itself or turns back on itself between points {segment} and {}",
        segment + 1
    )]
    SelfCrossing { fold: usize, segment: usize },
    #[error("fold {fold}: the line crosses fold {other}")]
    CrossesFold { fold: usize, other: usize },
    #[error(
        "fold {fold}: the line crosses {crossed} edges of the mesh; a fold needs at least 2 (draw it across at least two faces)"
    )]
    TooShort { fold: usize, crossed: usize },
    #[error("garment mesh: {0}")]
    Mesh(#[from] TopologyError),
    #[error("smoothing: lambda {0} is not in (0, 1]")]
    BadLambda(Real),
}

impl FoldError {
    /// The fold the error is about, when it is about one.
    pub fn fold(&self) -> Option<usize> {
        use FoldError::*;
        match self {
            TooFewPoints { fold, .. }
            | NonFinitePoint { fold, .. }
            | BadHeight { fold, .. }
            | OffGarment { fold, .. }
            | LeavesGarment { fold, .. }
            | SelfCrossing { fold, .. }
            | CrossesFold { fold, .. }
            | TooShort { fold, .. } => Some(*fold),
            Mesh(_) | BadLambda(_) => None,
        }
    }
}

/// Subdivides `mesh` along every line and raises (or lowers) the new vertices by the line's
/// height: the spiky fold of Algorithm 1 step 2, before any smoothing.
pub fn subdivide(mesh: &PolyMesh, lines: &[FoldLine], p: &FoldParams) -> Result<Folded, FoldError> {
    if !(p.lambda > 0.0 && p.lambda <= 1.0) {
        return Err(FoldError::BadLambda(p.lambda));
    }
    for (f, l) in lines.iter().enumerate() {
        check_line(f, l)?;
    }
    Topology::build(mesh)?;
    let crossings = path::walk_all(mesh, lines, p.snap)?;
    let mut out = split::split_along(mesh, &crossings)?;
    displace(&mut out, lines);
    out.region = smooth::region(&out, p.rings);
    Ok(out)
}

/// [`subdivide`], then `p.rounds` of smoothing: the fold ready to simulate.
pub fn build(mesh: &PolyMesh, lines: &[FoldLine], p: &FoldParams) -> Result<Folded, FoldError> {
    let mut out = subdivide(mesh, lines, p)?;
    let ring = ring_of(&out.mesh);
    for &r in &p.rounds {
        smooth_round(
            &mut out.mesh.positions,
            &ring,
            &out.is_new,
            &out.region,
            r,
            p.lambda,
        );
    }
    Ok(out)
}

/// The bend springs `p.hold` names (those crossing each fold's line, or spanning any edge of the
/// smoothed fold), with `p`'s changes.
pub fn bend_edits(folded: &Folded, p: &FoldParams) -> Vec<BendEdit> {
    let key = |u: u32, v: u32| (u.min(v), u.max(v));
    let (tris, _) = folded.mesh.triangulate();
    // The vertices opposite each held edge, from one pass over the triangles.
    let mut opposite: std::collections::HashMap<(u32, u32), Vec<u32>> = match p.hold {
        Hold::Line => folded
            .folds
            .iter()
            .flat_map(|f| f.ridge.windows(2).map(|w| (key(w[0], w[1]), Vec::new())))
            .collect(),
        Hold::Fold => {
            let inside = |v: u32| folded.region.get(v as usize).copied().unwrap_or(false);
            tris.iter()
                .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
                .filter(|&(a, b)| inside(a) && inside(b))
                .map(|(a, b)| (key(a, b), Vec::new()))
                .collect()
        }
    };
    for t in &tris {
        for k in 0..3 {
            if let Some(o) = opposite.get_mut(&key(t[k], t[(k + 1) % 3])) {
                o.push(t[(k + 2) % 3]);
            }
        }
    }
    let mut out: Vec<BendEdit> = opposite
        .values()
        .filter_map(|o| match o[..] {
            [a, b] if a != b => Some(BendEdit {
                a: a.min(b),
                b: a.max(b),
                rest_scale: p.bend_shorten,
                stiffness_scale: p.bend_stiffen,
            }),
            _ => None,
        })
        .collect();
    out.sort_by_key(|e| (e.a, e.b));
    out.dedup_by_key(|e| (e.a, e.b));
    out
}

/// Each vertex's neighbours in `mesh` (its one-ring), for smoothing.
pub fn ring_of(mesh: &PolyMesh) -> Vec<Vec<u32>> {
    let mut ring = vec![Vec::new(); mesh.positions.len()];
    for f in &mesh.faces {
        let vs = f.vertices();
        for k in 0..vs.len() {
            let (a, b) = (vs[k] as usize, vs[(k + 1) % vs.len()] as usize);
            if a < ring.len() && b < ring.len() {
                ring[a].push(b as u32);
                ring[b].push(a as u32);
            }
        }
    }
    for r in &mut ring {
        r.sort_unstable();
        r.dedup();
    }
    ring
}

fn check_line(fold: usize, l: &FoldLine) -> Result<(), FoldError> {
    if l.points.len() < 2 {
        return Err(FoldError::TooFewPoints {
            fold,
            count: l.points.len(),
        });
    }
    if let Some((point, p)) = l
        .points
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|c| c.is_finite()))
    {
        return Err(FoldError::NonFinitePoint {
            fold,
            point,
            value: [p.x, p.y, p.z],
        });
    }
    if !(l.height > 0.0 && l.height <= 1.0) {
        return Err(FoldError::BadHeight {
            fold,
            height: l.height,
        });
    }
    Ok(())
}

/// The new vertices moved along the subdivided surface's normal by their line's height.
fn displace(out: &mut Folded, lines: &[FoldLine]) {
    let (tris, _) = out.mesh.triangulate();
    let mut normals = Vec::new();
    vertex_normals(&out.mesh.positions, &tris, &mut normals);
    for (f, l) in out.folds.iter_mut().zip(lines) {
        f.drawn = match l.kind {
            FoldKind::Ridge => l.height,
            FoldKind::Valley => -l.height,
        };
        // Arc length along the line, for the taper.
        let x = &out.mesh.positions;
        let mut along = vec![0.0];
        for w in f.ridge.windows(2) {
            let step = (x[w[1] as usize] - x[w[0] as usize]).norm();
            along.push(along[along.len() - 1] + step);
        }
        let total = along[along.len() - 1].max(1e-12);
        let moves: Vec<(usize, Vec3)> = (f.ridge.iter().zip(&along))
            .map(|(&v, &s)| (v as usize, normals[v as usize] * f.drawn * taper(s / total)))
            .collect();
        for (v, d) in moves {
            out.mesh.positions[v] += d;
        }
    }
}

/// Share of a fold's height at `s` (0..1 along its line): full over the middle, easing to 0 at
/// the ends over a fifth of the line each (a fold dies out into the cloth; the ends, held still by
/// constrained smoothing, would otherwise stand as spikes).
pub fn taper(s: Real) -> Real {
    let ramp = |t: Real| {
        let t = (t / TAPER).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    };
    ramp(s) * ramp(1.0 - s)
}

/// The share of a line's length over which each end eases in.
const TAPER: Real = 0.2;
