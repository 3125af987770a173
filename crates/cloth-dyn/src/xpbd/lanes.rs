//! The XPBD constraints eight at a time: the constraints of one colour share no particle, so eight
//! of them are gathered into the lanes of `f32x8` vectors (`wide`), solved together and scattered
//! back. Positions stay in f64; each constraint's particles are taken relative to its first one
//! before they are narrowed to f32, so the narrowing costs relative, not absolute, precision (about
//! 1e-7 of an edge). Gauss-Seidel across colours is unchanged: a colour's constraints could be
//! solved in any order with the same result, and the lanes are such an order.
//!
//! The dihedral constraint here is [`super::constraints::dihedral`] with `hinge_move`'s response, in
//! lanes; a unit test holds the two to each other. A padded lane has all its particles at index 0:
//! its edge is degenerate, and a degenerate constraint moves nothing.

use super::constraints::{Edge, Hinge};
use std::ops::Range;
use tryon_core::math::{Real, Vec3};
use wide::{CmpGt, f32x8};

/// Constraints per batch.
pub const LANES: usize = 8;

/// Three coordinates, eight lanes each.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
struct V3 {
    x: f32x8,
    y: f32x8,
    z: f32x8,
}

impl V3 {
    fn sub(self, o: V3) -> V3 {
        V3 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
    fn add(self, o: V3) -> V3 {
        V3 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
    fn scale(self, s: f32x8) -> V3 {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
    fn dot(self, o: V3) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    fn cross(self, o: V3) -> V3 {
        V3 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }
}

/// Up to eight hinges of one colour, lane by lane.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct HingeBatch {
    /// `v[k][lane]`: the lane's particle k (a, b, c, d as in [`Hinge`]).
    pub v: [[u32; LANES]; 4],
    pub rest_angle: f32x8,
    pub compliance_scale: f32x8,
}

/// Up to eight distance constraints of one colour.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct EdgeBatch {
    pub i: [u32; LANES],
    pub j: [u32; LANES],
    pub rest: f32x8,
}

/// Batches of `items`, colour by colour (each colour's range in `ranges`), the last batch of a
/// colour padded by `pad`.
fn batches<T: Copy, B>(
    items: &[T],
    ranges: &[Range<usize>],
    pad: T,
    pack: impl Fn(&[T; LANES]) -> B,
) -> (Vec<B>, Vec<Range<usize>>) {
    let mut out = Vec::new();
    let mut out_ranges = Vec::with_capacity(ranges.len());
    for r in ranges {
        let start = out.len();
        for chunk in items[r.clone()].chunks(LANES) {
            let mut lane = [pad; LANES];
            lane[..chunk.len()].copy_from_slice(chunk);
            out.push(pack(&lane));
        }
        out_ranges.push(start..out.len());
    }
    (out, out_ranges)
}

/// The hinges of each colour (ranges into `hinges`) in batches, and each colour's range of them.
pub fn hinge_batches(
    hinges: &[Hinge],
    ranges: &[Range<usize>],
) -> (Vec<HingeBatch>, Vec<Range<usize>>) {
    let pad = Hinge {
        v: [0; 4],
        rest_angle: 0.0,
        compliance_scale: 1.0,
    };
    batches(hinges, ranges, pad, |h| HingeBatch {
        v: [0, 1, 2, 3].map(|k| h.map(|hg| hg.v[k])),
        rest_angle: f32x8::from(h.map(|hg| hg.rest_angle as f32)),
        compliance_scale: f32x8::from(h.map(|hg| hg.compliance_scale as f32)),
    })
}

/// The edges of each colour in batches, and each colour's range of them.
pub fn edge_batches(
    edges: &[Edge],
    ranges: &[Range<usize>],
) -> (Vec<EdgeBatch>, Vec<Range<usize>>) {
    let pad = Edge {
        i: 0,
        j: 0,
        rest: 1.0,
    };
    batches(edges, ranges, pad, |e| EdgeBatch {
        i: e.map(|e| e.i),
        j: e.map(|e| e.j),
        rest: f32x8::from(e.map(|e| e.rest as f32)),
    })
}

/// `x[to[l]] - x[from[l]]` of every lane, narrowed.
fn gather_rel(x: &[Vec3], to: &[u32; LANES], from: &[u32; LANES]) -> V3 {
    let mut c = [[0f32; LANES]; 3];
    for l in 0..LANES {
        let d = x[to[l] as usize] - x[from[l] as usize];
        c[0][l] = d.x as f32;
        c[1][l] = d.y as f32;
        c[2][l] = d.z as f32;
    }
    V3 {
        x: f32x8::from(c[0]),
        y: f32x8::from(c[1]),
        z: f32x8::from(c[2]),
    }
}

/// The inverse masses of the lanes' particles.
fn gather_w(w: &[Real], v: &[u32; LANES]) -> f32x8 {
    f32x8::from(v.map(|k| w[k as usize] as f32))
}

/// `x[v[l]] += m[l] * s[l]` for every lane.
fn scatter(x: &mut [Vec3], v: &[u32; LANES], m: V3, s: f32x8) {
    let (mx, my, mz) = (
        (m.x * s).to_array(),
        (m.y * s).to_array(),
        (m.z * s).to_array(),
    );
    for l in 0..LANES {
        x[v[l] as usize] += Vec3::new(mx[l] as Real, my[l] as Real, mz[l] as Real);
    }
}

/// `v` where `mask` is set, else 0.
fn keep(mask: f32x8, v: f32x8) -> f32x8 {
    mask.blend(v, f32x8::ZERO)
}

/// Solves a batch of hinges in place (compliance `alpha`, already over the step squared).
pub fn solve_hinge_batch(x: &mut [Vec3], w: &[Real], hb: &HingeBatch, alpha: f32) {
    let [va, vb, vc, vd] = &hb.v;
    let (e, c, d) = (
        gather_rel(x, vb, va),
        gather_rel(x, vc, va),
        gather_rel(x, vd, va),
    );
    let el2 = e.dot(e);
    let n1 = c.cross(c.sub(e));
    let n2 = d.sub(e).cross(d);
    let (l1, l2) = (n1.dot(n1), n2.dot(n2));
    let tiny = f32x8::splat(1e-30);
    let ok = el2.cmp_gt(tiny) & l1.cmp_gt(tiny) & l2.cmp_gt(tiny);
    // Degenerate lanes compute with harmless values and are masked out at the end.
    let one = f32x8::ONE;
    let (el2, l1, l2) = (ok.blend(el2, one), ok.blend(l1, one), ok.blend(l2, one));
    let el = el2.sqrt();
    let ie = one / el;
    let angle = (n1.cross(n2).dot(e) * ie).atan2(n1.dot(n2));
    let (k1, k2) = (one / l1, one / l2);
    let gc = n1.scale(el * k1);
    let gd = n2.scale(el * k2);
    let (s1, s2) = (ie * k1, ie * k2);
    let cb = c.sub(e);
    let db = d.sub(e);
    let ga = n1.scale(cb.dot(e) * s1).add(n2.scale(db.dot(e) * s2));
    let gb = n1.scale(c.dot(e) * s1).add(n2.scale(d.dot(e) * s2));
    // The gradients are -ga, +gb, -gc, -gd; signs are folded into the scatter's factors.
    let ws = [va, vb, vc, vd].map(|v| gather_w(w, v));
    let denom = ws[0] * ga.dot(ga) + ws[1] * gb.dot(gb) + ws[2] * gc.dot(gc) + ws[3] * gd.dot(gd);
    let pi = f32x8::PI;
    let mut cv = angle - hb.rest_angle;
    cv = cv.cmp_gt(pi).blend(cv - (pi + pi), cv);
    cv = (-pi).cmp_gt(cv).blend(cv + (pi + pi), cv);
    let total = denom + hb.compliance_scale * alpha;
    let ok = ok & total.cmp_gt(f32x8::splat(1e-20));
    let dl = keep(ok, -cv / ok.blend(total, one));
    scatter(x, va, ga, -(ws[0] * dl));
    scatter(x, vb, gb, ws[1] * dl);
    scatter(x, vc, gc, -(ws[2] * dl));
    scatter(x, vd, gd, -(ws[3] * dl));
}

/// Solves a batch of distance constraints in place (compliance per unit length `alpha`, over the
/// step squared); with `elastic`, adds their forces (`dl / h^2` along the edge) to it.
pub fn solve_edge_batch(
    x: &mut [Vec3],
    w: &[Real],
    eb: &EdgeBatch,
    alpha: f32,
    elastic: Option<(&mut [Vec3], Real)>,
) {
    let d = gather_rel(x, &eb.i, &eb.j);
    let (wi, wj) = (gather_w(w, &eb.i), gather_w(w, &eb.j));
    let wsum = wi + wj;
    let len2 = d.dot(d);
    let ok = len2.cmp_gt(f32x8::splat(1e-24)) & wsum.cmp_gt(f32x8::ZERO);
    let one = f32x8::ONE;
    let len = ok.blend(len2, one).sqrt();
    let n = d.scale(one / len);
    let a = f32x8::splat(alpha) / eb.rest.max(f32x8::splat(1e-9));
    let dl = keep(ok, (eb.rest - len) / (ok.blend(wsum, one) + a));
    scatter(x, &eb.i, n, wi * dl);
    scatter(x, &eb.j, n, -(wj * dl));
    if let Some((f, h)) = elastic {
        let s = f32x8::splat((1.0 / (h * h)) as f32) * dl;
        scatter(f, &eb.i, n, s);
        scatter(f, &eb.j, n, -s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::xpbd::constraints::{Edge, Hinge, dihedral};
    use crate::xpbd::hinge_move;

    /// A deterministic pseudo-random number in [-1, 1).
    fn rnd(seed: &mut u64) -> Real {
        *seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        ((*seed >> 11) as Real / (1u64 << 53) as Real) * 2.0 - 1.0
    }

    #[test]
    fn eight_hinges_in_lanes_move_as_each_alone_in_f64() {
        let mut seed = 7;
        let mut x = Vec::new();
        let mut hinges = Vec::new();
        for h in 0..8u32 {
            // A hinge near (h, 0, 0), centimetre-sized, bent at random, rest angle at random.
            let o = Vec3::new(h as Real, 0.3, -1.2);
            let p: Vec<Vec3> = (0..4)
                .map(|_| o + Vec3::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.01)
                .collect();
            x.extend(p);
            hinges.push(Hinge {
                v: [0, 1, 2, 3].map(|k| 4 * h + k),
                rest_angle: rnd(&mut seed) * 3.0,
                compliance_scale: 1.0 + h as Real,
            });
        }
        // Lane 7 degenerate: c on the edge.
        x[30] = x[28];
        let w: Vec<Real> = (0..32).map(|k| [1.0, 0.5, 2.0, 0.0][k % 4]).collect();
        let alpha = 0.3;
        let mut lanes = x.clone();
        let (hb, _) = hinge_batches(&hinges, std::slice::from_ref(&(0..8)));
        solve_hinge_batch(&mut lanes, &w, &hb[0], alpha as f32);
        for (h, hg) in hinges.iter().enumerate() {
            let v = hg.v.map(|k| k as usize);
            let m = hinge_move(v.map(|k| x[k]), v.map(|k| w[k]), hg, alpha);
            for k in 0..4 {
                let (want, got) = (x[v[k]] + m[k], lanes[v[k]]);
                let scale = m[k].norm().max(1e-6);
                assert!(
                    (want - got).norm() < 1e-4 * scale + 1e-9,
                    "hinge {h} vertex {k}: {want:?} vs {got:?}"
                );
            }
            if h == 7 {
                assert!(dihedral(v.map(|k| x[k])).is_none());
                assert!((0..4).all(|k| lanes[v[k]] == x[v[k]]));
            }
        }
    }

    #[test]
    fn eight_edges_in_lanes_move_and_record_as_each_alone() {
        let mut seed = 3;
        let x: Vec<Vec3> = (0..16)
            .map(|k| Vec3::new(k as Real, rnd(&mut seed), rnd(&mut seed)) * 0.01)
            .collect();
        let edges: Vec<Edge> = (0..6)
            .map(|k| Edge {
                i: 2 * k,
                j: 2 * k + 1,
                rest: 0.01 * (1.0 + 0.2 * rnd(&mut seed)),
            })
            .collect();
        let w: Vec<Real> = (0..16).map(|k| [1.0, 0.25, 0.0][k % 3]).collect();
        let (eb, ranges) = edge_batches(&edges, std::slice::from_ref(&(0..6)));
        assert_eq!(ranges, vec![0..1]);
        let (alpha, h) = (0.02, 0.005);
        let mut lanes = x.clone();
        let mut f = vec![Vec3::zeros(); 16];
        solve_edge_batch(&mut lanes, &w, &eb[0], alpha as f32, Some((&mut f, h)));
        for e in &edges {
            let (i, j) = (e.i as usize, e.j as usize);
            let d = x[i] - x[j];
            let n = d / d.norm();
            let wsum = w[i] + w[j];
            let dl = if wsum == 0.0 {
                0.0
            } else {
                -(d.norm() - e.rest) / (wsum + alpha / e.rest)
            };
            for (k, s, want_f) in [(i, w[i], n * dl / (h * h)), (j, -w[j], -n * dl / (h * h))] {
                let want = x[k] + n * (s * dl);
                assert!(
                    (want - lanes[k]).norm() < 1e-9,
                    "{k}: {want:?} vs {:?}",
                    lanes[k]
                );
                assert!(
                    (want_f - f[k]).norm() < 1e-5 * want_f.norm() + 1e-9,
                    "force {k}"
                );
            }
        }
        // The two padded lanes moved nothing and recorded nothing.
        assert!(lanes[12..].iter().zip(&x[12..]).all(|(a, b)| a == b));
        assert!(f[12..].iter().all(|v| *v == Vec3::zeros()));
    }
}
