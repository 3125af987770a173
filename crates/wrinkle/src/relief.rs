//! Compression relief: wrinkle heights laid across the direction the coarse cloth is compressed
//! in, with the amplitude that gives the lost length back (the `compression` wrinkle model; P1's
//! force-driven heights are the `force` model in `model.rs`; why both, docs/decisions, *wrinkle model*
//! 2026-11-29).
//!
//! Each coarse triangle's deformation gradient `F` against its rest shape gives the smallest
//! principal stretch `s` (the square root of the smaller eigenvalue of `F^T F`) and its direction
//! `d` in the rest plane; where `s < 1` the cloth lost `1/s - 1` of its length along `d`. Each
//! coarse vertex sums `area * (1/s - 1) d d^T` over its triangles; the tensor's principal axis
//! `e` (power iteration from last frame's, so a near-isotropic squeeze does not spin the stripes)
//! is the vertex's wrinkle direction, and `c = e^T T e / area` its compression. A stripe field
//! anchored at the vertex's rest position `r`, `h(p) = A (1 - cos(2 pi (p - r).e / w)) / 2` with
//! wavelength `w = period` fine edges, has mean slope length `1 + (pi A / 2w)^2`, so
//! `A = (2w / pi) sqrt(c)` gives the length back (Rohmer et al. 2010 orient wrinkles by the
//! same compression direction). A fine vertex blends the fields of its coarse triangle's three
//! vertices by its barycentric weights: continuous across coarse edges, zero at coarse vertices
//! (the coarse particles stay where the solver put them, and the relief rises outward from them).

use tryon_core::frames::FineSurface;
use tryon_core::math::{Real, Vec3};
use tryon_core::topology::Csr;

/// The relief's precomputed rest geometry and its per-frame fields.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Relief {
    tris: Vec<[u32; 3]>,
    /// Per coarse triangle: an orthonormal basis of its rest plane and the inverse of its rest
    /// edge matrix in that basis (row-major 2x2), and its rest area.
    basis: Vec<[Vec3; 2]>,
    dm_inv: Vec<[Real; 4]>,
    area: Vec<Real>,
    vertex_faces: Csr,
    rest: Vec<Vec3>,
    /// Per coarse vertex: stripe wavelength (m).
    wavelength: Vec<Real>,
    /// Per fine vertex: its rest position on the flat coarse rest triangle.
    fine_rest: Vec<Vec3>,
    /// Per coarse triangle this frame: `1/s - 1` (0 where not compressed) and `d`.
    tri_comp: Vec<Real>,
    tri_dir: Vec<Vec3>,
    /// Per coarse vertex this frame: wrinkle direction `e` and stripe amplitude `A` (m).
    pub dir: Vec<Vec3>,
    pub amplitude: Vec<Real>,
    /// Per coarse vertex, carried: the factor on `A` that last frames' fine paths asked for.
    pub gain: Vec<Real>,
}

/// Bounds of [`Relief::gain`], and of its change in one frame.
const GAIN: (Real, Real) = (0.25, 4.0);
const GAIN_STEP: (Real, Real) = (0.8, 1.25);
/// How far a gain moves toward its neighbours' mean each frame.
const SMOOTH: Real = 0.1;

/// Smallest principal stretch of a 2x2 right Cauchy-Green tensor `[[a, b], [b, c]]` squared, and
/// its eigenvector (unnormalised).
fn min_stretch2(a: Real, b: Real, c: Real) -> (Real, Real, Real) {
    let half = 0.5 * (a - c);
    let lmin = 0.5 * (a + c) - (half * half + b * b).sqrt();
    let (x, y) = if b.abs() > 1e-14 * (a + c).abs().max(1e-300) {
        (b, lmin - a)
    } else if a <= c {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    (lmin, x, y)
}

/// The stripe profile `(1 - cos(2 pi phase)) / 2 = sin^2(pi phase)`, from 0 at whole phases to 1
/// half-way; the sine by its Taylor series to degree 9 on [-pi/2, pi/2] (error under 4e-6), which
/// costs a third of libm's cosine.
#[inline]
fn stripe(phase: Real) -> Real {
    let x = std::f64::consts::PI * (phase - phase.round());
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0)))));
    s * s
}

impl Relief {
    /// Rest geometry for the coarse triangles `tris` over `rest`, and the fine surface laid on
    /// them at `n` segments per coarse edge; stripes `period` fine edges wide.
    pub fn new(tris: &[[u32; 3]], rest: &[Vec3], fine: &FineSurface, n: u32, period: Real) -> Self {
        let nc = rest.len();
        let mut basis = Vec::with_capacity(tris.len());
        let mut dm_inv = Vec::with_capacity(tris.len());
        let mut area = Vec::with_capacity(tris.len());
        let mut edge_sum = vec![0.0; nc];
        let mut edge_count = vec![0.0; nc];
        let mut pairs = Vec::with_capacity(tris.len() * 3);
        for (f, t) in tris.iter().enumerate() {
            let [a, b, c] = t.map(|v| rest[v as usize]);
            let (e1, e2) = (b - a, c - a);
            let normal = e1.cross(&e2);
            let (u, v) = match (e1.try_normalize(1e-15), normal.try_normalize(1e-30)) {
                (Some(u), Some(nrm)) => (u, nrm.cross(&u)),
                _ => (Vec3::x(), Vec3::y()),
            };
            let (m00, m01, m10, m11) = (e1.dot(&u), e2.dot(&u), e1.dot(&v), e2.dot(&v));
            let det = m00 * m11 - m01 * m10;
            basis.push([u, v]);
            dm_inv.push(if det.abs() > 1e-18 {
                [m11 / det, -m01 / det, -m10 / det, m00 / det]
            } else {
                [0.0; 4]
            });
            area.push(0.5 * normal.norm());
            for k in 0..3 {
                let (i, j) = (t[k] as usize, t[(k + 1) % 3] as usize);
                let len = (rest[i] - rest[j]).norm();
                for v in [i, j] {
                    edge_sum[v] += len;
                    edge_count[v] += 1.0;
                }
                pairs.push((t[k], f as u32));
            }
        }
        let wavelength = edge_sum
            .iter()
            .zip(&edge_count)
            .map(|(s, c)| {
                if *c > 0.0 {
                    period * s / c / n as Real
                } else {
                    0.0
                }
            })
            .collect();
        let fine_rest = fine
            .sources
            .iter()
            .map(|src| match tris.get(src.face as usize) {
                Some(t) => (0..3).map(|k| rest[t[k] as usize] * src.bary[k]).sum(),
                None => Vec3::zeros(),
            })
            .collect();
        Relief {
            tris: tris.to_vec(),
            basis,
            dm_inv,
            area,
            vertex_faces: crate::csr(nc, &mut pairs),
            rest: rest.to_vec(),
            wavelength,
            fine_rest,
            tri_comp: vec![0.0; tris.len()],
            tri_dir: vec![Vec3::zeros(); tris.len()],
            dir: vec![Vec3::zeros(); nc],
            amplitude: vec![0.0; nc],
            gain: vec![1.0; nc],
        }
    }

    /// Each coarse triangle's compression beyond the fabric's own, `1/s - 1 - min` (at most
    /// `cap`), and its direction.
    fn triangle_strain(&mut self, x: &[Vec3], (min, cap): (Real, Real)) {
        for (f, t) in self.tris.iter().enumerate() {
            let [a, b, c] = t.map(|v| x[v as usize]);
            let (d1, d2) = (b - a, c - a);
            let m = self.dm_inv[f];
            let f1 = d1 * m[0] + d2 * m[2];
            let f2 = d1 * m[1] + d2 * m[3];
            let (lmin, ex, ey) = min_stretch2(f1.dot(&f1), f1.dot(&f2), f2.dot(&f2));
            let comp = if lmin < 1.0 - 1e-9 && m != [0.0; 4] {
                (1.0 / lmin.max(1e-6).sqrt() - 1.0 - min).clamp(0.0, cap)
            } else {
                0.0
            };
            let [u, v] = self.basis[f];
            let dir = (u * ex + v * ey).try_normalize(1e-30).unwrap_or(u);
            // A non-finite corner (the solver rolls such a state back, but the relief must not
            // spread it) gives no compression here.
            let finite = comp.is_finite() && dir.iter().all(|c| c.is_finite());
            self.tri_comp[f] = if finite { comp } else { 0.0 };
            self.tri_dir[f] = if finite { dir } else { u };
        }
    }

    /// Each coarse vertex's wrinkle direction and amplitude from its triangles' compression.
    fn vertex_fields(&mut self) {
        for v in 0..self.rest.len() {
            let faces = self.vertex_faces.row(v);
            let (mut t, mut total, mut best, mut start) = ([0.0; 6], 0.0, 0.0, Vec3::zeros());
            for &f in faces {
                let f = f as usize;
                let (w, d) = (self.area[f] * self.tri_comp[f], self.tri_dir[f]);
                total += self.area[f];
                if w <= 0.0 {
                    continue;
                }
                for (k, (i, j)) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]
                    .into_iter()
                    .enumerate()
                {
                    t[k] += w * d[i] * d[j];
                }
                if w > best {
                    (best, start) = (w, d);
                }
            }
            if best <= 0.0 || total <= 0.0 {
                self.amplitude[v] = 0.0;
                continue;
            }
            let mul = |e: Vec3| {
                Vec3::new(
                    t[0] * e.x + t[1] * e.y + t[2] * e.z,
                    t[1] * e.x + t[3] * e.y + t[4] * e.z,
                    t[2] * e.x + t[4] * e.y + t[5] * e.z,
                )
            };
            // Last frame's axis where it still carries compression, else the largest triangle's.
            let prev = self.dir[v];
            let mut e = if mul(prev).dot(&prev) > 0.25 * best {
                prev
            } else {
                start
            };
            for _ in 0..3 {
                e = mul(e).try_normalize(1e-300).unwrap_or(e);
            }
            let comp = mul(e).dot(&e) / total;
            self.dir[v] = e;
            self.amplitude[v] =
                self.gain[v] * 2.0 * self.wavelength[v] / std::f64::consts::PI * comp.sqrt();
        }
    }

    /// This frame's relief height at every fine vertex, from the coarse positions `x`: the
    /// fabric takes up compression to `band.0` itself, and the relief gives back at most `band.1`
    /// beyond that.
    pub fn heights(
        &mut self,
        x: &[Vec3],
        fine: &FineSurface,
        band: (Real, Real),
        out: &mut [Real],
    ) {
        self.triangle_strain(x, band);
        self.vertex_fields();
        for ((h, src), p) in out.iter_mut().zip(&fine.sources).zip(&self.fine_rest) {
            let Some(t) = self.tris.get(src.face as usize) else {
                *h = 0.0;
                continue;
            };
            let mut sum = 0.0;
            for k in 0..3 {
                let c = t[k] as usize;
                let a = self.amplitude[c];
                if a > 0.0 && src.bary[k] > 0.0 {
                    let phase = (p - self.rest[c]).dot(&self.dir[c]) / self.wavelength[c];
                    sum += src.bary[k] * a * stripe(phase);
                }
            }
            *h = sum;
        }
    }

    /// P1's eq. 8 as feedback: each coarse vertex's compressed edges (fine path through the
    /// reference shorter than `target = rest (1 - min)`) asked for `want = target - reference path` and got
    /// `got = output path - reference path`; the gain on the vertex's amplitude moves by
    /// `sqrt(sum want / sum got)` (a stripe's extra length grows with the square of its amplitude),
    /// at most [`GAIN_STEP`] per frame and within [`GAIN`]. `paths[e] = (rest, reference, output)`
    /// for the coarse edges `edges`; the first `min` of an edge's rest length the fabric takes up
    /// itself.
    pub fn adapt(&mut self, edges: &[[u32; 2]], paths: &[(Real, Real, Real)], min: Real) {
        let nc = self.gain.len();
        let mut want = vec![0.0; nc];
        let mut got = vec![0.0; nc];
        for (&[a, b], &(rest, reference, output)) in edges.iter().zip(paths) {
            let target = rest * (1.0 - min);
            if reference < target {
                for v in [a as usize, b as usize] {
                    if v < nc {
                        want[v] += target - reference;
                        got[v] += output - reference;
                    }
                }
            }
        }
        for v in 0..nc {
            if want[v] <= 0.0 || self.amplitude[v] <= 0.0 {
                continue;
            }
            let step = if got[v] > 0.0 {
                (want[v] / got[v]).sqrt()
            } else {
                GAIN_STEP.1
            };
            let step = step.clamp(GAIN_STEP.0, GAIN_STEP.1);
            self.gain[v] = (self.gain[v] * step).clamp(GAIN.0, GAIN.1);
        }
        // A fine path takes its relief from both its ends, so raising one end's gain and
        // lowering the other's gives it the same length: moving each gain a little toward
        // its triangles' corners' mean keeps that see-saw from growing frame after frame.
        let mut smooth = self.gain.clone();
        for (v, g) in smooth.iter_mut().enumerate() {
            let (mut sum, mut count) = (0.0, 0.0);
            for &f in self.vertex_faces.row(v) {
                for &c in &self.tris[f as usize] {
                    sum += self.gain[c as usize];
                    count += 1.0;
                }
            }
            if count > 0.0 {
                *g += SMOOTH * (sum / count - *g);
            }
        }
        self.gain = smooth;
    }
}

#[cfg(test)]
mod tests {
    use crate::tests::{frame, linear_fine};
    use crate::{Detail, DetailParams};
    use tryon_core::math::{Real, Vec3};
    use tryon_core::mesh::grid_xz;

    /// A 6 x 6 sheet scaled by `sx` along x and `sz` along z, wrinkled for `frames` frames at
    /// refine level 2: the model, the fine positions and the reference (flat) positions.
    fn scaled(sx: Real, sz: Real, frames: usize) -> (Detail, Vec<Vec3>, Vec<Vec3>) {
        let mesh = grid_xz(6, 6, 1.0, 1.0, 0.0);
        let x: Vec<Vec3> = (mesh.positions.iter())
            .map(|p| Vec3::new(p.x * sx, p.y, p.z * sz))
            .collect();
        let mut d = Detail::new(
            &linear_fine(&mesh, &x, 2),
            &mesh.positions,
            DetailParams::default(),
        )
        .unwrap();
        let mut fine = linear_fine(&mesh, &x, 2);
        let flat = fine.positions.clone();
        for _ in 0..frames {
            fine = linear_fine(&mesh, &x, 2);
            d.wrinkle(&frame(&x, vec![Vec3::zeros(); x.len()]), &mut fine);
        }
        (d, fine.positions, flat)
    }

    /// Each coarse edge's fine path length over its rest length, split by the edge's direction
    /// (along x, along z; diagonals left out).
    fn path_ratios(d: &Detail, x: &[Vec3], flat: &[Vec3]) -> (Vec<Real>, Vec<Real>) {
        let (mut along_x, mut along_z) = (Vec::new(), Vec::new());
        for e in 0..d.edges.len() {
            let row = d.edge_vertices(e);
            let path: Real = row
                .windows(2)
                .map(|w| (x[w[1] as usize] - x[w[0] as usize]).norm())
                .sum();
            let span = flat[row[row.len() - 1] as usize] - flat[row[0] as usize];
            let ratio = path / d.edge_rest[e];
            if span.z.abs() < 1e-9 {
                along_x.push(ratio);
            } else if span.x.abs() < 1e-9 {
                along_z.push(ratio);
            }
        }
        (along_x, along_z)
    }

    /// The largest spread of heights among fine vertices sharing a coordinate (`key` of their
    /// flat position), over those away from the sheet's border across it (`across` within 0.3).
    fn largest_spread(
        d: &Detail,
        flat: &[Vec3],
        key: impl Fn(&Vec3) -> Real,
        across: impl Fn(&Vec3) -> Real,
    ) -> Real {
        let mut by: std::collections::BTreeMap<i64, Vec<Real>> = Default::default();
        for (p, h) in flat.iter().zip(&d.height) {
            if across(p).abs() < 0.3 {
                by.entry((key(p) * 1e6).round() as i64)
                    .or_default()
                    .push(*h);
            }
        }
        by.values()
            .map(|hs| {
                let hi = hs.iter().cloned().fold(0.0, Real::max);
                let lo = hs.iter().cloned().fold(Real::MAX, Real::min);
                hi - lo
            })
            .fold(0.0, Real::max)
    }

    /// Squeezed 10% along x and not along z: the stripes run along z (heights change along x
    /// only), the fine paths along x come back within 2% of rest and those along z stay there.
    #[test]
    fn a_sheet_squeezed_along_x_gets_ridges_across_x() {
        let (d, x, flat) = scaled(0.9, 1.0, 20);
        let hmax = d.height.iter().cloned().fold(0.0, Real::max);
        assert!(hmax > 0.005, "highest ridge {hmax} m");
        // Heights of fine vertices at the same x (away from the sheet's border) agree.
        let spread = largest_spread(&d, &flat, |p| p.x, |p| p.z);
        assert!(spread < 0.1 * hmax, "heights at one x differ by {spread} m");
        let (along_x, along_z) = path_ratios(&d, &x, &flat);
        assert!(!along_x.is_empty() && !along_z.is_empty());
        for r in &along_x {
            assert!((r - 1.0).abs() <= 0.02, "path along x / rest = {r}");
        }
        for r in &along_z {
            assert!((r - 1.0).abs() <= 0.02, "path along z / rest = {r}");
        }
    }

    /// Squeezed along z instead: the stripes turn, heights change along z only.
    #[test]
    fn the_stripes_turn_with_the_squeeze() {
        let (d, _, flat) = scaled(1.0, 0.9, 20);
        let hmax = d.height.iter().cloned().fold(0.0, Real::max);
        assert!(hmax > 0.005, "highest ridge {hmax} m");
        let spread = largest_spread(&d, &flat, |p| p.z, |p| p.x);
        assert!(spread < 0.1 * hmax, "heights at one z differ by {spread} m");
        // And not along x: the heights at one x do differ (the stripes did turn).
        assert!(largest_spread(&d, &flat, |p| p.x, |p| p.z) > 0.5 * hmax);
    }

    /// The fast profile against libm's cosine, over many periods and both signs.
    #[test]
    fn the_stripe_profile_is_the_half_versine() {
        for i in -4000..=4000 {
            let phase = i as Real * 0.00173;
            let exact = 0.5 * (1.0 - (2.0 * std::f64::consts::PI * phase).cos());
            let got = super::stripe(phase);
            assert!((got - exact).abs() < 1e-5, "{phase}: {got} vs {exact}");
        }
    }

    /// A coarse corner at NaN: the heights stay finite (no relief around it) and the rest of
    /// the sheet still wrinkles.
    #[test]
    fn a_non_finite_corner_spreads_nothing() {
        let mesh = grid_xz(6, 6, 1.0, 1.0, 0.0);
        let mut x: Vec<Vec3> = (mesh.positions.iter())
            .map(|p| Vec3::new(p.x * 0.9, p.y, p.z))
            .collect();
        x[24] = Vec3::new(Real::NAN, 0.0, 0.0);
        let fine = linear_fine(&mesh, &mesh.positions, 2);
        let mut d = Detail::new(&fine, &mesh.positions, DetailParams::default()).unwrap();
        let mut out = vec![0.0; fine.positions.len()];
        for _ in 0..3 {
            d.relief.heights(&x, &fine, (0.0, 0.5), &mut out);
            assert!(out.iter().all(|h| h.is_finite() && *h >= 0.0));
        }
        assert!(out.iter().any(|h| *h > 1e-4));
    }

    /// Stretched both ways, or not deformed at all: no relief anywhere.
    #[test]
    fn a_stretched_or_resting_sheet_stays_flat() {
        for (sx, sz) in [(1.1, 1.05), (1.0, 1.0)] {
            let (d, x, flat) = scaled(sx, sz, 5);
            assert!(d.height.iter().all(|h| *h == 0.0), "{sx} x {sz}");
            assert_eq!(x, flat);
        }
    }

    /// The gain that feeds back the fine paths stays within its bounds, however long the squeeze
    /// lasts, and settles: the last frames change it by under 1%.
    #[test]
    fn the_gain_stays_bounded_and_settles() {
        let (d, _, _) = scaled(0.85, 0.95, 60);
        let g = d.relief.gain.clone();
        assert!(
            g.iter()
                .all(|g| (super::GAIN.0..=super::GAIN.1).contains(g))
        );
        let (d2, _, _) = scaled(0.85, 0.95, 61);
        for (a, b) in g.iter().zip(&d2.relief.gain) {
            assert!((a - b).abs() <= 0.01 * a, "{a} -> {b}");
        }
    }
}
