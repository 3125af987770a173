//! The cloth-cloth referee: how many of the output garment's triangle pairs cross each other, and
//! how close its layers come. It is measurement, independent of the solver's own proximity code:
//! a uniform grid of the triangles' boxes finds the candidates (each overlapping pair in the one
//! cell holding the low corner of its overlap), a plane-side test rejects pairs that cannot
//! touch, signs of volumes decide the rest (`tritri`), and parry's GJK the pairs too close to
//! call (`query::intersection_test`); gaps are parry's point-triangle projections.

use parry3d_f64::math::{Isometry, Point};
use parry3d_f64::query::{PointQuery, intersection_test};
use parry3d_f64::shape::Triangle;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use tryon_core::math::{Real, Vec3};

/// Farthest layer gap the referee looks for (m); a garment with no closer layers reads this.
pub const GAP_REACH: Real = 0.01;

/// A layer gap is measured along the face's normal: the vertex's offset from its projection
/// makes at least this cosine with the face normal (in-plane neighbours are not layers).
const ALONG_NORMAL: Real = 0.9;

/// Most grid cells a triangle's box spans along an axis.
const MOST_CELLS: Real = 16.0;

/// Smallest grid cell (m): a gap query's box (up to `2 GAP_REACH` wide) spans at most five a side.
const MIN_CELL: Real = GAP_REACH / 2.0;

/// Fewest triangles a thread takes at once.
const CHUNK: usize = 64;

/// What the referee found in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ClothContact {
    /// Pairs of triangles that share no vertex and intersect.
    pub crossings: usize,
    /// Smallest distance from a vertex to a triangle not around it, where the offset to the
    /// triangle's nearest point runs along the triangle's normal (so a neighbour in the cloth's
    /// own plane is not a layer) (m); `GAP_REACH` when none is nearer.
    pub min_gap: Real,
}

/// A uniform grid over boxes: each box is listed in every cell it overlaps.
struct Grid {
    cell: Real,
    /// (cell key, item), sorted.
    entries: Vec<(u64, u32)>,
    /// Open-addressed table of the occupied cells: (key, first entry, entry count); a slot with
    /// count 0 is empty. Its length is a power of two.
    table: Vec<(u64, u32, u32)>,
    /// Number of items (boxes).
    items: usize,
    /// Per item, the cell holding its box's low corner.
    low: Vec<[i64; 3]>,
}

/// One thread's scratch space for grid queries: the items found, the cells' keys, and a stamp
/// per item marking the query that last found it (so each is listed once without sorting).
#[derive(Default)]
struct Scratch {
    found: Vec<u32>,
    keys: Vec<u64>,
    seen: Vec<u32>,
    stamp: u32,
}

fn key(c: [i64; 3]) -> u64 {
    // Wrapping mix of the three cell coordinates; distinct cells may share a key (the exact
    // tests that follow sort them out).
    (c[0] as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (c[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (c[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9)
}

impl Grid {
    /// The keys of the cells a box overlaps.
    fn cells(&self, lo: &Vec3, hi: &Vec3, out: &mut Vec<u64>) {
        let f = |v: Real| (v / self.cell).floor() as i64;
        let (a, b) = ([f(lo.x), f(lo.y), f(lo.z)], [f(hi.x), f(hi.y), f(hi.z)]);
        out.clear();
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                out.extend((a[2]..=b[2]).map(|z| key([x, y, z])));
            }
        }
    }

    fn new(boxes: &[(Vec3, Vec3)], cell: Real) -> Self {
        let mut g = Grid {
            cell,
            entries: Vec::new(),
            table: Vec::new(),
            items: boxes.len(),
            low: Vec::with_capacity(boxes.len()),
        };
        let mut keys = Vec::new();
        for (i, (lo, hi)) in boxes.iter().enumerate() {
            let f = |v: Real| (v / cell).floor() as i64;
            g.low.push([f(lo.x), f(lo.y), f(lo.z)]);
            g.cells(lo, hi, &mut keys);
            g.entries.extend(keys.iter().map(|&k| (k, i as u32)));
        }
        g.entries.sort_unstable();
        // Two cells that share a key are one run; a box in both is listed in it once.
        g.entries.dedup();
        let cells = g.entries.chunk_by(|a, b| a.0 == b.0).count();
        g.table = vec![(0, 0, 0); (2 * cells).next_power_of_two().max(2)];
        let mut start = 0;
        for run in g.entries.chunk_by(|a, b| a.0 == b.0) {
            let slot = g.slot(run[0].0);
            g.table[slot] = (run[0].0, start as u32, run.len() as u32);
            start += run.len();
        }
        g
    }

    /// The table slot holding cell `key`, or the empty slot where it would go.
    fn slot(&self, key: u64) -> usize {
        let mask = self.table.len() - 1;
        // The keys are already mixed: their high bits index the table.
        let mut s = (key >> 32) as usize & mask;
        while self.table[s].2 != 0 && self.table[s].0 != key {
            s = (s + 1) & mask;
        }
        s
    }

    /// Items whose cells meet the box, each once, into `s.found` (in no particular order, the
    /// same on every call).
    fn query(&self, lo: &Vec3, hi: &Vec3, s: &mut Scratch) {
        self.cells(lo, hi, &mut s.keys);
        s.found.clear();
        s.seen.resize(self.items, 0);
        s.stamp = s.stamp.wrapping_add(1);
        if s.stamp == 0 {
            s.seen.fill(0);
            s.stamp = 1;
        }
        for &k in &s.keys {
            let (_, start, count) = self.table[self.slot(k)];
            let run = &self.entries[start as usize..(start + count) as usize];
            for &(_, item) in run {
                let seen = &mut s.seen[item as usize];
                if *seen != s.stamp {
                    *seen = s.stamp;
                    s.found.push(item);
                }
            }
        }
    }
}

fn bounds(x: &[Vec3], t: &[u32; 3], pad: Real) -> (Vec3, Vec3) {
    let (a, b, c) = (x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]);
    let p = Vec3::repeat(pad);
    (a.inf(&b).inf(&c) - p, a.sup(&b).sup(&c) + p)
}

fn triangle(x: &[Vec3], t: &[u32; 3]) -> Triangle {
    let p = |i: u32| Point::from(x[i as usize]);
    Triangle::new(p(t[0]), p(t[1]), p(t[2]))
}

fn shares_vertex(a: &[u32; 3], b: &[u32; 3]) -> bool {
    a.iter().any(|v| b.contains(v))
}

/// Whether all three corners of `b` lie strictly on one side of `a`'s plane.
fn one_side(x: &[Vec3], a: &[u32; 3], b: &[u32; 3]) -> bool {
    let (p, q, r) = (x[a[0] as usize], x[a[1] as usize], x[a[2] as usize]);
    let n = (q - p).cross(&(r - p));
    let s = b.map(|v| n.dot(&(x[v as usize] - p)));
    s.iter().all(|d| *d > 0.0) || s.iter().all(|d| *d < 0.0)
}

/// Whether triangles `a` and `b` (sharing no vertex) intersect.
fn crossing(x: &[Vec3], a: &[u32; 3], b: &[u32; 3]) -> bool {
    if one_side(x, a, b) || one_side(x, b, a) {
        return false;
    }
    let corners = |t: &[u32; 3]| t.map(|v| x[v as usize]);
    crate::tritri::intersect(&corners(a), &corners(b)).unwrap_or_else(|| {
        let id = Isometry::identity();
        intersection_test(&id, &triangle(x, a), &id, &triangle(x, b)).unwrap_or(false)
    })
}

/// Judges one frame of a garment: positions `x`, triangles `tris` (indices checked by the caller).
pub fn judge(x: &[Vec3], tris: &[[u32; 3]]) -> ClothContact {
    match index(x, tris) {
        Some((boxes, grid)) => ClothContact {
            crossings: crossing_pairs(x, tris, &boxes, &grid).len(),
            min_gap: min_gap(x, tris, &boxes, &grid),
        },
        None => ClothContact {
            crossings: 0,
            min_gap: if tris.is_empty() { GAP_REACH } else { 0.0 },
        },
    }
}

/// The crossing pairs of triangles (indices into `tris`, the lower first, in order): where a
/// garment passes through itself.
pub fn crossings(x: &[Vec3], tris: &[[u32; 3]]) -> Vec<[u32; 2]> {
    index(x, tris).map_or_else(Vec::new, |(boxes, grid)| {
        crossing_pairs(x, tris, &boxes, &grid)
    })
}

/// The triangles' boxes and their grid (`None` for no triangles or non-finite positions).
fn index(x: &[Vec3], tris: &[[u32; 3]]) -> Option<(Vec<(Vec3, Vec3)>, Grid)> {
    if tris.is_empty() {
        return None;
    }
    let boxes: Vec<(Vec3, Vec3)> = tris.iter().map(|t| bounds(x, t, 0.0)).collect();
    let mean_edge = tris
        .iter()
        .map(|t| (x[t[0] as usize] - x[t[1] as usize]).norm())
        .sum::<Real>()
        / tris.len() as Real;
    // Twice the mean edge, but no box spans more than `MOST_CELLS` cells a side (a stray long
    // triangle, or a collapsed mesh, would list itself in millions).
    let widest = boxes
        .iter()
        .map(|(lo, hi)| (hi - lo).max())
        .fold(0.0, Real::max);
    let cell = (2.0 * mean_edge).max(widest / MOST_CELLS).max(MIN_CELL);
    cell.is_finite().then(|| {
        let grid = Grid::new(&boxes, cell);
        (boxes, grid)
    })
}

fn crossing_pairs(
    x: &[Vec3],
    tris: &[[u32; 3]],
    boxes: &[(Vec3, Vec3)],
    grid: &Grid,
) -> Vec<[u32; 2]> {
    // Pairs are met cell by cell: each pair of boxes that overlap is tested in one cell only,
    // the one holding the low corner of their overlap (both boxes are listed there).
    let runs: Vec<(u64, u32, u32)> = grid.table.iter().filter(|c| c.2 > 1).copied().collect();
    let mut pairs: Vec<[u32; 2]> = runs
        .par_iter()
        .with_min_len(CHUNK)
        .flat_map_iter(|&(cell, start, count)| {
            let run = &grid.entries[start as usize..(start + count) as usize];
            let mut out = Vec::new();
            for (a, &(_, i)) in run.iter().enumerate() {
                let (ilo, ihi) = &boxes[i as usize];
                let ic = grid.low[i as usize];
                for &(_, j) in &run[a + 1..] {
                    // The overlap's low corner is in the cell of the larger low cell indices.
                    let jc = grid.low[j as usize];
                    if key([ic[0].max(jc[0]), ic[1].max(jc[1]), ic[2].max(jc[2])]) != cell {
                        continue;
                    }
                    let (jlo, jhi) = &boxes[j as usize];
                    if (0..3).any(|k| ilo[k] > jhi[k] || jlo[k] > ihi[k]) {
                        continue;
                    }
                    let (ti, tj) = (&tris[i as usize], &tris[j as usize]);
                    if !shares_vertex(ti, tj) && crossing(x, ti, tj) {
                        out.push([i.min(j), i.max(j)]);
                    }
                }
            }
            out
        })
        .collect();
    pairs.sort_unstable();
    pairs
}

/// The smallest vertex-face gap along the face's normal (see [`ClothContact::min_gap`]).
///
/// The answer is one number for the whole garment, so every vertex looks only as far as the
/// smallest gap found so far by any thread (`bound`): a candidate no nearer than that cannot
/// lower the minimum, so the result is the same whatever the order, and a layered garment's
/// vertices query a box a few millimetres wide instead of two centimetres.
fn min_gap(x: &[Vec3], tris: &[[u32; 3]], boxes: &[(Vec3, Vec3)], grid: &Grid) -> Real {
    let bound = AtomicU64::new(GAP_REACH.to_bits());
    (0..x.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .for_each_init(Scratch::default, |scratch, v| {
            let reach = Real::from_bits(bound.load(Ordering::Relaxed));
            let best = vertex_gap(x, tris, boxes, grid, v, reach, scratch);
            if best < reach {
                // Non-negative floats order as their bits do.
                bound.fetch_min(best.to_bits(), Ordering::Relaxed);
            }
        });
    Real::from_bits(bound.into_inner())
}

/// Vertex `v`'s smallest gap along a face's normal to a triangle not around it, if below `reach`
/// (else `reach`).
fn vertex_gap(
    x: &[Vec3],
    tris: &[[u32; 3]],
    boxes: &[(Vec3, Vec3)],
    grid: &Grid,
    v: usize,
    reach: Real,
    scratch: &mut Scratch,
) -> Real {
    let p = x[v];
    let pad = Vec3::repeat(reach);
    grid.query(&(p - pad), &(p + pad), scratch);
    let mut best = reach;
    for &j in scratch.found.iter() {
        let t = &tris[j as usize];
        // A triangle is no nearer than its box: one that far cannot lower `best`.
        let (lo, hi) = &boxes[j as usize];
        let outside = (lo - p).sup(&(p - hi)).sup(&Vec3::zeros());
        if outside.norm_squared() >= best * best || t.contains(&(v as u32)) {
            continue;
        }
        let tri = triangle(x, t);
        let proj = tri.project_local_point(&Point::from(p), false);
        let off = p - proj.point.coords;
        let d = off.norm();
        let n = tri.normal().map(|n| n.into_inner());
        let along = n.is_some_and(|n| n.dot(&off).abs() >= ALONG_NORMAL * d);
        if d < best && along {
            best = d;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat square sheet of n x n cells of side `s` at height `z`, indices offset by `base`.
    fn sheet(n: u32, s: Real, z: Real, base: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut x = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                x.push(Vec3::new(i as Real * s, j as Real * s, z));
            }
        }
        let mut t = Vec::new();
        let id = |i: u32, j: u32| base + j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        (x, t)
    }

    /// Two such sheets, the second `gap` above the first; with the first sheet's vertex count.
    fn two_sheets(n: u32, s: Real, gap: Real) -> (Vec<Vec3>, Vec<[u32; 3]>, u32) {
        let (mut x, mut t) = sheet(n, s, 0.0, 0);
        let first = x.len() as u32;
        let (x2, t2) = sheet(n, s, gap, first);
        x.extend(x2);
        t.extend(t2);
        (x, t, first)
    }

    #[test]
    fn two_parallel_sheets_do_not_cross_and_their_gap_is_their_distance() {
        let (x, t, _) = two_sheets(6, 0.02, 0.003);
        let j = judge(&x, &t);
        assert_eq!(j.crossings, 0);
        assert!((j.min_gap - 0.003).abs() < 1e-9, "{j:?}");
        // One sheet alone: its own neighbours are in its plane, so no gap is found.
        let (x1, t1) = sheet(6, 0.02, 0.0, 0);
        assert_eq!(judge(&x1, &t1).min_gap, GAP_REACH);
    }

    #[test]
    fn a_vertex_pushed_through_the_other_sheet_makes_its_triangles_cross() {
        let (mut x, t, n) = two_sheets(4, 0.02, 0.003);
        // Vertex (2, 2) of the upper sheet goes 2 mm below the lower one: its six triangles
        // each pass through the lower sheet.
        let v = (n + 2 * 5 + 2) as usize;
        x[v].z = -0.002;
        let j = judge(&x, &t);
        // Each of the six triangles around it crosses the two lower triangles under the vertex
        // or the ones it passes through; at least six pairs cross, and every one shares the
        // moved vertex (counted by brute force below).
        let brute = (0..t.len())
            .flat_map(|a| (a + 1..t.len()).map(move |b| (a, b)))
            .filter(|&(a, b)| !shares_vertex(&t[a], &t[b]))
            .filter(|&(a, b)| {
                let id = Isometry::identity();
                intersection_test(&id, &triangle(&x, &t[a]), &id, &triangle(&x, &t[b])).unwrap()
            })
            .count();
        assert!(j.crossings >= 6, "{j:?}");
        assert_eq!(j.crossings, brute);
    }

    #[test]
    fn a_crumpled_sheet_crosses_itself_where_brute_force_says() {
        // A sheet folded over itself twice and shaken, so hundreds of pairs cross at every
        // angle; each crossing pair is listed once, lower index first, in order.
        let (mut x, t) = sheet(14, 0.01, 0.0, 0);
        let mut s = 0x2545_f491_4f6c_dd1d_u64;
        for p in x.iter_mut() {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let r = (s >> 11) as Real / (1u64 << 53) as Real - 0.5;
            let (u, v) = (p.x * 60.0, p.y * 31.0);
            *p = Vec3::new(
                0.03 * u.sin(),
                p.y,
                0.004 * u + 0.01 * v.cos() * u.cos() + r * 0.01,
            );
        }
        let want: Vec<[u32; 2]> = (0..t.len())
            .flat_map(|a| (a + 1..t.len()).map(move |b| (a, b)))
            .filter(|&(a, b)| !shares_vertex(&t[a], &t[b]))
            .filter(|&(a, b)| {
                let id = Isometry::identity();
                intersection_test(&id, &triangle(&x, &t[a]), &id, &triangle(&x, &t[b])).unwrap()
            })
            .map(|(a, b)| [a as u32, b as u32])
            .collect();
        assert!(want.len() > 100, "{}", want.len());
        assert_eq!(crossings(&x, &t), want);
    }

    /// The smallest gap by brute force: every vertex against every triangle not around it, the
    /// offset from parry's nearest point within 26 degrees of the triangle's normal.
    fn brute_gap(x: &[Vec3], t: &[[u32; 3]]) -> Real {
        let mut best = GAP_REACH;
        for (v, p) in x.iter().enumerate() {
            for tri in t.iter().filter(|tri| !tri.contains(&(v as u32))) {
                let tr = triangle(x, tri);
                let q = tr.project_local_point(&Point::from(*p), false).point.coords;
                let (off, n) = (p - q, tr.normal().unwrap().into_inner());
                if n.dot(&off).abs() >= ALONG_NORMAL * off.norm() {
                    best = best.min(off.norm());
                }
            }
        }
        best
    }

    #[test]
    fn the_smallest_gap_is_the_brute_force_one_on_any_thread_count() {
        // Two wavy sheets a few millimetres apart, the upper one dented toward the lower in a
        // few places, so the smallest gap sits at one vertex somewhere in the middle.
        let (mut x, t, n) = two_sheets(12, 0.01, 0.006);
        for (k, p) in x.iter_mut().enumerate() {
            p.z += 0.001 * ((k as Real) * 0.7).sin();
        }
        for (k, dent) in [(40, 0.0031), (97, 0.0042), (130, 0.0027)] {
            x[n as usize + k].z -= dent;
        }
        let want = brute_gap(&x, &t);
        assert!(want < 0.004 && want > 0.0, "{want}");
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let got = pool.install(|| judge(&x, &t));
            assert_eq!(got.min_gap, want, "{threads} threads");
        }
    }

    #[test]
    fn degenerate_and_empty_input_give_no_crossings() {
        assert_eq!(judge(&[], &[]).crossings, 0);
        // Triangles collapsed to points, apart from each other.
        let mut x = vec![Vec3::zeros(); 6];
        x[3..].fill(Vec3::repeat(1.0));
        assert_eq!(judge(&x, &[[0, 1, 2], [3, 4, 5]]).crossings, 0);
        // A non-finite vertex gives no figures rather than a panic.
        x[0].x = Real::NAN;
        assert_eq!(judge(&x, &[[0, 1, 2], [3, 4, 5]]).crossings, 0);
    }
}
