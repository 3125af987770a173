//! P2's shape fitting: per sub-mesh, the blend weights W of the target shapes that minimise eq. (1),
//! `sum_j lambda_j (d_j - d'_j(W))^2`, d'_j(W) being dimension j's edge lengths summed on the
//! blended mesh `base + sum_k w_k (target_k - base)`; then the sub-meshes moved in 3D so they meet.
//!
//! Choices the paper leaves open, made here: lambda_j = 1 / d_j^2 (so the terms are relative
//! errors); each weight within [`FitParams::bounds`]; a ridge term `ridge * |W - W_prior|^2` (the prior
//! 0 for the back, fitted first, and the back's weights for every other sub-mesh) so that a
//! sub-mesh with fewer dimensions than targets changes no more than it must; solved by projected
//! Gauss-Newton with Levenberg-Marquardt damping. The sub-meshes meet by moving each, in the order
//! back, fronts, sleeves, collar, by the mean gap to the ones already placed at the vertices they
//! share, and then giving those vertices the placed positions.

use crate::dims::Dimensions;
use crate::mesh::{KimonoMesh, sub};
use nalgebra::{DMatrix, DVector};
use thiserror::Error;
use tryon_core::math::{Real, Vec3};

/// Settings of the fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitParams {
    /// Lowest and highest weight of a target.
    pub bounds: (Real, Real),
    /// Weight of `|W|^2` against the relative squared errors.
    pub ridge: Real,
    /// Gauss-Newton iterations at most per sub-mesh.
    pub iterations: usize,
}

impl Default for FitParams {
    fn default() -> Self {
        FitParams {
            bounds: (-0.5, 1.5),
            ridge: 1e-3,
            iterations: 50,
        }
    }
}

/// Why a fit cannot be made.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FitError {
    #[error("no target shapes to blend")]
    NoTargets,
    #[error("shape {shape} has {found} vertices, the kimono mesh has {expected}")]
    VertexCount {
        shape: String,
        found: usize,
        expected: usize,
    },
    #[error("shape {shape}, vertex {vertex}: non-finite position")]
    NonFinite { shape: String, vertex: usize },
}

/// The fitted kimono.
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    /// Per sub-mesh, one weight per target.
    pub weights: Vec<Vec<Real>>,
    pub positions: Vec<Vec3>,
    /// Each dimension set measured on `positions`.
    pub measured: Vec<Real>,
}

fn check(name: &str, shape: &[Vec3], n: usize) -> Result<(), FitError> {
    if shape.len() != n {
        return Err(FitError::VertexCount {
            shape: name.to_string(),
            found: shape.len(),
            expected: n,
        });
    }
    match shape.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        Some(vertex) => Err(FitError::NonFinite {
            shape: name.to_string(),
            vertex,
        }),
        None => Ok(()),
    }
}

/// Fits `mesh` (whose positions are `base`) to `dims` by blending `targets` (same topology).
pub fn fit(
    mesh: &KimonoMesh,
    base: &[Vec3],
    targets: &[Vec<Vec3>],
    dims: &Dimensions,
    p: &FitParams,
) -> Result<Fit, FitError> {
    if targets.is_empty() {
        return Err(FitError::NoTargets);
    }
    let n = mesh.positions.len();
    check("base", base, n)?;
    for (k, t) in targets.iter().enumerate() {
        check(&format!("target {k}"), t, n)?;
    }
    let table = dims.table();
    let verts = mesh.sub_mesh_vertices();
    let owner = owners(mesh, &verts);
    let mut out = base.to_vec();
    let mut placed = vec![false; n];
    let mut weights = vec![Vec::new(); sub::COUNT];
    for s in ORDER {
        let model = Affine::new(&verts[s as usize], base, targets, &out, &placed);
        let sets: Vec<(usize, Real)> = (0..mesh.dimensions.len())
            .filter(|&k| owner[k] == s)
            .map(|k| (k, table[mesh.dimensions[k].table_index].1))
            .collect();
        // The back, fitted first to the garment's length and widths, is every other sub-mesh's
        // prior: a part changes from the back's blend only as far as its own dimensions ask.
        let prior = if s == sub::BACK {
            vec![0.0; targets.len()]
        } else {
            weights[sub::BACK as usize].clone()
        };
        let w = solve(mesh, &model, &prior, &sets, p);
        model.place(&verts[s as usize], &w, &mut out, &mut placed);
        weights[s as usize] = w;
    }
    let measured = (0..mesh.dimensions.len())
        .map(|k| mesh.measure(k, &out))
        .collect();
    Ok(Fit {
        weights,
        positions: out,
        measured,
    })
}

/// The kimono blended with `weights` (per sub-mesh, one per target), the sub-meshes meeting as
/// [`fit`] makes them meet.
pub fn blend(
    mesh: &KimonoMesh,
    base: &[Vec3],
    targets: &[Vec<Vec3>],
    weights: &[Vec<Real>],
) -> Vec<Vec3> {
    let verts = mesh.sub_mesh_vertices();
    let mut out = base.to_vec();
    let mut placed = vec![false; base.len()];
    for s in ORDER {
        let model = Affine::new(&verts[s as usize], base, targets, &out, &placed);
        model.place(
            &verts[s as usize],
            &weights[s as usize],
            &mut out,
            &mut placed,
        );
    }
    out
}

/// The order the sub-meshes are fitted and placed in: each meets the ones before it.
const ORDER: [u8; sub::COUNT] = [
    sub::BACK,
    sub::LEFT_FRONT,
    sub::RIGHT_FRONT,
    sub::LEFT_SLEEVE,
    sub::RIGHT_SLEEVE,
    sub::COLLAR,
];

/// The sub-mesh each dimension set is fitted in: the first in [`ORDER`] holding all its vertices
/// (a sleeve's attachment is the front panel's edge, placed before the sleeve meets it).
fn owners(mesh: &KimonoMesh, verts: &[Vec<u32>]) -> Vec<u8> {
    mesh.dimensions
        .iter()
        .map(|d| {
            ORDER
                .into_iter()
                .find(|&s| {
                    let vs = &verts[s as usize];
                    d.edges
                        .iter()
                        .flatten()
                        .all(|v| vs.binary_search(v).is_ok())
                })
                .unwrap_or(d.sub_mesh)
        })
        .collect()
}

/// A sub-mesh's positions as an affine function of its weights, once it meets what is placed: a
/// vertex already placed stays; any other is blended, then moved by its nearest placed vertices'
/// gaps (inverse-distance weights over [`NEAREST`] of them), so a collar sewn along its whole edge
/// moves with that edge and a sleeve with its seam.
struct Affine {
    /// Per vertex: the position at W = 0 and its change per unit of each weight.
    at0: Vec<Vec3>,
    per: Vec<Vec<Vec3>>,
    /// Local index of each mesh vertex (`u32::MAX` outside the sub-mesh).
    local: Vec<u32>,
}

/// How many placed vertices move a vertex that meets them.
const NEAREST: usize = 4;

impl Affine {
    fn new(
        vs: &[u32],
        base: &[Vec3],
        targets: &[Vec<Vec3>],
        out: &[Vec3],
        placed: &[bool],
    ) -> Self {
        let shared: Vec<u32> = vs.iter().copied().filter(|&v| placed[v as usize]).collect();
        let delta = |k: usize, v: u32| targets[k][v as usize] - base[v as usize];
        let mut at0 = Vec::with_capacity(vs.len());
        let mut per = Vec::with_capacity(vs.len());
        for &v in vs {
            if placed[v as usize] {
                at0.push(out[v as usize]);
                per.push(vec![Vec3::zeros(); targets.len()]);
                continue;
            }
            let near = nearest(&shared, base, v);
            let mut a = base[v as usize];
            for &(u, c) in &near {
                a += (out[u as usize] - base[u as usize]) * c;
            }
            at0.push(a);
            per.push(
                (0..targets.len())
                    .map(|k| delta(k, v) - near.iter().map(|&(u, c)| delta(k, u) * c).sum::<Vec3>())
                    .collect(),
            );
        }
        let mut local = vec![u32::MAX; base.len()];
        for (i, &v) in vs.iter().enumerate() {
            local[v as usize] = i as u32;
        }
        Affine { at0, per, local }
    }

    /// The change of edge `e` (mesh vertices) at W = 0 and per unit of weight `t` (None).
    fn edge(&self, e: &[u32; 2], t: Option<usize>) -> Vec3 {
        let (a, b) = (
            self.local[e[0] as usize] as usize,
            self.local[e[1] as usize] as usize,
        );
        match t {
            None => self.at0[b] - self.at0[a],
            Some(t) => self.per[b][t] - self.per[a][t],
        }
    }

    /// Writes the sub-mesh's vertices `vs` at weights `w` into `out`, marking them placed.
    fn place(&self, vs: &[u32], w: &[Real], out: &mut [Vec3], placed: &mut [bool]) {
        for (i, &v) in vs.iter().enumerate() {
            out[v as usize] = self.at(i, w);
            placed[v as usize] = true;
        }
    }

    /// Local vertex `i` at weights `w`.
    fn at(&self, i: usize, w: &[Real]) -> Vec3 {
        let mut x = self.at0[i];
        for (d, wk) in self.per[i].iter().zip(w) {
            x += d * *wk;
        }
        x
    }
}

/// The [`NEAREST`] vertices of `shared` closest to `v` on `base`, with normalised inverse-square
/// distance weights.
fn nearest(shared: &[u32], base: &[Vec3], v: u32) -> Vec<(u32, Real)> {
    let p = base[v as usize];
    let mut by: Vec<(Real, u32)> = shared
        .iter()
        .map(|&u| ((base[u as usize] - p).norm_squared(), u))
        .collect();
    let m = NEAREST.min(by.len());
    if m == 0 {
        return Vec::new();
    }
    by.select_nth_unstable_by(m - 1, |a, b| a.0.total_cmp(&b.0));
    let near = &by[..m];
    let w: Vec<Real> = near.iter().map(|(d2, _)| 1.0 / d2.max(1e-12)).collect();
    let sum: Real = w.iter().sum();
    near.iter()
        .zip(&w)
        .map(|((_, u), wi)| (*u, wi / sum))
        .collect()
}

/// One dimension's edges as affine functions of the weights.
struct EdgeBasis {
    base: Vec<Vec3>,
    delta: Vec<Vec<Vec3>>,
    target: Real,
}

/// Relative residuals and their Jacobian at `w`.
fn residuals(sets: &[EdgeBasis], w: &[Real]) -> (DVector<Real>, DMatrix<Real>) {
    let k = w.len();
    let mut r = DVector::zeros(sets.len());
    let mut jac = DMatrix::zeros(sets.len(), k);
    for (j, s) in sets.iter().enumerate() {
        let mut len = 0.0;
        for (e, b) in s.base.iter().enumerate() {
            let mut x = *b;
            for t in 0..k {
                x += s.delta[t][e] * w[t];
            }
            let l = x.norm();
            len += l;
            if l > 0.0 {
                for t in 0..k {
                    jac[(j, t)] += x.dot(&s.delta[t][e]) / l / s.target;
                }
            }
        }
        r[j] = (len - s.target) / s.target;
    }
    (r, jac)
}

fn cost(r: &DVector<Real>, w: &[Real], prior: &[Real], ridge: Real) -> Real {
    r.norm_squared()
        + ridge
            * w.iter()
                .zip(prior)
                .map(|(x, p)| (x - p) * (x - p))
                .sum::<Real>()
}

/// The weights of one sub-mesh (its positions `model`) whose dimension sets are `sets` (index,
/// target length).
fn solve(
    mesh: &KimonoMesh,
    model: &Affine,
    prior: &[Real],
    sets: &[(usize, Real)],
    p: &FitParams,
) -> Vec<Real> {
    let k = prior.len();
    let mut w = prior.to_vec();
    if sets.is_empty() {
        return w;
    }
    let basis: Vec<EdgeBasis> = sets
        .iter()
        .map(|&(s, target)| {
            let edges = &mesh.dimensions[s].edges;
            EdgeBasis {
                base: edges.iter().map(|e| model.edge(e, None)).collect(),
                delta: (0..k)
                    .map(|t| edges.iter().map(|e| model.edge(e, Some(t))).collect())
                    .collect(),
                target,
            }
        })
        .collect();
    let (lo, hi) = p.bounds;
    let (mut r, mut jac) = residuals(&basis, &w);
    let mut c = cost(&r, &w, prior, p.ridge);
    let mut damping = 1e-3;
    for _ in 0..p.iterations {
        let g = jac.transpose() * &r
            + (DVector::from_column_slice(&w) - DVector::from_column_slice(prior)) * p.ridge;
        let mut h = jac.transpose() * &jac;
        for t in 0..k {
            h[(t, t)] += p.ridge + damping * (1.0 + h[(t, t)]);
        }
        let Some(step) = h.cholesky().map(|ch| ch.solve(&(-g))) else {
            damping *= 10.0;
            continue;
        };
        let trial: Vec<Real> = (0..k).map(|t| (w[t] + step[t]).clamp(lo, hi)).collect();
        let (r2, j2) = residuals(&basis, &trial);
        let c2 = cost(&r2, &trial, prior, p.ridge);
        if c2.is_finite() && c2 < c {
            let gain = c - c2;
            (w, r, jac, c) = (trial, r2, j2, c2);
            damping = (damping * 0.3).max(1e-12);
            if gain < 1e-16 {
                break;
            }
        } else {
            damping *= 10.0;
            if damping > 1e12 {
                break;
            }
        }
    }
    w
}
