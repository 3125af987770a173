//! wrinkle: P1 sections 4.2-4.4 on the refined surface. Each fine vertex `i` ends at
//! `P_i = S_i + dh_i n_i` (eq. 2), with `S_i` and `n_i` the PN reference surface and its normal.
//!
//! - [`Detail::wrinkle`] (P1.4.3): the height `dh_i` starts from last frame's (eq. 3) and changes by
//!   `dh_deformation`. Forces on fine vertices are interpolated from the coarse particles' elastic
//!   forces along coarse edges with the bend cosines as transmission (eqs. 4-5), and inside a face
//!   along both lattice directions, averaged; the vertical force `v_i` sums neighbours' forces along
//!   the direction to `i` (eqs. 6-7). Each coarse edge's required length change is
//!   `L_rest - fine path length` (eq. 8 with the sign of section 4.3.4, see PAPERS.md), averaged per
//!   coarse vertex and interpolated to fine vertices. The expected change `dL_expected` (eqs. 9-10,
//!   PAPERS.md's reading) is what moving every vertex by `k_out v` would give; so moving vertex `i` by
//!   `dh_length = (dL_required / dL_expected) k_out v_i` gives the required length when the ratio is
//!   positive (eq. 11, read with the `k_out v_i` factor so that it is a height; nothing moves when the
//!   ratio is not positive). `dh_deformation` is whichever of `dh_length` and the one-step force limit
//!   `k_out v_i dt` (eq. 12) is smaller in size; both point the way `v_i` does: pushed from around, the
//!   relief rises, pulled, it flattens. Constraints (P1.4.3.4): `dh >= 0`; two neighbouring fine
//!   vertices may differ in height only as far as keeps their edge within `max_fine_stretch` of its
//!   length on the reference surface; a coarse triangle whose three edges are all longer than rest
//!   gets no wrinkle inside.
//! - [`Detail::fine_collision`] (P1.4.2): hierarchical from the coarse contacts. Coarse triangles
//!   none of whose corners touches the body (a contact this frame, or within `margin`) are skipped;
//!   inside the others the lattice is probed level by level, a vertex only when one of the two
//!   vertices of the coarser level whose edge it halves touched. A vertex inside the body, or within
//!   `skin` of it, is raised along its control direction until it is `skin` out (`dh_penetration`).
//!   This height is not carried to the next frame (carrying it would leave bumps where the body was);
//!   the wrinkle height is.
//! - [`Detail::blend_normals`] (P1.4.4, eqs. 13-14): the deformed surface's normal blended with the
//!   PN normal by `alpha = min(dh / h_normal, 1)`.

pub mod stage;

pub use stage::DetailStage;
use thiserror::Error;
use tryon_core::frames::{CoarseFrame, FineSurface, lattice_index, lattice_len};
use tryon_core::math::{Real, Vec3, unit, vertex_normals};
use tryon_core::stages::{Collider, Probe};
use tryon_core::topology::Csr;

/// Parameters of the detail stages.
#[derive(Clone, Debug, PartialEq)]
pub struct DetailParams {
    /// Run the wrinkle model (P1.4.3).
    pub wrinkles: bool,
    /// Run fine penetration removal (P1.4.2).
    pub fine_collision: bool,
    /// Blend normals (P1.4.4).
    pub blend_normals: bool,
    /// k_out-plane of eqs. 10 and 12 (m/N).
    pub k_out_plane: Real,
    /// Height at which the deformed normal takes over fully (m), eq. 13.
    pub h_normal: Real,
    /// Frame time (s) for eq. 12.
    pub dt: Real,
    /// Distance fine vertices keep from the body (m).
    pub skin: Real,
    /// A vertex within this distance of the body "touches" it, and the lattice below it is probed (m).
    pub margin: Real,
    /// Longest a fine edge may get through height differences, over its reference length.
    pub max_fine_stretch: Real,
}

impl Default for DetailParams {
    fn default() -> Self {
        DetailParams {
            wrinkles: true,
            fine_collision: true,
            blend_normals: true,
            k_out_plane: 1.0,
            h_normal: 0.005,
            dt: 1.0 / 30.0,
            skin: 0.001,
            margin: 0.01,
            max_fine_stretch: 1.25,
        }
    }
}

/// Why a detail model could not be built.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum DetailError {
    #[error("fine surface has no lattice (segments 0): refine it first")]
    NoLattice,
    #[error(
        "fine surface lattice has {got} entries, {expected} expected for {triangles} coarse triangles at {segments} segments"
    )]
    Lattice {
        got: usize,
        expected: usize,
        triangles: usize,
        segments: u32,
    },
    #[error("fine surface: consecutive lattice vertices are not joined by a fine triangle edge")]
    NotALattice,
    #[error("coarse triangle {face} refers to vertex {vertex}, but the rest shape has {count}")]
    Coarse {
        face: usize,
        vertex: u32,
        count: usize,
    },
    #[error("parameter {name} = {value} is out of range: expected {expected}")]
    Param {
        name: &'static str,
        value: Real,
        expected: &'static str,
    },
}

/// Per-frame figures of the detail stages.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DetailStats {
    /// Fine vertices probed by the fine collision this frame.
    pub probed: usize,
    /// Fine vertices raised out of the body this frame.
    pub raised: usize,
    /// Largest wrinkle height (m).
    pub max_height: Real,
}

/// P1 section 4's detail model over one fine lattice.
#[derive(Clone, Debug)]
pub struct Detail {
    pub params: DetailParams,
    n: u32,
    coarse_vertices: usize,
    coarse_tris: Vec<[u32; 3]>,
    lattice: Vec<u32>,
    /// Unique coarse edges and their rest lengths.
    pub edges: Vec<[u32; 2]>,
    pub edge_rest: Vec<Real>,
    /// Fine vertices along each coarse edge, from `edges[e][0]` to `edges[e][1]`.
    edge_fine: Csr,
    /// Coarse edges of each coarse triangle (a-b, b-c, c-a).
    tri_edges: Vec<[u32; 3]>,
    /// Coarse edges around each coarse vertex.
    vertex_edges: Csr,
    /// Fine triangles around each fine vertex, and how many fine triangles there were.
    vertex_tris: Csr,
    tri_count: usize,
    /// Each fine edge once (i < j), for the passes that visit edges rather than vertices.
    fine_edges: Vec<[u32; 2]>,
    /// Interior fine vertices of each coarse triangle.
    interior: Csr,
    /// The lines forces are interpolated along (eqs. 4-5), built once: first each coarse edge's
    /// fine vertices (`edge_fine`'s rows), then inside each coarse triangle the lattice rows of
    /// both directions. Per item, `line_step` is the fine edge to the next item (unused on a line's
    /// last item) and `line_sign` is +1 when that step runs from the edge's second vertex to its
    /// first (the direction of `x[i] - x[j]`), -1 otherwise.
    lines: Csr,
    line_step: Vec<u32>,
    line_sign: Vec<Real>,
    /// Per line: its interior vertices already have a force from the other lattice direction,
    /// which this line's is averaged with.
    line_average: Vec<bool>,
    /// This frame's length and unit direction (`x[i] - x[j]`, zero when degenerate) of each fine edge.
    edge_len: Vec<Real>,
    edge_unit: Vec<Vec3>,
    /// Carried wrinkle height of each fine vertex (m).
    pub height: Vec<Real>,
    /// Penetration height of each fine vertex this frame (m).
    pub raise: Vec<Real>,
    pub stats: DetailStats,
    reference: Vec<Vec3>,
    control: Vec<Vec3>,
    ef: Vec<Vec3>,
    vforce: Vec<Real>,
    expected: Vec<Real>,
    required_edge: Vec<Real>,
    required_vertex: Vec<Real>,
    weights: Vec<Real>,
    new_height: Vec<Real>,
    touched: Vec<u32>,
    stamp: u32,
    which: Vec<u32>,
    probes: Vec<Probe>,
    deformed_normals: Vec<Vec3>,
}

fn csr(rows: usize, pairs: &mut [(u32, u32)]) -> Csr {
    pairs.sort_unstable();
    let mut offsets = vec![0u32; rows + 1];
    for &(r, _) in pairs.iter() {
        offsets[r as usize + 1] += 1;
    }
    for r in 0..rows {
        offsets[r + 1] += offsets[r];
    }
    Csr {
        offsets,
        items: pairs.iter().map(|p| p.1).collect(),
    }
}

impl Detail {
    /// A detail model for a fine surface laid out by a refiner, with the coarse cloth's rest shape
    /// (its edge lengths are the rest lengths).
    pub fn new(
        fine: &FineSurface,
        coarse_rest: &[Vec3],
        params: DetailParams,
    ) -> Result<Self, DetailError> {
        let check = |name, value: Real, ok: bool, expected| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(DetailError::Param {
                    name,
                    value,
                    expected,
                })
            }
        };
        check(
            "k_out_plane",
            params.k_out_plane,
            params.k_out_plane >= 0.0,
            ">= 0",
        )?;
        check("h_normal", params.h_normal, params.h_normal > 0.0, "> 0")?;
        check("dt", params.dt, params.dt > 0.0, "> 0")?;
        check("skin", params.skin, params.skin >= 0.0, ">= 0")?;
        check(
            "margin",
            params.margin,
            params.margin >= params.skin,
            ">= skin",
        )?;
        check(
            "max_fine_stretch",
            params.max_fine_stretch,
            params.max_fine_stretch >= 1.0,
            ">= 1",
        )?;
        let n = fine.segments;
        if n == 0 {
            return Err(DetailError::NoLattice);
        }
        let per = lattice_len(n);
        let tris = fine.coarse_triangles.clone();
        if fine.lattice.len() != tris.len() * per {
            return Err(DetailError::Lattice {
                got: fine.lattice.len(),
                expected: tris.len() * per,
                triangles: tris.len(),
                segments: n,
            });
        }
        let nc = coarse_rest.len();
        for (face, t) in tris.iter().enumerate() {
            if let Some(&vertex) = t.iter().find(|v| **v as usize >= nc) {
                return Err(DetailError::Coarse {
                    face,
                    vertex,
                    count: nc,
                });
            }
        }
        let m = fine.positions.len();
        let at = |f: usize, i: u32, j: u32| fine.lattice[f * per + lattice_index(n, i, j)];
        let mut edge_id = std::collections::HashMap::new();
        let mut edges = Vec::new();
        let mut tri_edges = Vec::with_capacity(tris.len());
        let mut interior_rows = Vec::new();
        for (f, t) in tris.iter().enumerate() {
            let mut te = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                let id = *edge_id.entry(key).or_insert_with(|| {
                    edges.push([a, b]);
                    edges.len() as u32 - 1
                });
                te[k] = id;
            }
            tri_edges.push(te);
            for j in 1..n {
                for i in 1..n - j {
                    interior_rows.push((f as u32, at(f, i, j)));
                }
            }
        }
        // Fill edge_fine in order: rows (edge, step) -> fine vertex.
        let mut edge_fine_pairs: Vec<(u32, u32)> =
            Vec::with_capacity(edges.len() * (n as usize + 1));
        {
            let mut seen = vec![false; edges.len()];
            for (f, t) in tris.iter().enumerate() {
                for k in 0..3 {
                    let id = tri_edges[f][k] as usize;
                    if seen[id] || [t[k], t[(k + 1) % 3]] != edges[id] {
                        continue;
                    }
                    seen[id] = true;
                    for s in 0..=n {
                        let (i, j) = match k {
                            0 => (s, 0),
                            1 => (n - s, s),
                            _ => (0, n - s),
                        };
                        edge_fine_pairs.push((id as u32, at(f, i, j)));
                    }
                }
            }
        }
        // In order along each edge (a CSR built by sorting would lose the order).
        let mut ef_offsets = vec![0u32; edges.len() + 1];
        let mut ef_items = vec![0u32; edges.len() * (n as usize + 1)];
        {
            let mut fill = vec![0usize; edges.len()];
            for &(e, v) in &edge_fine_pairs {
                let e = e as usize;
                ef_items[e * (n as usize + 1) + fill[e]] = v;
                fill[e] += 1;
            }
            for e in 0..edges.len() {
                ef_offsets[e + 1] = ((e + 1) * (n as usize + 1)) as u32;
            }
        }
        let edge_fine = Csr {
            offsets: ef_offsets,
            items: ef_items,
        };
        let edge_rest = edges
            .iter()
            .map(|[a, b]| (coarse_rest[*a as usize] - coarse_rest[*b as usize]).norm())
            .collect();
        let mut ve: Vec<(u32, u32)> = edges
            .iter()
            .enumerate()
            .flat_map(|(e, [a, b])| [(*a, e as u32), (*b, e as u32)])
            .collect();
        let vertex_edges = csr(nc, &mut ve);
        let mut ring_pairs: Vec<(u32, u32)> = Vec::with_capacity(fine.triangles.len() * 6);
        for t in &fine.triangles {
            for k in 0..3 {
                ring_pairs.push((t[k], t[(k + 1) % 3]));
                ring_pairs.push((t[(k + 1) % 3], t[k]));
            }
        }
        ring_pairs.sort_unstable();
        ring_pairs.dedup();
        let fine_edges: Vec<[u32; 2]> = ring_pairs
            .iter()
            .filter(|(i, j)| i < j)
            .map(|&(i, j)| [i, j])
            .collect();
        let mut vt: Vec<(u32, u32)> = fine
            .triangles
            .iter()
            .enumerate()
            .flat_map(|(f, t)| t.map(|v| (v, f as u32)))
            .collect();
        let vertex_tris = csr(m, &mut vt);
        let interior = csr(tris.len(), &mut interior_rows);
        // The interpolation lines, each step named by its fine edge.
        let edge_index: std::collections::HashMap<(u32, u32), u32> = fine_edges
            .iter()
            .enumerate()
            .map(|(k, &[i, j])| ((i, j), k as u32))
            .collect();
        let mut line_offsets = vec![0u32];
        let (mut line_items, mut line_step, mut line_sign) = (Vec::new(), Vec::new(), Vec::new());
        let mut line_average = Vec::new();
        let mut push_line = |verts: &[u32], average: bool| {
            for (k, &v) in verts.iter().enumerate() {
                line_items.push(v);
                let (e, sign) = match verts.get(k + 1) {
                    Some(&w) => (
                        edge_index
                            .get(&(v.min(w), v.max(w)))
                            .copied()
                            .unwrap_or(u32::MAX),
                        if v > w { 1.0 } else { -1.0 },
                    ),
                    None => (u32::MAX, 0.0),
                };
                line_step.push(e);
                line_sign.push(sign);
            }
            line_offsets.push(line_items.len() as u32);
            line_average.push(average);
        };
        for e in 0..edges.len() {
            push_line(edge_fine.row(e), false);
        }
        let mut verts = Vec::new();
        for f in 0..tris.len() {
            for dir in 0..2 {
                for r in 1..n {
                    verts.clear();
                    for s in 0..=n - r {
                        let (i, j) = if dir == 0 { (s, r) } else { (r, s) };
                        verts.push(at(f, i, j));
                    }
                    if verts.len() >= 3 {
                        push_line(&verts, dir == 1);
                    }
                }
            }
        }
        if line_step
            .iter()
            .zip(&line_sign)
            .any(|(&e, &s)| s != 0.0 && e == u32::MAX)
        {
            return Err(DetailError::NotALattice);
        }
        let lines = Csr {
            offsets: line_offsets,
            items: line_items,
        };
        Ok(Detail {
            params,
            n,
            coarse_vertices: nc,
            coarse_tris: tris,
            lattice: fine.lattice.clone(),
            edges,
            edge_rest,
            edge_fine,
            tri_edges,
            vertex_edges,
            vertex_tris,
            tri_count: fine.triangles.len(),
            fine_edges,
            interior,
            lines,
            line_step,
            line_sign,
            line_average,
            edge_len: Vec::new(),
            edge_unit: Vec::new(),
            height: vec![0.0; m],
            raise: vec![0.0; m],
            stats: DetailStats::default(),
            reference: Vec::new(),
            control: Vec::new(),
            ef: vec![Vec3::zeros(); m],
            vforce: vec![0.0; m],
            expected: vec![0.0; m],
            required_edge: Vec::new(),
            required_vertex: Vec::new(),
            weights: Vec::new(),
            new_height: Vec::new(),
            touched: vec![0; m],
            stamp: 0,
            which: Vec::new(),
            probes: Vec::new(),
            deformed_normals: Vec::new(),
        })
    }

    /// Fine vertices along coarse edge `e`, from `edges[e][0]` to `edges[e][1]`.
    pub fn edge_vertices(&self, e: usize) -> &[u32] {
        self.edge_fine.row(e)
    }

    /// Takes the refined surface as this frame's reference: `S` and `n` are kept, and the
    /// positions become `S + dh n` with the carried wrinkle height.
    fn take_reference(&mut self, fine: &mut FineSurface) {
        // The refiner rewrites every position each frame, so the buffers are swapped rather
        // than copied: `fine.positions` gets last frame's reference, overwritten below.
        std::mem::swap(&mut self.reference, &mut fine.positions);
        fine.positions.resize(self.reference.len(), Vec3::zeros());
        self.control.clone_from(&fine.normals);
        self.raise.iter_mut().for_each(|r| *r = 0.0);
        for i in 0..fine.positions.len() {
            fine.positions[i] = self.reference[i] + self.control[i] * self.height[i];
        }
    }

    /// This frame's fine edge lengths and unit directions (`x[i] - x[j]`, zero when degenerate).
    fn edge_geometry(&mut self, x: &[Vec3]) {
        let ne = self.fine_edges.len();
        self.edge_len.resize(ne, 0.0);
        self.edge_unit.resize(ne, Vec3::zeros());
        for ((&[i, j], len), unit) in self
            .fine_edges
            .iter()
            .zip(&mut self.edge_len)
            .zip(&mut self.edge_unit)
        {
            let d = x[i as usize] - x[j as usize];
            let l = d.norm();
            *len = l;
            *unit = if l > 1e-30 {
                d * (1.0 / l)
            } else {
                Vec3::zeros()
            };
        }
    }

    /// Forces on fine vertices interpolated from the coarse elastic forces (eqs. 4-5): along each
    /// coarse edge from its ends, then inside each coarse triangle along both lattice directions
    /// from the edges, averaged.
    fn interpolate_forces(&mut self, coarse: &CoarseFrame, nf: usize) {
        let mut ef = std::mem::take(&mut self.ef);
        ef.clear();
        ef.resize(nf, Vec3::zeros());
        for k in 0..self.coarse_vertices.min(nf) {
            ef[k] = coarse.elastic_force.get(k).copied().unwrap_or_default();
        }
        let mut weights = std::mem::take(&mut self.weights);
        let offsets = &self.lines.offsets;
        for (line, &average) in self.line_average.iter().enumerate() {
            let (a, b) = (offsets[line] as usize, offsets[line + 1] as usize);
            let m = b - a;
            if m < 3 {
                continue;
            }
            let items = &self.lines.items[a..b];
            let (steps, signs) = (&self.line_step[a..b], &self.line_sign[a..b]);
            if weights.len() < m {
                weights.resize(m, 0.0);
            }
            let w = &mut weights[..m];
            // Transmission c_k at interior points (eq. 4), clamped to [0, 1] (a fold bent past
            // 90 degrees transmits nothing): the cosine between the steps into and out of the
            // point.
            let mut total = 0.0;
            for k in 1..m - 1 {
                let (e1, e2) = (steps[k - 1] as usize, steps[k] as usize);
                let cos = if self.edge_len[e1] * self.edge_len[e2] > 1e-30 {
                    signs[k - 1] * signs[k] * self.edge_unit[e1].dot(&self.edge_unit[e2])
                } else {
                    1.0
                };
                w[k] = cos.clamp(0.0, 1.0);
                total += w[k];
            }
            // Cumulative weights (eq. 5).
            if total < 1e-12 {
                for (k, wk) in w.iter_mut().enumerate() {
                    *wk = k as Real / (m - 1) as Real;
                }
            } else {
                let mut run = 0.0;
                for wk in &mut w[1..m - 1] {
                    let c = *wk;
                    *wk = (run + 0.5 * c) / total;
                    run += c;
                }
            }
            let (f1, fn_) = (ef[items[0] as usize], ef[items[m - 1] as usize]);
            for (&v, &wk) in items[1..m - 1].iter().zip(&w[1..m - 1]) {
                let v = v as usize;
                let add = f1 + (fn_ - f1) * wk;
                ef[v] = if average { (ef[v] + add) * 0.5 } else { add };
            }
        }
        self.ef = ef;
        self.weights = weights;
    }

    /// P1.4.3: updates the carried wrinkle height and writes `S + dh n` into `fine.positions`
    /// (taking the refiner's positions and normals as the reference surface: call it once per
    /// frame, after the refiner has written the surface).
    pub fn wrinkle(&mut self, coarse: &CoarseFrame, fine: &mut FineSurface) {
        self.take_reference(fine);
        if !self.params.wrinkles {
            return;
        }
        let nf = fine.positions.len();
        let x = std::mem::take(&mut fine.positions);
        self.edge_geometry(&x);
        self.interpolate_forces(coarse, nf);
        // Vertical forces (eqs. 6-7).
        self.vforce.clear();
        self.vforce.resize(nf, 0.0);
        for (&[i, j], u) in self.fine_edges.iter().zip(&self.edge_unit) {
            let (i, j) = (i as usize, j as usize);
            self.vforce[i] += u.dot(&self.ef[j]);
            self.vforce[j] -= u.dot(&self.ef[i]);
        }
        for v in &mut self.vforce {
            if !v.is_finite() {
                *v = 0.0;
            }
        }
        // Required length change per coarse edge (eq. 8, section 4.3.4's sign), per coarse vertex.
        self.required_edge.clear();
        for e in 0..self.edges.len() {
            // The coarse edge's line: its steps are its fine path.
            let (a, b) = (
                self.lines.offsets[e] as usize,
                self.lines.offsets[e + 1] as usize,
            );
            let len: Real = self.line_step[a..b - 1]
                .iter()
                .map(|&k| self.edge_len[k as usize])
                .sum();
            self.required_edge.push(self.edge_rest[e] - len);
        }
        self.required_vertex.clear();
        for v in 0..self.coarse_vertices {
            let row = self.vertex_edges.row(v);
            let s: Real = row.iter().map(|&e| self.required_edge[e as usize]).sum();
            self.required_vertex.push(if row.is_empty() {
                0.0
            } else {
                s / row.len() as Real
            });
        }
        let k = self.params.k_out_plane;
        let dt = self.params.dt;
        // Expected length change (eqs. 9-10), summed per fine edge into both ends: the sign test
        // `(v_i - v_j)(dh_i - dh_j) >= 0` is the same product seen from either end.
        self.expected.clear();
        self.expected.resize(nf, 0.0);
        for &[i, j] in &self.fine_edges {
            let (i, j) = (i as usize, j as usize);
            let dv = self.vforce[i] - self.vforce[j];
            let term = k * dv.abs();
            let term = if dv * (self.height[i] - self.height[j]) >= 0.0 {
                term
            } else {
                -term
            };
            self.expected[i] += term;
            self.expected[j] += term;
        }
        let mut new_height = std::mem::take(&mut self.new_height);
        new_height.clone_from(&self.height);
        for i in 0..nf {
            let src = &fine.sources[i];
            let req = if i < self.coarse_vertices {
                self.required_vertex[i]
            } else if let Some(t) = self.coarse_tris.get(src.face as usize) {
                (0..3)
                    .map(|c| src.bary[c] * self.required_vertex[t[c] as usize])
                    .sum()
            } else {
                0.0
            };
            let vi = self.vforce[i];
            let expected = self.expected[i];
            let ratio = if expected.abs() > 1e-30 {
                req / expected
            } else {
                0.0
            };
            let dh = if ratio > 0.0 && ratio.is_finite() {
                let by_length = ratio * k * vi;
                let by_force = k * vi * dt;
                if by_length.abs() < by_force.abs() {
                    by_length
                } else {
                    by_force
                }
            } else {
                0.0
            };
            new_height[i] = (self.height[i] + dh).max(0.0);
        }
        // No wrinkle inside a triangle all of whose edges are stretched.
        for (f, te) in self.tri_edges.iter().enumerate() {
            if te.iter().all(|&e| self.required_edge[e as usize] < 0.0) {
                for &v in self.interior.row(f) {
                    new_height[v as usize] = 0.0;
                }
            }
        }
        // Neighbours may not be pulled apart beyond max_fine_stretch (two Gauss-Seidel passes,
        // lowering the higher vertex). The height difference an edge allows is `slope` times its
        // length on the reference surface, compared squared; its square root is taken only
        // where the edge is shortened (most edges have equal heights, zero, at both ends).
        let r = self.params.max_fine_stretch;
        let slope2 = (r * r - 1.0).max(0.0);
        for _ in 0..2 {
            for &[i, j] in &self.fine_edges {
                let (i, j) = (i as usize, j as usize);
                let d = new_height[i] - new_height[j];
                if d == 0.0 {
                    continue;
                }
                let allowed2 = (self.reference[i] - self.reference[j]).norm_squared() * slope2;
                if d * d > allowed2 {
                    let allowed = allowed2.sqrt();
                    if d > 0.0 {
                        new_height[i] = new_height[j] + allowed;
                    } else {
                        new_height[j] = new_height[i] + allowed;
                    }
                }
            }
        }
        self.new_height = std::mem::replace(&mut self.height, new_height);
        let mut x = x;
        let mut hmax: Real = 0.0;
        for i in 0..nf {
            x[i] = self.reference[i] + self.control[i] * self.height[i];
            hmax = hmax.max(self.height[i]);
        }
        self.stats.max_height = hmax;
        fine.positions = x;
    }

    /// Probes the vertices in `self.which`, raises those within `skin` of the body and marks those
    /// within `margin` as touching. Returns how many were raised.
    fn probe_and_raise(&mut self, fine: &mut FineSurface, collider: &mut dyn Collider) -> usize {
        let skin = self.params.skin;
        let margin = self.params.margin;
        let mut raised = 0;
        for pass in 0..2 {
            collider.probe_near(
                &fine.positions,
                &self.which,
                margin.max(skin),
                &mut self.probes,
            );
            let mut again = Vec::new();
            for (k, &v) in self.which.iter().enumerate() {
                let pr = self.probes[k];
                let v = v as usize;
                if pass == 0 && pr.distance < margin {
                    self.touched[v] = self.stamp;
                }
                if !(pr.distance < skin)
                    || !pr.distance.is_finite()
                    || !tryon_core::math::is_finite(&pr.normal)
                {
                    continue;
                }
                let need = skin - pr.distance;
                let n = self.control[v];
                let along = n.dot(&pr.normal);
                if along > 0.25 {
                    let dh = need / along;
                    self.raise[v] += dh;
                    fine.positions[v] += n * dh;
                } else {
                    // The control direction runs along or into the body: leave along the body normal.
                    fine.positions[v] += pr.normal * need;
                }
                if pass == 0 {
                    raised += 1;
                    again.push(v as u32);
                }
            }
            if again.is_empty() {
                break;
            }
            self.which = again;
        }
        raised
    }

    /// P1.4.2: hierarchical fine penetration removal (see the crate docs).
    pub fn fine_collision(
        &mut self,
        coarse: &CoarseFrame,
        fine: &mut FineSurface,
        collider: &mut dyn Collider,
    ) {
        if self.reference.len() != fine.positions.len() {
            self.take_reference(fine);
        }
        self.stamp = self.stamp.wrapping_add(1).max(1);
        let stamp = self.stamp;
        let mut probed = 0;
        let mut raised = 0;
        // Level 0: every coarse vertex (contacts count as touching).
        self.which.clear();
        self.which.extend(0..self.coarse_vertices as u32);
        probed += self.which.len();
        raised += self.probe_and_raise(fine, collider);
        for c in &coarse.contacts {
            if (c.point as usize) < self.coarse_vertices {
                self.touched[c.point as usize] = stamp;
            }
        }
        let n = self.n;
        let per = lattice_len(n);
        let level = n.trailing_zeros();
        let faces: Vec<usize> = (0..self.coarse_tris.len())
            .filter(|&f| {
                self.coarse_tris[f]
                    .iter()
                    .any(|&v| self.touched[v as usize] == stamp)
            })
            .collect();
        let mut visited = vec![false; 0];
        visited.resize(fine.positions.len(), false);
        for l in 1..=level {
            let s = n >> l; // step of the level-l lattice
            self.which.clear();
            for &f in &faces {
                let lat = &self.lattice[f * per..(f + 1) * per];
                let at = |i: u32, j: u32| lat[lattice_index(n, i, j)] as usize;
                let mut j = 0;
                while j <= n {
                    let mut i = 0;
                    while i + j <= n {
                        let (oi, oj) = ((i / s) % 2 == 1, (j / s) % 2 == 1);
                        if oi || oj {
                            let (a, b) = match (oi, oj) {
                                (true, false) => (at(i - s, j), at(i + s, j)),
                                (false, true) => (at(i, j - s), at(i, j + s)),
                                _ => (at(i + s, j - s), at(i - s, j + s)),
                            };
                            let v = at(i, j);
                            if !visited[v] && (self.touched[a] == stamp || self.touched[b] == stamp)
                            {
                                visited[v] = true;
                                self.which.push(v as u32);
                            }
                        }
                        i += s;
                    }
                    j += s;
                }
            }
            probed += self.which.len();
            raised += self.probe_and_raise(fine, collider);
        }
        self.stats.probed = probed;
        self.stats.raised = raised;
    }

    /// P1.4.4: blends the deformed surface's normals with the PN normals by height (eqs. 13-14).
    ///
    /// Where the height is zero the PN normal is kept as it is, so the deformed surface's normal
    /// (area-weighted over the vertex's triangles) is computed only where a vertex is raised.
    pub fn blend_normals(&mut self, fine: &mut FineSurface) {
        let gather = self.tri_count == fine.triangles.len()
            && self.vertex_tris.offsets.len() == fine.positions.len() + 1;
        if !gather {
            vertex_normals(&fine.positions, &fine.triangles, &mut self.deformed_normals);
        }
        let h = self.params.h_normal;
        let x = &fine.positions;
        for i in 0..x.len() {
            let dh = self.height[i] + self.raise[i];
            let alpha = (dh / h).clamp(0.0, 1.0);
            let pn = self.control.get(i).copied().unwrap_or(fine.normals[i]);
            if !(alpha > 0.0) {
                fine.normals[i] = pn;
                continue;
            }
            let mut nd = if gather {
                let mut sum = Vec3::zeros();
                for &t in self.vertex_tris.row(i) {
                    let [a, b, c] = fine.triangles[t as usize];
                    let (a, b, c) = (a as usize, b as usize, c as usize);
                    sum += (x[b] - x[a]).cross(&(x[c] - x[a]));
                }
                unit(&sum, 1e-30).unwrap_or(Vec3::y())
            } else {
                self.deformed_normals[i]
            };
            // The deformed surface is built from the same triangles, so its normal faces the
            // PN normal's side; flip one that does not (a fold turned over).
            if nd.dot(&pn) < 0.0 {
                nd = -nd;
            }
            fine.normals[i] = unit(&(nd * alpha + pn * (1.0 - alpha)), 1e-30).unwrap_or(pn);
        }
    }

    /// Length restoration over the coarse edges that are compressed on the reference surface:
    /// mean of `|fine path length - rest| / rest` (with the path through `positions`), and how many
    /// edges counted.
    pub fn length_error(&self, positions: &[Vec3]) -> (Real, usize) {
        let (mut sum, mut count) = (0.0, 0);
        for e in 0..self.edges.len() {
            let row = self.edge_fine.row(e);
            let path = |x: &[Vec3]| -> Real {
                row.windows(2)
                    .map(|w| (x[w[1] as usize] - x[w[0] as usize]).norm())
                    .sum()
            };
            let rest = self.edge_rest[e];
            if self.reference.len() != positions.len() || !(rest > 0.0) {
                continue;
            }
            if path(&self.reference) < rest {
                sum += (path(positions) - rest).abs() / rest;
                count += 1;
            }
        }
        (if count > 0 { sum / count as Real } else { 0.0 }, count)
    }
}

#[cfg(test)]
mod tests;
