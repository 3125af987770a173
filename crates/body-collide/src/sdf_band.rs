//! The SDF collider's narrow band, eight grid nodes at a time: every body triangle visits the nodes
//! within the band of its bounds, and the squared distances from eight of them to the triangle are
//! found together in the lanes of `f32x8` vectors (`wide`). A moving body rebuilds the band every
//! frame, and these distances were most of its cost (about 1.9 million point-triangle distances a
//! frame for a 15,000-triangle body at any resolution: the body's triangles are smaller than a
//! cell, so each visits (2 band + 1)^3 nodes).
//!
//! The distances are in f32, each node taken relative to the triangle's first corner, so they are
//! good to about 1e-7 of the cell; they only choose each node's nearest triangle, whose exact
//! distance and sign the collider then computes in f64.

use tryon_core::math::{Real, Vec3};
use wide::{CmpGe, f32x8};

const LANES: usize = 8;

/// One triangle, relative to its first corner, set up for distances from eight points at once.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct TriLanes {
    /// Corners b and c relative to a.
    b: [f32; 3],
    c: [f32; 3],
    /// Edges a->b, b->c, c->a, and the reciprocals of their squared lengths.
    e: [[f32; 3]; 3],
    inv_e2: [f32; 3],
    /// The normal, the reciprocal of its squared length, and each edge's in-plane inward normal
    /// (n x e), for the inside test.
    n: [f32; 3],
    inv_n2: f32,
    inward: [[f32; 3]; 3],
    /// False for a triangle of no area: it is only its edges.
    has_area: bool,
}

fn f3(v: Vec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}

fn cross(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl TriLanes {
    /// The triangle (a, b, c).
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Self {
        let (b, c) = (f3(b - a), f3(c - a));
        let e = [
            b,
            [c[0] - b[0], c[1] - b[1], c[2] - b[2]],
            [-c[0], -c[1], -c[2]],
        ];
        let n = cross(e[0], [c[0], c[1], c[2]]);
        let n2 = dot(n, n);
        TriLanes {
            b,
            c,
            e,
            inv_e2: e.map(|e| 1.0 / dot(e, e).max(1e-30)),
            n,
            inv_n2: 1.0 / n2.max(1e-30),
            inward: e.map(|e| cross(n, e)),
            has_area: n2 > 1e-30,
        }
    }

    /// Squared distances from the points `p` (relative to the triangle's first corner) to it.
    pub fn dist2(&self, p: [f32x8; 3]) -> f32x8 {
        let s = |v: f32| f32x8::splat(v);
        let corners = [[0.0; 3], self.b, self.c];
        let zero = f32x8::ZERO;
        let mut inside = f32x8::splat(if self.has_area { 1.0 } else { 0.0 }).cmp_ge(s(0.5));
        let mut edge = s(f32::INFINITY);
        for k in 0..3 {
            let v = corners[k];
            let d = [p[0] - s(v[0]), p[1] - s(v[1]), p[2] - s(v[2])];
            let e = self.e[k];
            let along = d[0] * s(e[0]) + d[1] * s(e[1]) + d[2] * s(e[2]);
            let t = (along * s(self.inv_e2[k])).max(zero).min(f32x8::ONE);
            let r = [d[0] - t * s(e[0]), d[1] - t * s(e[1]), d[2] - t * s(e[2])];
            edge = edge.min(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
            let w = self.inward[k];
            inside &= (d[0] * s(w[0]) + d[1] * s(w[1]) + d[2] * s(w[2])).cmp_ge(zero);
        }
        let h = p[0] * s(self.n[0]) + p[1] * s(self.n[1]) + p[2] * s(self.n[2]);
        inside.blend(h * h * s(self.inv_n2), edge)
    }
}

/// The grid the band is written into: nodes at `origin + (i, j, k) cell`, x fastest.
#[derive(Debug)]
pub struct BandGrid<'a> {
    pub origin: Vec3,
    pub cell: Real,
    pub dims: [usize; 3],
    /// Squared distance to the nearest triangle so far (infinite where none).
    pub dist2: &'a mut [Real],
    /// That triangle.
    pub face: &'a mut [u32],
}

/// Lane offsets 0..8.
const IOTA: [f32; LANES] = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];

impl BandGrid<'_> {
    /// Visits the nodes within `reach` of triangle `f`'s bounds (a box `reach` larger on every
    /// side) and keeps `f` where it is the nearest so far. A row of nodes along x goes into the
    /// lanes at once: contiguous in the grid, so nothing is gathered or scattered.
    pub fn add_triangle(&mut self, f: u32, [a, b, c]: [Vec3; 3], reach: Real) {
        let lo = a.inf(&b).inf(&c) - Vec3::repeat(reach);
        let hi = a.sup(&b).sup(&c) + Vec3::repeat(reach);
        let inv = 1.0 / self.cell;
        // A node on the box's face is in: a tolerance of 1e-6 cell keeps that true whatever the
        // rounding of the grid's origin (a body vertex on a node line puts the face there
        // exactly, and a field focused on the cloth has an origin a few ulps from the whole one).
        let tol = 1e-6;
        let range = |axis: usize| {
            let i0 = ((lo[axis] - self.origin[axis]) * inv - tol).ceil().max(0.0) as usize;
            let i1 = (((hi[axis] - self.origin[axis]) * inv + tol)
                .floor()
                .max(-1.0)
                + 1.0) as usize;
            i0..i1.min(self.dims[axis])
        };
        let (ri, rj, rk) = (range(0), range(1), range(2));
        if ri.is_empty() || rj.is_empty() || rk.is_empty() {
            return;
        }
        let tri = TriLanes::new(a, b, c);
        // Node (i0, j0, k0) relative to a, in f64, then small steps in f32.
        let base = self.origin
            + Vec3::new(ri.start as Real, rj.start as Real, rk.start as Real) * self.cell
            - a;
        let (base, cell) = (f3(base), self.cell as f32);
        let (nx, nxy) = (self.dims[0], self.dims[0] * self.dims[1]);
        let iota = f32x8::from(IOTA) * f32x8::splat(cell);
        for k in rk.clone() {
            let z = f32x8::splat(base[2] + (k - rk.start) as f32 * cell);
            for j in rj.clone() {
                let y = f32x8::splat(base[1] + (j - rj.start) as f32 * cell);
                let row = nx * j + nxy * k;
                for s in ri.clone().step_by(LANES) {
                    let x = f32x8::splat(base[0] + (s - ri.start) as f32 * cell) + iota;
                    let d2 = tri.dist2([x, y, z]).to_array();
                    let count = (ri.end - s).min(LANES);
                    let first = row + s;
                    let (dist, face) = (
                        &mut self.dist2[first..first + count],
                        &mut self.face[first..first + count],
                    );
                    for l in 0..count {
                        let d = d2[l] as Real;
                        if d < dist[l] {
                            dist[l] = d;
                            face[l] = f;
                        }
                    }
                }
            }
        }
    }
}

/// Whether any lane of `a` is below `b` (for tests).
#[cfg(test)]
fn any_below(a: f32x8, b: f32) -> bool {
    use wide::CmpLt;
    a.cmp_lt(f32x8::splat(b)).any()
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::math::closest_point_on_triangle;

    fn rnd(seed: &mut u64) -> Real {
        *seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        ((*seed >> 11) as Real / (1u64 << 53) as Real) * 2.0 - 1.0
    }

    #[test]
    fn lane_distances_match_the_closest_point_in_every_region() {
        let mut seed = 11;
        let mut worst: Real = 0.0;
        for t in 0..300 {
            let o = Vec3::new(0.4, 1.1, -0.2);
            let mut v = || o + Vec3::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.02;
            let (a, b, mut c) = (v(), v(), v());
            if t % 50 == 0 {
                c = a + (b - a) * 0.3; // no area: only its edges
            }
            let tri = TriLanes::new(a, b, c);
            let pts: Vec<Vec3> = (0..LANES)
                .map(|_| o + Vec3::new(rnd(&mut seed), rnd(&mut seed), rnd(&mut seed)) * 0.05)
                .collect();
            let lanes =
                [0, 1, 2].map(|ax| f32x8::from(std::array::from_fn(|l| (pts[l] - a)[ax] as f32)));
            let got = tri.dist2(lanes).to_array();
            assert!(!any_below(tri.dist2(lanes), 0.0));
            for l in 0..LANES {
                let want = (closest_point_on_triangle(&pts[l], &a, &b, &c).0 - pts[l]).norm();
                let g = (got[l] as Real).sqrt();
                worst = worst.max((g - want).abs());
            }
        }
        assert!(worst < 1e-7, "worst distance error {worst} m");
    }

    #[test]
    fn the_band_keeps_the_nearest_triangle_of_every_node_it_reaches() {
        let dims = [6, 5, 7];
        let total = dims[0] * dims[1] * dims[2];
        let (mut dist2, mut face) = (vec![Real::INFINITY; total], vec![u32::MAX; total]);
        let mut grid = BandGrid {
            origin: Vec3::new(-0.1, -0.1, -0.1),
            cell: 0.04,
            dims,
            dist2: &mut dist2,
            face: &mut face,
        };
        let tris = [
            [
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.03, 0.0, 0.0),
                Vec3::new(0.0, 0.02, 0.01),
            ],
            [
                Vec3::new(0.05, 0.05, 0.1),
                Vec3::new(0.06, 0.04, 0.12),
                Vec3::new(0.05, 0.07, 0.1),
            ],
        ];
        for (f, t) in tris.iter().enumerate() {
            grid.add_triangle(f as u32, *t, 1.0);
        }
        let mut reached = 0;
        for n in 0..total {
            let (i, j, k) = (n % 6, (n / 6) % 5, n / 30);
            let p = Vec3::new(-0.1, -0.1, -0.1) + Vec3::new(i as Real, j as Real, k as Real) * 0.04;
            let d: Vec<Real> = tris
                .iter()
                .map(|[a, b, c]| (closest_point_on_triangle(&p, a, b, c).0 - p).norm_squared())
                .collect();
            if face[n] == u32::MAX {
                continue;
            }
            reached += 1;
            let f = face[n] as usize;
            assert!(d[f] <= d[1 - f] + 1e-9, "node {n}: kept {f}");
            assert!((dist2[n] - d[f]).abs() < 1e-8, "node {n}");
        }
        assert_eq!(reached, total);
        // With a short reach, exactly the nodes of the box `reach` around the triangle's bounds.
        let (mut dist2, mut face) = (vec![Real::INFINITY; total], vec![u32::MAX; total]);
        let mut grid = BandGrid {
            origin: Vec3::new(-0.1, -0.1, -0.1),
            cell: 0.04,
            dims,
            dist2: &mut dist2,
            face: &mut face,
        };
        let [a, b, c] = tris[0];
        let reach = 0.07;
        grid.add_triangle(0, tris[0], reach);
        let (lo, hi) = (a.inf(&b).inf(&c), a.sup(&b).sup(&c));
        let (mut inside, mut outside) = (0, 0);
        for n in 0..total {
            let (i, j, k) = (n % 6, (n / 6) % 5, n / 30);
            let p = Vec3::new(-0.1, -0.1, -0.1) + Vec3::new(i as Real, j as Real, k as Real) * 0.04;
            let gap = (lo - p).sup(&(p - hi)).sup(&Vec3::zeros()).max();
            if gap < reach - 1e-9 {
                inside += 1;
                assert!(face[n] == 0, "node {n} at {gap} m not reached");
            } else if gap > reach + 1e-9 {
                outside += 1;
                assert!(face[n] == u32::MAX, "node {n} at {gap} m reached");
            }
        }
        assert!(
            inside > 10 && outside > 10,
            "{inside} within, {outside} beyond"
        );
    }
}
