//! Swept body collision (issue 20, item 2): the body moves between two collider updates, and a
//! point outside it at the start of a cloth step must not end inside, however fast the limb. The
//! body's shape before its last move is kept; during a step that covers the fraction [s0, s1] of
//! that move each body vertex moves linearly between its shapes at s0 and s1, each point from its
//! start to its end, and every point's path is tested against every triangle whose swept box it
//! meets ([`crate::ccd`]). A point that crosses the surface inward is stopped: it goes where the
//! surface point it hit is at the step's end, `skin` out along the normal there. The side it came
//! from is kept: a point caught where two body parts meet (an armpit) is not pushed through one
//! of them.
//!
//! The broad phase is a spatial hash of the triangles by the box each sweeps over the whole move,
//! built once per move over the region the points occupy.

use crate::body::BodyMesh;
use crate::ccd::{Crossing, inward_crossing};
use crate::grid::{bucket, cell_of};
use rayon::prelude::*;
use tryon_core::frames::Contact;
use tryon_core::math::{Real, Vec3, is_finite};

/// Side of the hash's cells (m).
const CELL: Real = 0.04;
/// Boxes spanning more cells than this along an axis are tested against every point instead.
const MAX_SPAN: i64 = 8;
/// The hashed region is the points' box grown by this (m), so later steps of the same move fit.
const GROW: Real = 0.1;

/// Fewest points a thread takes at once.
const PAR_CHUNK: usize = 64;

/// An axis-aligned box.
type Aabb = (Vec3, Vec3);

fn overlaps(a: &Aabb, b: &Aabb) -> bool {
    (0..3).all(|k| a.0[k] <= b.1[k] && b.0[k] <= a.1[k])
}

fn contains(outer: &Aabb, inner: &Aabb) -> bool {
    (0..3).all(|k| outer.0[k] <= inner.0[k] && inner.1[k] <= outer.1[k])
}

/// The body's last move and the hash of its triangles.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SweptBody {
    /// The body's shape before its last move (empty until the first: a body that never moved).
    pub before: Vec<Vec3>,
    /// Whether the last move left the body where it was.
    still: bool,
    /// Bucket b holds `items[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    items: Vec<u32>,
    /// Triangles whose box spans too many cells: tried for every point.
    big: Vec<u32>,
    /// Per body triangle, the box it sweeps over the whole move (set for the hashed ones): a
    /// candidate whose box misses a point's path is passed over before its corners are found.
    boxes: Vec<Aabb>,
    /// The region hashed, `None` when the hash is stale.
    region: Option<Aabb>,
}

impl SweptBody {
    /// The body is about to move away from `before` (its shape until now); `still` says the new
    /// shape is the same.
    pub fn moved(&mut self, before: &[Vec3], still: bool) {
        if still && self.still && self.before.as_slice() == before {
            return;
        }
        self.before.clear();
        self.before.extend_from_slice(before);
        self.still = still;
        self.region = None;
    }

    /// Body vertex `v` at fraction `s` of the last move.
    #[inline]
    fn vertex_at(&self, body: &BodyMesh, v: u32, s: Real) -> Vec3 {
        let now = body.positions[v as usize];
        match self.before.get(v as usize) {
            Some(b) => b + (now - b) * s,
            None => now,
        }
    }

    /// The box triangle `f` sweeps over the whole move.
    fn swept_box(&self, body: &BodyMesh, f: usize) -> Aabb {
        let mut b = (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        );
        for &v in &body.triangles[f] {
            for s in [0.0, 1.0] {
                let p = self.vertex_at(body, v, s);
                b = (b.0.inf(&p), b.1.sup(&p));
            }
        }
        b
    }

    /// Hashes every triangle whose swept box meets `region`.
    fn build(&mut self, body: &BodyMesh, region: Aabb) {
        let inv = 1.0 / CELL;
        let buckets = (2 * body.triangles.len()).max(1).next_power_of_two();
        self.starts.clear();
        self.starts.resize(buckets + 1, 0);
        self.big.clear();
        let mut kept: Vec<(u32, [i64; 3], [i64; 3])> = Vec::new();
        self.boxes.clear();
        self.boxes.reserve(body.triangles.len());
        for f in 0..body.triangles.len() {
            let b = self.swept_box(body, f);
            self.boxes.push(b);
            if !is_finite(&b.0) || !is_finite(&b.1) || !overlaps(&b, &region) {
                continue;
            }
            let (lo, hi) = (cell_of(&b.0, inv), cell_of(&b.1, inv));
            if (0..3).any(|k| hi[k] - lo[k] > MAX_SPAN) {
                self.big.push(f as u32);
                continue;
            }
            for_cells(lo, hi, |c| self.starts[bucket(c, buckets - 1) + 1] += 1);
            kept.push((f as u32, lo, hi));
        }
        for b in 0..buckets {
            self.starts[b + 1] += self.starts[b];
        }
        self.items.clear();
        self.items.resize(self.starts[buckets] as usize, 0);
        let mut fill: Vec<u32> = self.starts[..buckets].to_vec();
        for (f, lo, hi) in kept {
            for_cells(lo, hi, |c| {
                let b = bucket(c, buckets - 1);
                self.items[fill[b] as usize] = f;
                fill[b] += 1;
            });
        }
        self.region = Some(region);
    }

    /// Collects into `found` the triangles hashed in the cells `path` meets, each once.
    fn candidates(&self, path: &Aabb, found: &mut Vec<u32>) {
        found.clear();
        let buckets = self.starts.len().saturating_sub(1);
        if buckets == 0 {
            return;
        }
        let inv = 1.0 / CELL;
        let (lo, hi) = (cell_of(&path.0, inv), cell_of(&path.1, inv));
        if (0..3).any(|k| hi[k] - lo[k] > MAX_SPAN) {
            found.extend_from_slice(&self.items);
        } else {
            for_cells(lo, hi, |c| {
                let b = bucket(c, buckets - 1);
                found.extend_from_slice(
                    &self.items[self.starts[b] as usize..self.starts[b + 1] as usize],
                );
            });
        }
        found.extend_from_slice(&self.big);
        if lo != hi || !self.big.is_empty() {
            // One cell holds each triangle once; several may share some.
            found.sort_unstable();
            found.dedup();
        }
    }

    /// Stops every point of `end` whose path from `start` crosses the body inward while the body
    /// covers the fraction `span` of its last move (see the module's text); appends one contact
    /// per stopped point. Non-finite points and slices of different lengths are left alone.
    pub fn sweep(
        &mut self,
        body: &BodyMesh,
        start: &[Vec3],
        end: &mut [Vec3],
        span: [Real; 2],
        skin: Real,
        contacts: &mut Vec<Contact>,
    ) {
        if start.len() != end.len() || !span.iter().all(|s| s.is_finite()) {
            return;
        }
        let mut bounds = (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        );
        for p in start.iter().chain(end.iter()).filter(|p| is_finite(p)) {
            bounds = (bounds.0.inf(p), bounds.1.sup(p));
        }
        if !is_finite(&bounds.0) {
            return;
        }
        if !self.region.is_some_and(|r| contains(&r, &bounds)) {
            let grown = (bounds.0.add_scalar(-GROW), bounds.1.add_scalar(GROW));
            self.build(body, grown);
        }
        // Each point's crossing is found on its own (in parallel), then applied in order.
        let this = &*self;
        let ends: &[Vec3] = end;
        let hits: Vec<Option<(u32, Crossing)>> = (0..ends.len())
            .into_par_iter()
            .with_min_len(PAR_CHUNK)
            .map_init(Vec::new, |found, i| {
                let path = (start[i], ends[i]);
                if !is_finite(&path.0) || !is_finite(&path.1) {
                    return None;
                }
                this.first_crossing(body, &path, span, found)
            })
            .collect();
        for (i, hit) in hits.into_iter().enumerate() {
            let Some((f, hit)) = hit else { continue };
            let (q, n) = self.surface_at(body, f, hit.bary, span[1]);
            let height = (end[i] - q).dot(&n);
            if height >= skin {
                continue;
            }
            end[i] += n * (skin - height);
            contacts.push(Contact {
                point: i as u32,
                face: f,
                bary: hit.bary,
                normal: n,
                depth: (-height).max(0.0),
                body_velocity: body.velocity_at(f as usize, hit.bary),
            });
        }
    }

    /// The earliest inward crossing of `path` through any candidate triangle, with its triangle
    /// (the lowest index on a tie, so the result does not depend on the hash's order).
    fn first_crossing(
        &self,
        body: &BodyMesh,
        path: &(Vec3, Vec3),
        span: [Real; 2],
        found: &mut Vec<u32>,
    ) -> Option<(u32, Crossing)> {
        let pbox = (path.0.inf(&path.1), path.0.sup(&path.1));
        self.candidates(&pbox, found);
        let mut best: Option<(u32, Crossing)> = None;
        for &f in found.iter() {
            if !overlaps(&self.boxes[f as usize], &pbox) {
                continue;
            }
            let corners = body.triangles[f as usize].map(|v| {
                (
                    self.vertex_at(body, v, span[0]),
                    self.vertex_at(body, v, span[1]),
                )
            });
            let mut tbox = (
                Vec3::repeat(Real::INFINITY),
                Vec3::repeat(Real::NEG_INFINITY),
            );
            for (a, b) in &corners {
                tbox = (tbox.0.inf(a).inf(b), tbox.1.sup(a).sup(b));
            }
            if !overlaps(&tbox, &pbox) {
                continue;
            }
            if let Some(hit) = inward_crossing(path, &corners)
                && best.is_none_or(|(g, b)| hit.t < b.t || (hit.t == b.t && f < g))
            {
                best = Some((f, hit));
            }
        }
        best
    }

    /// The point at `bary` on triangle `f` at fraction `s` of the move, and the triangle's unit
    /// outward normal there (its normal at the start of the move if it has collapsed).
    fn surface_at(&self, body: &BodyMesh, f: u32, bary: [Real; 3], s: Real) -> (Vec3, Vec3) {
        let c = body.triangles[f as usize].map(|v| self.vertex_at(body, v, s));
        let q = c[0] * bary[0] + c[1] * bary[1] + c[2] * bary[2];
        let n = (c[1] - c[0]).cross(&(c[2] - c[0]));
        let n = n.try_normalize(1e-20).unwrap_or_else(|| {
            let c0 = body.triangles[f as usize].map(|v| self.vertex_at(body, v, 0.0));
            (c0[1] - c0[0])
                .cross(&(c0[2] - c0[0]))
                .try_normalize(1e-20)
                .unwrap_or_else(Vec3::zeros)
        });
        (q, n)
    }
}

/// Calls `f` on every cell from `lo` to `hi` (inclusive).
fn for_cells(lo: [i64; 3], hi: [i64; 3], mut f: impl FnMut([i64; 3])) {
    for x in lo[0]..=hi[0] {
        for y in lo[1]..=hi[1] {
            for z in lo[2]..=hi[2] {
                f([x, y, z]);
            }
        }
    }
}
