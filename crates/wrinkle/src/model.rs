//! The wrinkle model of P1.4.3 (eqs. 3-12 and the constraints of 4.3.4): each fine edge's
//! geometry, forces interpolated from the coarse particles, and the height change per frame.

use crate::{Detail, WrinkleModel};
use tryon_core::frames::{CoarseFrame, FineSurface};
use tryon_core::math::{Real, Vec3};

impl Detail {
    /// This frame's fine edge lengths and unit directions (`x[i] - x[j]`, zero when degenerate).
    pub(crate) fn edge_geometry(&mut self, x: &[Vec3]) {
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
    pub(crate) fn interpolate_forces(&mut self, coarse: &CoarseFrame, nf: usize) {
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
        let mut new_height = std::mem::take(&mut self.new_height);
        new_height.resize(nf, 0.0);
        if self.params.model == WrinkleModel::Compression {
            let band = (self.params.min_compression, self.params.max_compression);
            self.relief
                .heights(&coarse.positions, fine, band, &mut new_height);
        } else {
            self.force_heights(coarse, fine, &x, &mut new_height);
        }
        self.constrain(&mut new_height);
        self.new_height = std::mem::replace(&mut self.height, new_height);
        let mut x = x;
        let mut hmax: Real = 0.0;
        for i in 0..nf {
            x[i] = self.reference[i] + self.control[i] * self.height[i];
            hmax = hmax.max(self.height[i]);
        }
        self.stats.max_height = hmax;
        if self.params.model == WrinkleModel::Compression {
            let paths = self.edge_paths(&x);
            self.relief
                .adapt(&self.edges, &paths, self.params.min_compression);
        }
        fine.positions = x;
    }

    /// Each coarse edge's rest length and fine path length through the reference surface and
    /// through `x`.
    pub(crate) fn edge_paths(&self, x: &[Vec3]) -> Vec<(Real, Real, Real)> {
        (0..self.edges.len())
            .map(|e| {
                let row = self.edge_fine.row(e);
                let path = |p: &[Vec3]| -> Real {
                    row.windows(2)
                        .map(|w| (p[w[1] as usize] - p[w[0] as usize]).norm())
                        .sum()
                };
                (self.edge_rest[e], path(&self.reference), path(x))
            })
            .collect()
    }

    /// P1.4.3's heights (eqs. 6-12) from the carried ones into `new_height`.
    fn force_heights(
        &mut self,
        coarse: &CoarseFrame,
        fine: &FineSurface,
        x: &[Vec3],
        new_height: &mut [Real],
    ) {
        let nf = x.len();
        self.edge_geometry(x);
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
        new_height.copy_from_slice(&self.height);
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
        // No wrinkle inside a triangle all of whose edges are stretched (P1.4.3.4; the
        // compression relief fades there instead, from its corners' fields).
        for (f, te) in self.tri_edges.iter().enumerate() {
            if te.iter().all(|&e| self.required_edge[e as usize] < 0.0) {
                for &v in self.interior.row(f) {
                    new_height[v as usize] = 0.0;
                }
            }
        }
    }

    /// P1.4.3.4's constraint on this frame's heights that both models share.
    fn constrain(&self, new_height: &mut [Real]) {
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
    }
}
