//! Body parts pressed against each other. Linear blend skinning moves each part with its bones
//! alone, so where two parts meet in a pose (an arm hanging against the chest, thighs together, the
//! chin on the chest) their surfaces pass into each other by a centimetre or more, and cloth caught
//! between them has no place outside both. Real tissue gives way instead: here each vertex found
//! behind the surface of a facing part moves out along that part's normal by half the overlap
//! plus half of a gap, so the two surfaces meet `gap` apart, as flesh pressed together does.
//!
//! A vertex's facing part is found as the collider finds a pinch: the nearest vertex of another
//! part whose normal opposes the vertex's own, with the vertex in front of it or at most
//! [`DEEPEST`] behind (deeper, it is the part's far side).

use rayon::prelude::*;
use tryon_core::math::{Real, Vec3, vertex_normals};
use tryon_core::pose::Skeleton;

/// How far behind a facing part's surface a vertex may be and still be pressed out (m).
pub const DEEPEST: Real = 0.03;
/// How far a facing vertex is looked for (m); also the lookup's cell.
const REACH: Real = 0.03;
/// Normals whose cosine is below this face each other.
const FACING: Real = -0.5;

/// Which part each vertex belongs to, and the gap kept between parts.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Press {
    /// Part of each vertex (for example torso, each arm, each leg, head).
    pub parts: Vec<u8>,
    /// Distance kept between two parts pressed together (m).
    pub gap: Real,
}

impl Press {
    /// Each vertex's part from its strongest joint: part `k + 1` is everything from
    /// `roots[k]` down the skeleton (a limb, the head), 0 the rest (the torso). `joints` and
    /// `weights` are the skin's four influences per vertex; a joint outside the skeleton counts
    /// as the torso.
    pub fn parts_from_roots(
        skeleton: &Skeleton,
        joints: &[[u16; 4]],
        weights: &[[Real; 4]],
        roots: &[Option<usize>],
    ) -> Vec<u8> {
        let part_of_joint: Vec<u8> = (0..skeleton.parents.len())
            .map(|mut j| {
                loop {
                    if let Some(k) = roots.iter().position(|r| *r == Some(j)) {
                        break k as u8 + 1;
                    }
                    match skeleton.parents[j] {
                        Some(p) => j = p,
                        None => break 0,
                    }
                }
            })
            .collect();
        joints
            .iter()
            .zip(weights)
            .map(|(j, w)| {
                let k = (0..4).max_by(|&a, &b| w[a].total_cmp(&w[b])).unwrap_or(0);
                part_of_joint.get(j[k] as usize).copied().unwrap_or(0)
            })
            .collect()
    }
}

/// What one pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pressed {
    /// Vertices moved.
    pub moved: usize,
    /// The largest overlap found (m), before the move.
    pub deepest: Real,
}

/// The 27 offsets of a cell's neighbourhood.
fn ring() -> impl Iterator<Item = [i32; 3]> + Clone {
    (-1..=1).flat_map(|a| (-1..=1).flat_map(move |b| (-1..=1).map(move |k| [a, b, k])))
}

/// Vertices binned in a dense grid of cells at least [`REACH`] wide, with the parts each cell holds.
struct Grid {
    lo: Vec3,
    cell: Real,
    dims: [i64; 3],
    /// Vertices of cell `c` are `items[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
    /// A bit per part present in the cell.
    mask: Vec<u32>,
    /// The items' positions and parts in the items' order (a cell's are contiguous).
    xs: Vec<Vec3>,
    parts: Vec<u8>,
}

/// Most cells a grid may have; a body spread wider gets coarser cells.
const MAX_CELLS: i64 = 1 << 22;

impl Grid {
    fn new(x: &[Vec3], parts: &[u8]) -> Option<Grid> {
        let ok = |p: &Vec3| p.iter().all(|c| c.is_finite());
        let (mut lo, mut hi) = (Vec3::repeat(Real::MAX), Vec3::repeat(Real::MIN));
        for p in x.iter().filter(|p| ok(p)) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if lo.x > hi.x {
            return None;
        }
        let mut cell = REACH;
        let dims = loop {
            let d = ((hi - lo) / cell).map(|e| (e.floor() as i64).saturating_add(1));
            if d.iter().all(|&e| e <= MAX_CELLS)
                && d.x.saturating_mul(d.y).saturating_mul(d.z) <= MAX_CELLS
            {
                break [d.x, d.y, d.z];
            }
            cell *= 2.0;
        };
        let mut g = Grid {
            lo,
            cell,
            dims,
            start: vec![0; (dims[0] * dims[1] * dims[2]) as usize + 1],
            items: Vec::new(),
            mask: vec![0; (dims[0] * dims[1] * dims[2]) as usize],
            xs: Vec::new(),
            parts: Vec::new(),
        };
        let at: Vec<Option<usize>> = x
            .iter()
            .map(|p| ok(p).then(|| g.index(g.coords(p))).flatten())
            .collect();
        for (v, c) in at.iter().enumerate() {
            if let Some(c) = *c {
                g.start[c + 1] += 1;
                g.mask[c] |= 1 << (parts[v] % 32);
            }
        }
        for c in 1..g.start.len() {
            g.start[c] += g.start[c - 1];
        }
        let mut fill = g.start.clone();
        g.items = vec![0; g.start[g.start.len() - 1] as usize];
        for (v, c) in at.iter().enumerate() {
            if let Some(c) = *c {
                g.items[fill[c] as usize] = v as u32;
                fill[c] += 1;
            }
        }
        g.xs = g.items.iter().map(|&v| x[v as usize]).collect();
        g.parts = g.items.iter().map(|&v| parts[v as usize]).collect();
        Some(g)
    }

    fn coords(&self, p: &Vec3) -> [i64; 3] {
        let q = (p - self.lo) / self.cell;
        [q.x, q.y, q.z].map(|e| e.floor() as i64)
    }

    fn index(&self, c: [i64; 3]) -> Option<usize> {
        let inside = (0..3).all(|k| c[k] >= 0 && c[k] < self.dims[k]);
        inside.then(|| ((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0]) as usize)
    }

    /// The cells around `c` (itself included) that exist.
    fn around(&self, c: [i64; 3]) -> impl Iterator<Item = usize> + '_ {
        ring().filter_map(move |d| {
            self.index([c[0] + d[0] as i64, c[1] + d[1] as i64, c[2] + d[2] as i64])
        })
    }

    /// Per cell, the parts present in it and the 26 around it: the masks OR-ed along x, then y,
    /// then z (the same as over the 27 cells, in 9 reads per cell instead of 27), row by row
    /// with no division per cell.
    fn masks_around(&self) -> Vec<u32> {
        let [nx, ny, nz] = self.dims.map(|d| d as usize);
        let mut m = self.mask.clone();
        let mut src = vec![0; m.len()];
        for (stride, len) in [(1, nx), (nx, ny), (nx * ny, nz)] {
            src.copy_from_slice(&m);
            // Cells are runs of `len` along this axis, `stride` apart: run starts are the cells
            // whose index along the axis is 0.
            let block = stride * len;
            for base in (0..m.len()).step_by(block) {
                for off in 0..stride {
                    let first = base + off;
                    for i in 0..len {
                        let c = first + i * stride;
                        if i > 0 {
                            m[c] |= src[c - stride];
                        }
                        if i + 1 < len {
                            m[c] |= src[c + stride];
                        }
                    }
                }
            }
        }
        m
    }

    fn items(&self, c: usize) -> &[u32] {
        &self.items[self.start[c] as usize..self.start[c + 1] as usize]
    }
}

impl Press {
    /// Moves the vertices of `positions` (triangles `triangles`) out of facing parts. Vertices
    /// with no part (past the end of `parts`) or non-finite positions are left alone.
    pub fn apply(&self, positions: &mut [Vec3], triangles: &[[u32; 3]]) -> Pressed {
        let n = positions.len().min(self.parts.len());
        let Some(grid) = Grid::new(&positions[..n], &self.parts) else {
            return Pressed::default();
        };
        let mut normals = Vec::new();
        vertex_normals(positions, triangles, &mut normals);
        // Only vertices of cells whose neighbourhood holds more than one part can press.
        let around = grid.masks_around();
        let candidates: Vec<usize> = (0..grid.mask.len())
            .filter(|&c| grid.mask[c] != 0 && around[c].count_ones() > 1)
            .flat_map(|c| grid.items(c).iter().map(|&v| v as usize))
            .collect();
        // Each candidate judged on its own, in parallel, the moves collected in order.
        let x: &[Vec3] = positions;
        let ns: Vec<Vec3> = grid.items.iter().map(|&v| normals[v as usize]).collect();
        let moves: Vec<(usize, Vec3, Real)> = candidates
            .par_iter()
            .with_min_len(64)
            .filter_map(|&v| self.overlap(v, x, (&normals, &ns), &grid))
            .collect();
        let mut out = Pressed::default();
        for (v, n, depth) in moves {
            positions[v] += n * (depth + self.gap) * 0.5;
            out.moved += 1;
            out.deepest = out.deepest.max(depth);
        }
        out
    }

    /// The facing part's normal and how far `v` lies behind its surface (negative down to `-gap`:
    /// in front, but nearer than the gap). `normals` per vertex, and in the grid's item order.
    fn overlap(
        &self,
        v: usize,
        x: &[Vec3],
        (normals, sorted): (&[Vec3], &[Vec3]),
        grid: &Grid,
    ) -> Option<(usize, Vec3, Real)> {
        let (p, part, nv) = (x[v], self.parts[v], normals[v]);
        let mut best: Option<(Real, u32, usize)> = None;
        let others = !(1u32 << (part % 32));
        for c in grid.around(grid.coords(&p)) {
            if grid.mask[c] & others == 0 {
                continue; // only this vertex's own part here
            }
            // The cell's items are contiguous in the grid's sorted copies.
            for k in grid.start[c] as usize..grid.start[c + 1] as usize {
                let d = (grid.xs[k] - p).norm_squared();
                let u = grid.items[k];
                if grid.parts[k] != part
                    && d <= REACH * REACH
                    && sorted[k].dot(&nv) < FACING
                    && best.is_none_or(|(b, w, _)| d < b || (d == b && u < w))
                {
                    best = Some((d, u, k));
                }
            }
        }
        let (_, u, k) = best?;
        let height = (p - x[u as usize]).dot(&sorted[k]);
        (height < self.gap && height > -DEEPEST).then_some((v, sorted[k], -height))
    }
}

#[cfg(test)]
mod tests;
