//! Cloth against itself: proximity of vertex-triangle and edge-edge pairs with a thickness, found
//! through a spatial hash (`grid.rs`), and the bound that keeps a step from making any two of
//! them cross.
//!
//! The guarantee follows Chen et al.'s offset geometric contact (SIGGRAPH 2025): at detection,
//! each vertex gets a bound `b_v = share * (distance to the nearest primitive it is part of a
//! pair with)`, at most `share * reach` (its own); with `share < 1/2`, a step that moves no vertex farther
//! than its bound from where detection saw it cannot bring two primitives that were apart into
//! contact, whatever path the vertices take (each primitive's points move no farther than its
//! farthest vertex). The cloth then never passes through itself where it did not at the start.
//!
//! Left out of both the pairs and the bounds: primitives sharing a vertex, primitives within two
//! rings of each other in the mesh unless they face each other (`FACING`: neighbours in the
//! cloth's own plane are held by its springs, a sharp fold brings one face on), and pairs nearer
//! than a tenth of the thickness in the starting shape (layers modelled touching, or crossing, as
//! some MakeHuman garments are: they were never apart). A pair nearer than the thickness there
//! keeps 0.9 of its distance there instead of the thickness.

pub mod broad;
mod energy;
pub mod geom;
pub mod grid;
mod keep;
pub mod stage;
mod untangle;

use broad::{Broad, BroadPhase, Scratch};
use rayon::prelude::*;
use std::collections::HashSet;
use tryon_core::math::{Real, Vec3};
pub use tryon_core::stages::Untangled;

/// Primitives within two rings of each other in the mesh pair up only where they face each
/// other: the offset between them makes at least this cosine with the triangle's normal (or the
/// two edges' common normal). Neighbours in the cloth's own plane are held by its springs; a
/// sharp fold brings a neighbour's neighbour face on.
const FACING: Real = 0.5;

/// Pairs nearer than this share of the thickness in the starting shape touch there: left out.
const TOUCHING: Real = 0.1;

/// A pair nearer than the thickness in the starting shape keeps this share of its distance there.
const REST_SHARE: Real = 0.9;

/// Edges whose cross product is below this share of their lengths' product are parallel.
const PARALLEL: Real = 0.1;

/// Fewest queries a thread takes at once.
const CHUNK: usize = 64;

/// Self-contact settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SelfParams {
    /// Distance the cloth keeps from itself (m).
    pub thickness: Real,
    /// Share of its nearest pair's distance a vertex may move in a step (below 1/2).
    pub share: Real,
    /// Nearest a detection looks (m): a vertex with nothing nearer may move `share` times its
    /// reach, which grows with its guessed move in the step.
    pub reach: Real,
    /// Coulomb friction between layers.
    pub friction: Real,
    /// How candidate pairs are found.
    pub broad: BroadPhase,
    /// Pairs within one garment (the cloth against itself).
    pub within: bool,
    /// Pairs between garments (layers worn over each other).
    pub between: bool,
    /// Untangling also opens pairs nearer than the gap (else only crossing triangles).
    pub untangle_near: bool,
}

impl Default for SelfParams {
    fn default() -> Self {
        SelfParams {
            thickness: 0.002,
            share: 0.3,
            reach: 0.005,
            friction: 0.3,
            broad: BroadPhase::default(),
            within: true,
            between: true,
            untangle_near: true,
        }
    }
}

/// One contact: the signed combination `sum w_k x_{v_k}` is the offset between the two
/// primitives' nearest points (a vertex minus its triangle's point, or one edge's point minus the
/// other's). The weights are those at detection; the energy finds them again where it is
/// evaluated ([`Stencil::weights`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Stencil {
    pub v: [u32; 4],
    pub w: [Real; 4],
    /// An edge-edge pair (else a vertex and a triangle).
    pub edges: bool,
    /// The offset's direction at detection (for friction's tangent plane).
    pub normal: Vec3,
    /// The contact's normal force at detection (N), for lagged friction; 0 while apart.
    pub lambda: Real,
    /// The primitives' distance at detection (m).
    pub gap: Real,
    /// The distance this pair keeps: the thickness, or less where the pair was nearer in the
    /// starting shape (a layer modelled 1 mm over another is held at 0.9 mm, not pushed off).
    pub thickness: Real,
}

/// A pair found by a query: its stencil and distance at detection.
type Found = (Stencil, Real);

/// Self-contacts of one cloth mesh.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SelfContacts {
    pub params: SelfParams,
    tris: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    /// Per triangle, its three edges.
    tri_edges: Vec<[u32; 3]>,
    /// Per vertex, itself and its neighbours, sorted (CSR).
    ring_start: Vec<u32>,
    ring: Vec<u32>,
    /// Per vertex, the vertices within two rings, sorted (CSR).
    near_start: Vec<u32>,
    near: Vec<u32>,
    /// Vertex-triangle (`v << 32 | t`) and edge-edge (`1 << 63 | e << 32 | f`) pairs touching
    /// in the starting shape.
    rest_near: HashSet<u64>,
    /// The starting shape.
    rest: Vec<Vec3>,
    broad: Broad,
    boxes: Vec<(Vec3, Vec3)>,
    /// The pairs near enough to touch in this step.
    pub stencils: Vec<Stencil>,
    /// Per vertex, how far it may move from where detection saw it (m).
    pub bound: Vec<Real>,
    /// Per vertex, its stencils and its slot in each (CSR).
    by_vertex_start: Vec<u32>,
    by_vertex: Vec<(u32, u8)>,
    /// Positions detection saw.
    pub seen: Vec<Vec3>,
    /// How far the last detection looked, per vertex (m).
    pub reach: Vec<Real>,
    /// The cloth's shape at its last frame's end (none crossing), set by the solver.
    pub last_end: Vec<Vec3>,
    /// Per vertex, its garment and its garment's layer (empty: one garment).
    garment: Vec<u16>,
    layer: Vec<u32>,
}

impl Stencil {
    /// The weights of the two primitives' nearest points at `x`.
    pub fn weights(&self, x: &[Vec3]) -> [Real; 4] {
        let p = self.v.map(|i| x[i as usize]);
        if self.edges {
            let (s, t) = geom::segment_segment(&p[0], &p[1], &p[2], &p[3]);
            [1.0 - s, s, t - 1.0, -t]
        } else {
            let w = geom::point_triangle(&p[0], &p[1], &p[2], &p[3]);
            [1.0, -w[0], -w[1], -w[2]]
        }
    }
}

fn ring_of<'a>(start: &[u32], ring: &'a [u32], v: u32) -> &'a [u32] {
    &ring[start[v as usize] as usize..start[v as usize + 1] as usize]
}

impl SelfContacts {
    /// Self-contacts of the mesh `tris` over `n` vertices whose rest shape is `rest`.
    pub fn new(tris: &[[u32; 3]], rest: &[Vec3], params: SelfParams) -> Self {
        let n = rest.len();
        let mut neighbours: Vec<Vec<u32>> = (0..n as u32).map(|v| vec![v]).collect();
        let mut edge_ids = std::collections::HashMap::new();
        let mut edges = Vec::new();
        let mut tri_edges = Vec::with_capacity(tris.len());
        for t in tris {
            let mut te = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                neighbours[a as usize].push(b);
                neighbours[b as usize].push(a);
                let key = (a.min(b), a.max(b));
                te[k] = *edge_ids.entry(key).or_insert_with(|| {
                    edges.push([key.0, key.1]);
                    edges.len() as u32 - 1
                });
            }
            tri_edges.push(te);
        }
        let mut ring_start = vec![0u32];
        let mut ring = Vec::new();
        for mut l in neighbours {
            l.sort_unstable();
            l.dedup();
            ring.extend(l);
            ring_start.push(ring.len() as u32);
        }
        let (mut near_start, mut near) = (vec![0u32], Vec::new());
        for v in 0..n as u32 {
            let mut l: Vec<u32> = ring_of(&ring_start, &ring, v)
                .iter()
                .flat_map(|&u| ring_of(&ring_start, &ring, u).iter().copied())
                .collect();
            l.sort_unstable();
            l.dedup();
            near.extend(l);
            near_start.push(near.len() as u32);
        }
        let mut s = SelfContacts {
            params,
            near_start,
            near,
            broad: Broad::new(params.broad),
            tris: tris.to_vec(),
            edges,
            tri_edges,
            ring_start,
            ring,
            ..SelfContacts::default()
        };
        s.set_rest(rest);
        s
    }

    /// The same contacts over several garments: vertex `v` belongs to garment `garment[v]`,
    /// worn in layer `layer[v]` (higher over lower). Pairs within a garment count with
    /// `params.within`, between garments with `params.between`; untangling moves the higher
    /// layer out.
    pub fn with_garments(mut self, garment: &[u16], layer: &[u32]) -> Self {
        self.garment = garment.to_vec();
        self.layer = layer.to_vec();
        let rest = std::mem::take(&mut self.rest);
        self.set_rest(&rest);
        self
    }

    /// Whether pairs between vertices `a` and `b`'s garments count.
    fn wanted(&self, a: u32, b: u32) -> bool {
        let g = |v: u32| self.garment.get(v as usize).copied().unwrap_or(0);
        if g(a) == g(b) {
            self.params.within
        } else {
            self.params.between
        }
    }

    /// Vertex `v`'s layer (0 for one garment).
    fn layer_of(&self, v: u32) -> u32 {
        self.layer.get(v as usize).copied().unwrap_or(0)
    }

    /// Takes `x` as the starting shape: pairs touching in it (nearer than [`TOUCHING`] times the
    /// thickness) were never apart and are left out; pairs nearer than the thickness keep their
    /// distance in it.
    pub fn set_rest(&mut self, x: &[Vec3]) {
        let touching = TOUCHING * self.params.thickness;
        let found = self.find(x, &vec![touching; x.len()]);
        self.rest_near = found.into_iter().map(|(key, _)| key).collect();
        self.rest = x.to_vec();
    }

    /// The distance stencil `st`'s primitives had in the starting shape.
    fn rest_distance(&self, st: &Stencil) -> Real {
        let Some(p) =
            st.v.iter()
                .map(|&v| self.rest.get(v as usize))
                .collect::<Option<Vec<_>>>()
        else {
            return Real::INFINITY;
        };
        let probe = Stencil {
            v: [0, 1, 2, 3],
            ..*st
        };
        let x: Vec<Vec3> = p.into_iter().copied().collect();
        let w = probe.weights(&x);
        (0..4).map(|m| x[m] * w[m]).sum::<Vec3>().norm()
    }

    fn near_in_mesh(&self, a: &[u32], b: &[u32]) -> bool {
        a.iter().any(|&u| {
            let r = ring_of(&self.near_start, &self.near, u);
            b.iter().any(|w| r.binary_search(w).is_ok())
        })
    }

    /// Every pair whose distance at `x` is under the larger reach of its vertices (`reach`, per
    /// vertex), keyed as in `rest_near`, in a fixed order. A pair nearer than either primitive's
    /// reach is found from one side or the other: each triangle's box is grown by its corners'
    /// largest reach, each query's box by its own.
    fn find(&mut self, x: &[Vec3], reach: &[Real]) -> Vec<(u64, Found)> {
        if !self.index(x, reach) {
            return Vec::new();
        }
        let this = &*self;
        let vt = (0..x.len() as u32)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map_init(Scratch::default, |buf, v| {
                this.vertex_pairs(x, v, reach, buf)
            })
            .flatten_iter();
        let ee = (0..self.edges.len() as u32)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map_init(Scratch::default, |buf, e| this.edge_pairs(x, e, reach, buf))
            .flatten_iter();
        vt.chain(ee).collect()
    }

    /// The triangles' boxes grown by their corners' largest reach, and the broad phase over
    /// them; false where the positions are not finite.
    fn index(&mut self, x: &[Vec3], reach: &[Real]) -> bool {
        self.boxes.clear();
        for t in &self.tris {
            let (a, b, c) = (x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]);
            let pad = Vec3::repeat(t.iter().map(|&v| reach[v as usize]).fold(0.0, Real::max));
            self.boxes
                .push((a.inf(&b).inf(&c) - pad, a.sup(&b).sup(&c) + pad));
        }
        let per = |n: usize| n.max(1) as Real;
        let mean = self
            .edges
            .iter()
            .map(|e| (x[e[0] as usize] - x[e[1] as usize]).norm())
            .sum::<Real>()
            / per(self.edges.len());
        let cell = mean.max(reach.iter().sum::<Real>() / per(reach.len()));
        if !(cell.is_finite() && cell > 0.0) {
            return false;
        }
        self.broad.build(&self.boxes, (x, &self.edges, reach), cell);
        true
    }

    fn vertex_pairs(
        &self,
        x: &[Vec3],
        v: u32,
        reach: &[Real],
        sc: &mut Scratch,
    ) -> Vec<(u64, Found)> {
        let p = x[v as usize];
        let rv = reach[v as usize];
        let (plo, phi) = (p.add_scalar(-rv), p.add_scalar(rv));
        self.broad.triangles(&plo, &phi, sc);
        let mut out = Vec::new();
        for &t in sc.found.iter() {
            let (lo, hi) = &self.boxes[t as usize];
            let meets = (0..3).all(|k| lo[k] <= phi[k] && plo[k] <= hi[k]);
            if meets && self.may_pair_vt(v, t) {
                out.extend(self.vt_pair(x, v, t, reach));
            }
        }
        out
    }

    /// Whether vertex `v` and triangle `t` may ever pair: not a corner of it, and of garments
    /// whose pairs count.
    fn may_pair_vt(&self, v: u32, t: u32) -> bool {
        let tri = self.tris[t as usize];
        !tri.contains(&v) && self.wanted(v, tri[0])
    }

    /// Whether edges `e` and `f` may ever pair: no shared vertex, garments whose pairs count.
    fn may_pair_ee(&self, e: u32, f: u32) -> bool {
        let ([a, b], [c, d]) = (self.edges[e as usize], self.edges[f as usize]);
        ![a, b].iter().any(|v| [c, d].contains(v)) && self.wanted(a, c)
    }

    /// Vertex `v` and triangle `t` at `x` as a pair, when nearer than the larger reach of their
    /// vertices and not neighbours in the mesh beside each other.
    fn vt_pair(&self, x: &[Vec3], v: u32, t: u32, reach: &[Real]) -> Option<(u64, Found)> {
        let p = x[v as usize];
        let tri = self.tris[t as usize];
        let c = tri.map(|i| x[i as usize]);
        let w = geom::point_triangle(&p, &c[0], &c[1], &c[2]);
        let d = p - (c[0] * w[0] + c[1] * w[1] + c[2] * w[2]);
        let dist = d.norm();
        let facing = || {
            let n = (c[1] - c[0]).cross(&(c[2] - c[0]));
            n.dot(&d).abs() >= FACING * n.norm() * dist
        };
        let r = tri
            .iter()
            .map(|&u| reach[u as usize])
            .fold(reach[v as usize], Real::max);
        if !(dist < r && (!self.near_in_mesh(&[v], &tri) || facing())) {
            return None;
        }
        let st = Stencil {
            v: [v, tri[0], tri[1], tri[2]],
            w: [1.0, -w[0], -w[1], -w[2]],
            edges: false,
            normal: d / dist.max(1e-12),
            lambda: 0.0,
            gap: dist,
            thickness: 0.0,
        };
        Some(((v as u64) << 32 | t as u64, (st, dist)))
    }

    fn edge_pairs(
        &self,
        x: &[Vec3],
        e: u32,
        reach: &[Real],
        sc: &mut Scratch,
    ) -> Vec<(u64, Found)> {
        let [a, b] = self.edges[e as usize];
        let (pa, pb) = (x[a as usize], x[b as usize]);
        let re = reach[a as usize].max(reach[b as usize]);
        let (lo, hi) = (pa.inf(&pb).add_scalar(-re), pa.sup(&pb).add_scalar(re));
        self.broad.edges(e, (&lo, &hi), &self.tri_edges, sc);
        let mut out = Vec::new();
        for &f in &sc.found {
            let [c, d] = self.edges[f as usize];
            let (pc, pd) = (x[c as usize], x[d as usize]);
            let (flo, fhi) = (pc.inf(&pd), pc.sup(&pd));
            let rf = reach[c as usize].max(reach[d as usize]);
            let apart = (0..3).any(|k| flo[k] - rf > hi[k] || lo[k] > fhi[k] + rf);
            if !apart && self.may_pair_ee(e, f) {
                out.extend(self.ee_pair(x, e, f, reach));
            }
        }
        out
    }

    /// Edges `e` and `f` at `x` as a pair, when nearer than the larger reach of their ends and
    /// facing each other where they are neighbours in the mesh.
    fn ee_pair(&self, x: &[Vec3], e: u32, f: u32, reach: &[Real]) -> Option<(u64, Found)> {
        let ([a, b], [c, d]) = (self.edges[e as usize], self.edges[f as usize]);
        let (pa, pb) = (x[a as usize], x[b as usize]);
        let (pc, pd) = (x[c as usize], x[d as usize]);
        let r = [a, b, c, d]
            .iter()
            .map(|&v| reach[v as usize])
            .fold(0.0, Real::max);
        let (s, t) = geom::segment_segment(&pa, &pb, &pc, &pd);
        let off = pa + (pb - pa) * s - pc - (pd - pc) * t;
        let dist = off.norm();
        let facing = || {
            // Parallel edges have no common normal: side by side, not facing.
            let n = (pb - pa).cross(&(pd - pc));
            let square = (pb - pa).norm() * (pd - pc).norm();
            n.norm() > PARALLEL * square && n.dot(&off).abs() >= FACING * n.norm() * dist
        };
        if !(dist < r && (!self.near_in_mesh(&[a, b], &[c, d]) || facing())) {
            return None;
        }
        let st = Stencil {
            v: [a, b, c, d],
            w: [1.0 - s, s, t - 1.0, -t],
            edges: true,
            normal: off / dist.max(1e-12),
            lambda: 0.0,
            gap: dist,
            thickness: 0.0,
        };
        Some((1 << 63 | (e as u64) << 32 | f as u64, (st, dist)))
    }

    /// Finds the pairs at `x` (the step's start, or where a sweep left the cloth) and each
    /// vertex's bound, each vertex looking as far as its `reach` (at least the distance a pair
    /// must have to stay beyond the thickness in a step); `stiffness(v)` is the contact penalty
    /// of vertex `v` (N/m), for the lagged friction's normal force.
    pub fn detect(&mut self, x: &[Vec3], reach: &[Real], stiffness: impl Fn(usize) -> Real) {
        let p = self.params;
        // A pair farther than this cannot come within the thickness in one step.
        let keep = p.thickness / (1.0 - 2.0 * p.share).max(0.05);
        let mut reach: Vec<Real> = reach.iter().map(|r| r.max(keep)).collect();
        reach.resize(x.len(), keep);
        let found = self.find(x, &reach);
        self.seen.clear();
        self.seen.extend_from_slice(x);
        self.bound.clear();
        self.bound.extend(reach.iter().map(|r| p.share * r));
        self.reach = reach;
        self.stencils.clear();
        for (key, (mut st, dist)) in found {
            if self.rest_near.contains(&key) {
                continue;
            }
            for &v in &st.v {
                let b = &mut self.bound[v as usize];
                *b = b.min(p.share * dist);
            }
            if dist < keep {
                st.thickness = p.thickness.min(REST_SHARE * self.rest_distance(&st));
                let k =
                    st.v.iter()
                        .map(|&v| stiffness(v as usize))
                        .fold(0.0, Real::max);
                st.lambda = k * (st.thickness - dist).max(0.0);
                self.stencils.push(st);
            }
        }
        self.index_by_vertex(x.len());
    }

    fn index_by_vertex(&mut self, n: usize) {
        self.by_vertex_start.clear();
        self.by_vertex_start.resize(n + 1, 0);
        for st in &self.stencils {
            for &v in &st.v {
                self.by_vertex_start[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            self.by_vertex_start[i + 1] += self.by_vertex_start[i];
        }
        self.by_vertex.clear();
        self.by_vertex
            .resize(self.by_vertex_start[n] as usize, (0, 0));
        let mut fill = self.by_vertex_start.clone();
        for (s, st) in self.stencils.iter().enumerate() {
            for (slot, &v) in st.v.iter().enumerate() {
                self.by_vertex[fill[v as usize] as usize] = (s as u32, slot as u8);
                fill[v as usize] += 1;
            }
        }
    }

    /// Moves `xi` (vertex `i`'s new position) back toward where detection saw it, to within its
    /// bound; returns whether it had to.
    pub fn clamp(&self, i: usize, xi: &mut Vec3) -> bool {
        let (Some(b), Some(s)) = (self.bound.get(i), self.seen.get(i)) else {
            return false;
        };
        let d = *xi - s;
        let l = d.norm();
        if l > *b {
            *xi = s + d * (b / l);
            true
        } else {
            false
        }
    }

    /// Every vertex moved to within its bound (`clamp`), except those `fixed` says are led from
    /// outside (kinematic).
    pub fn clamp_all(&self, x: &mut [Vec3], fixed: impl Fn(usize) -> bool) -> usize {
        let mut n = 0;
        for (i, xi) in x.iter_mut().enumerate() {
            if !fixed(i) && self.clamp(i, xi) {
                n += 1;
            }
        }
        n
    }
}

#[cfg(test)]
pub(crate) mod tests;
