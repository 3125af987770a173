//! Layers that cross or touch in the starting shape, pulled apart before the first step.
//!
//! Some garments are modelled tangled: MakeHuman's elegant suit has 95 pairs of triangles passing
//! through each other where its jacket meets the skirt's waistband and at the collar. The
//! bounds of `mod.rs` keep apart what is apart, so a tangle at the start would stay (and spread
//! as the layers slide). On a body the layer order is known: of two crossing or touching
//! primitives, the one farther from the body is the outer. Each pass moves the outer side of every
//! crossing triangle pair and of every pair nearer than the gap outward along the body's normal,
//! until none is left or the passes run out.

use super::{SelfContacts, ring_of};
use parry3d_f64::math::{Isometry, Point};
use parry3d_f64::query::intersection_test;
use parry3d_f64::shape::Triangle;
use rayon::prelude::*;
use tryon_core::math::{Real, Vec3};
use tryon_core::stages::{Probe, Untangled};

fn triangle(x: &[Vec3], t: &[u32; 3]) -> Triangle {
    let p = |i: u32| Point::from(x[i as usize]);
    Triangle::new(p(t[0]), p(t[1]), p(t[2]))
}

/// A pair counts as touching under this share of the gap.
const NEAR: Real = 0.9;

/// Share of the missing gap the outer side of a touching pair moves in a pass.
const OPEN: Real = 0.6;

/// A touching pair is one layer over another when its offset makes at least this cosine with
/// the body's normal there.
const LAYERED: Real = 0.5;

/// Farthest untangling moves a vertex, in gaps.
const MAX_MOVE: Real = 2.0;

/// Rings around a vertex whose untangled vertices tell its layer's depth.
const LAYER_RINGS: usize = 3;

impl SelfContacts {
    /// How deep vertex `v`'s layer lies: the mean body distance of the vertices within
    /// [`LAYER_RINGS`] rings of it that no crossing touches (its own where all are). Where two
    /// layers pass through each other, their own distances say nothing of which is the outer.
    fn layer_depth(&self, v: u32, tangled: &[bool], raw: impl Fn(u32) -> Real) -> Real {
        let mut seen = vec![v];
        let mut frontier = vec![v];
        for _ in 0..LAYER_RINGS {
            let mut next = Vec::new();
            for &u in &frontier {
                for &w in ring_of(&self.ring_start, &self.ring, u) {
                    if !seen.contains(&w) {
                        seen.push(w);
                        next.push(w);
                    }
                }
            }
            frontier = next;
        }
        let clear: Vec<Real> = seen
            .iter()
            .filter(|&&u| !tangled[u as usize])
            .map(|&u| raw(u))
            .collect();
        if clear.is_empty() {
            raw(v)
        } else {
            clear.iter().sum::<Real>() / clear.len() as Real
        }
    }

    /// Pairs of triangles sharing no vertex that intersect at `x`, each once, in order.
    pub fn crossing_triangles(&mut self, x: &[Vec3]) -> Vec<[u32; 2]> {
        if !self.index(x, &vec![0.0; x.len()]) {
            return Vec::new();
        }
        let this = &*self;
        let cand: Vec<[u32; 2]> = (0..self.tris.len())
            .into_par_iter()
            .with_min_len(super::CHUNK)
            .map_init(super::Scratch::default, |sc, s| {
                let (lo, hi) = &this.boxes[s];
                this.broad.triangles(lo, hi, sc);
                sc.found
                    .iter()
                    .filter(|&&t| t as usize > s)
                    .map(|&t| [s as u32, t])
                    .collect::<Vec<_>>()
            })
            .flatten_iter()
            .collect();
        let id = Isometry::identity();
        let tris = &self.tris;
        let this = &*self;
        let mut out: Vec<[u32; 2]> = cand
            .into_par_iter()
            .filter(|[s, t]| {
                let (a, b) = (&tris[*s as usize], &tris[*t as usize]);
                s != t
                    && !a.iter().any(|v| b.contains(v))
                    && this.wanted(a[0], b[0])
                    && intersection_test(&id, &triangle(x, a), &id, &triangle(x, b))
                        .unwrap_or(false)
            })
            .collect();
        out.sort_unstable();
        out
    }

    /// Moves the outer side of crossing and touching pairs outward (`probes`: each vertex's body
    /// distance and outward normal at `x`) until no triangle pair crosses and (with
    /// `params.untangle_near`) no pair is nearer than nine tenths of `gap`, in at most `passes`
    /// passes. Vertices `fixed` says are led from outside stay.
    pub fn untangle(
        &mut self,
        x: &mut [Vec3],
        probes: &[Probe],
        (gap, passes): (Real, u32),
        fixed: impl Fn(usize) -> bool,
    ) -> Untangled {
        let start = x.to_vec();
        let mut report = Untangled::default();
        let raw = |v: u32| {
            probes
                .get(v as usize)
                .map_or(0.0, |p| p.distance.clamp(-1.0, 1.0))
        };
        for pass in 0..=passes {
            let crossing = self.crossing_triangles(x);
            let near = match self.params.untangle_near {
                true => self.find(x, &vec![NEAR * gap; x.len()]),
                false => Vec::new(),
            };
            if pass == 0 {
                report.crossings_before = crossing.len();
            }
            report.crossings_after = crossing.len();
            report.near_after = near.len();
            if pass == passes || (crossing.is_empty() && near.is_empty()) {
                break;
            }
            let mut tangled = vec![false; x.len()];
            for [s, t] in &crossing {
                for v in self.tris[*s as usize].iter().chain(&self.tris[*t as usize]) {
                    tangled[*v as usize] = true;
                }
            }
            // A garment's layer ranks first; within one, the depth of the vertex's layer of cloth.
            let depth =
                |v: u32| 4.0 * self.layer_of(v) as Real + self.layer_depth(v, &tangled, raw);
            let mut push = vec![0.0; x.len()];
            for [s, t] in &crossing {
                let (a, b) = (self.tris[*s as usize], self.tris[*t as usize]);
                let mean = |t: [u32; 3]| t.iter().map(|&v| depth(v)).sum::<Real>() / 3.0;
                let outer = if mean(a) >= mean(b) { a } else { b };
                for v in outer {
                    push[v as usize] = Real::max(push[v as usize], 0.5 * gap);
                }
            }
            for (_, (st, dist)) in &near {
                // Side by side (an open seam) rather than one over the other: not a layer.
                let n: Vec3 =
                    st.v.iter()
                        .map(|&v| probes.get(v as usize).map_or(Vec3::zeros(), |q| q.normal))
                        .sum();
                if n.dot(&st.normal).abs() < LAYERED * n.norm() {
                    continue;
                }
                let side = |positive: bool| {
                    (0..4)
                        .filter(|&m| (st.w[m] > 0.0) == positive && st.w[m] != 0.0)
                        .map(|m| st.w[m].abs() * depth(st.v[m]))
                        .sum::<Real>()
                };
                let outer_positive = side(true) >= side(false);
                for m in 0..4 {
                    if st.w[m] != 0.0 && (st.w[m] > 0.0) == outer_positive {
                        let v = st.v[m] as usize;
                        push[v] = Real::max(push[v], OPEN * (gap - dist));
                    }
                }
            }
            let mut changed = false;
            for (v, p) in push.iter().enumerate() {
                let n = probes.get(v).map_or(Vec3::zeros(), |q| q.normal);
                if *p > 0.0 && !fixed(v) && n != Vec3::zeros() {
                    // Never farther than the cap from where it was modelled: a tangle the cap
                    // leaves (a button sewn through the cloth) stays, left out as never apart.
                    let moved = x[v] + n * *p - start[v];
                    let to = start[v] + moved * (MAX_MOVE * gap / moved.norm()).min(1.0);
                    changed |= to != x[v];
                    x[v] = to;
                }
            }
            if !changed {
                // What is left cannot move (capped, led from outside, or side by side).
                break;
            }
        }
        for (a, b) in x.iter().zip(&start) {
            let d = (a - b).norm();
            if d > 0.0 {
                report.moved += 1;
                report.farthest = report.farthest.max(d);
            }
        }
        report
    }
}
