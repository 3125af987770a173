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
//!   That is the `force` model ([`WrinkleModel::Force`]). The default, `compression`
//!   ([`relief`]), takes the height from the coarse triangles' compression instead: stripes across
//!   its direction, as high as gives the lost length back, with eq. 8's deficit of the fine paths
//!   fed back into the amplitude; then the same `max_fine_stretch` limit.
//! - [`Detail::fine_collision`] (P1.4.2): hierarchical from the coarse contacts. The lattice is
//!   probed level by level, a vertex only when the body may be within `margin` of it, judged from
//!   the two vertices of the coarser level whose edge it halves: its distance is at least theirs
//!   less its distance from them, and a contact's or raised vertex's is taken as 0. (P1 probes
//!   below touched vertices only; a coarse triangle spanning a thigh or an arm with its corners
//!   beyond `margin` cut into it between them.) A vertex inside the body, or within
//!   `skin` of it, is raised along its control direction until it is `skin` out (`dh_penetration`).
//!   This height is not carried to the next frame (carrying it would leave bumps where the body was);
//!   the wrinkle height is.
//! - [`Detail::blend_normals`] (P1.4.4, eqs. 13-14): the deformed surface's normal blended with the
//!   PN normal by `alpha = min(dh / h_normal, 1)`.

mod collide;
mod model;
pub mod relief;
pub mod stage;

pub use stage::DetailStage;
use thiserror::Error;
use tryon_core::frames::{FineSurface, lattice_index, lattice_len};
use tryon_core::math::{Real, Vec3};
use tryon_core::stages::Probe;
use tryon_core::topology::Csr;

/// Parameters of the detail stages.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DetailParams {
    /// Run the wrinkle model (P1.4.3).
    pub wrinkles: bool,
    /// Which heights the wrinkle model gives (see [`WrinkleModel`]).
    pub model: WrinkleModel,
    /// Wavelength of the compression relief, in fine edges (>= 2).
    pub period: Real,
    /// Compression the fabric takes up in its plane without buckling: the relief gives back only
    /// what lies beyond it.
    pub min_compression: Real,
    /// Compression the relief gives back at most (`1/s - 1` of the smallest principal stretch `s`).
    pub max_compression: Real,
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
    /// A finer level's vertex is probed where the body may be within this distance of it (m).
    pub margin: Real,
    /// Longest a fine edge may get through height differences, over its reference length.
    pub max_fine_stretch: Real,
    /// After the fine collision, lift the fine surface over body vertices that poke through
    /// between its vertices (a nipple, a shoulder's tip), by the collider's `pokes`.
    pub pokes: bool,
}

impl Default for DetailParams {
    fn default() -> Self {
        DetailParams {
            wrinkles: true,
            model: WrinkleModel::Compression,
            period: 4.0,
            min_compression: 0.0,
            max_compression: 0.5,
            fine_collision: true,
            blend_normals: true,
            k_out_plane: 1.0,
            h_normal: 0.005,
            dt: 1.0 / 30.0,
            skin: 0.001,
            margin: 0.01,
            max_fine_stretch: 1.25,
            pokes: true,
        }
    }
}

/// Where the wrinkle heights come from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WrinkleModel {
    /// P1.4.3 as written: heights driven by the coarse elastic forces (eqs. 4-12), carried from
    /// frame to frame.
    Force,
    /// Stripes across each coarse vertex's compression direction whose amplitude gives the lost
    /// length back ([`relief`]), then P1.4.3.4's constraints.
    #[default]
    Compression,
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
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DetailStats {
    /// Fine vertices probed by the fine collision this frame.
    pub probed: usize,
    /// Fine vertices raised out of the body this frame.
    pub raised: usize,
    /// Fine vertices lifted over body vertices poking through between them this frame.
    pub lifted: usize,
    /// Largest wrinkle height (m).
    pub max_height: Real,
}

/// P1 section 4's detail model over one fine lattice.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
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
    /// The compression relief's geometry and fields.
    pub relief: relief::Relief,
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
    /// Per fine vertex, a lower bound of its distance to the body this frame (`fine_collision`).
    near: Vec<Real>,
    which: Vec<u32>,
    probes: Vec<Probe>,
    deformed_normals: Vec<Vec3>,
    /// Scratch: each fine triangle's (unnormalised) normal this frame.
    #[serde(skip)]
    face_cross: Vec<Vec3>,
}

pub(crate) fn csr(rows: usize, pairs: &mut [(u32, u32)]) -> Csr {
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
        check("period", params.period, params.period >= 2.0, ">= 2")?;
        check(
            "min_compression",
            params.min_compression,
            (0.0..=0.2).contains(&params.min_compression),
            "0..=0.2",
        )?;
        check(
            "max_compression",
            params.max_compression,
            (0.0..=1.0).contains(&params.max_compression),
            "0..=1",
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
        let relief = relief::Relief::new(&tris, coarse_rest, fine, n, params.period);
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
            relief,
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
            near: vec![0.0; m],
            which: Vec::new(),
            probes: Vec::new(),
            deformed_normals: Vec::new(),
            face_cross: Vec::new(),
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
}

#[cfg(test)]
mod poke_tests;
#[cfg(test)]
mod tests;
