//! The broad phase: a spatial hash of boxes (Teschner et al. 2003), rebuilt from scratch each
//! time the cloth has moved. Cells are hashed into a table twice the number of entries, filled
//! by a counting sort, so a rebuild allocates nothing once the vectors have grown.

use tryon_core::math::{Real, Vec3};

/// Most cells one box covers along an axis: the cells grow to keep every box within it.
const MAX_SPAN: i64 = 16;

/// A spatial hash of boxes.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Grid {
    cell: Real,
    mask: u64,
    /// Bucket `b`'s items are `items[start[b]..start[b + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
    /// Scratch: (bucket, item) before the sort.
    pairs: Vec<(u32, u32)>,
}

fn bucket(c: [i64; 3], mask: u64) -> u32 {
    let h = (c[0] as u64).wrapping_mul(73_856_093)
        ^ (c[1] as u64).wrapping_mul(19_349_663)
        ^ (c[2] as u64).wrapping_mul(83_492_791);
    (h.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 20 & mask) as u32
}

impl Grid {
    fn span(&self, lo: &Vec3, hi: &Vec3) -> ([i64; 3], [i64; 3]) {
        let f = |v: Real| (v / self.cell).floor() as i64;
        let a = [f(lo.x), f(lo.y), f(lo.z)];
        let b = [f(hi.x), f(hi.y), f(hi.z)];
        (a, b)
    }

    /// Rebuilds the hash over `boxes` with cells of side at least `cell` (finite and positive;
    /// larger where a box would cover more than `MAX_SPAN` cells along an axis).
    pub fn build(&mut self, boxes: &[(Vec3, Vec3)], cell: Real) {
        let longest = boxes
            .iter()
            .map(|(lo, hi)| (hi - lo).max())
            .fold(0.0, Real::max);
        self.cell = cell.max(longest / (MAX_SPAN - 1) as Real);
        self.pairs.clear();
        let mut count = 0usize;
        for (lo, hi) in boxes {
            let (a, b) = self.span(lo, hi);
            count += (0..3)
                .map(|k| (b[k] - a[k] + 1).max(0) as usize)
                .product::<usize>();
        }
        let size = (2 * count.max(1)).next_power_of_two();
        self.mask = size as u64 - 1;
        for (i, (lo, hi)) in boxes.iter().enumerate() {
            let (a, b) = self.span(lo, hi);
            for x in a[0]..=b[0] {
                for y in a[1]..=b[1] {
                    for z in a[2]..=b[2] {
                        self.pairs.push((bucket([x, y, z], self.mask), i as u32));
                    }
                }
            }
        }
        self.start.clear();
        self.start.resize(size + 1, 0);
        for &(b, _) in &self.pairs {
            self.start[b as usize + 1] += 1;
        }
        for b in 0..size {
            self.start[b + 1] += self.start[b];
        }
        self.items.clear();
        self.items.resize(self.pairs.len(), 0);
        let mut fill = self.start.clone();
        for &(b, i) in &self.pairs {
            self.items[fill[b as usize] as usize] = i;
            fill[b as usize] += 1;
        }
    }

    /// Every item listed in a cell the box `lo..hi` covers, sorted, each once (and perhaps
    /// items of other cells sharing a bucket).
    pub fn query(&self, lo: &Vec3, hi: &Vec3, out: &mut Vec<u32>) {
        self.query_any_order(lo, hi, out);
        out.sort_unstable();
        out.dedup();
    }

    /// As [`Grid::query`], in the order the cells list them and each once by `seen` (a stamp
    /// per item, kept by the caller between queries; no sort).
    pub fn query_once(&self, lo: &Vec3, hi: &Vec3, seen: &mut Stamps, out: &mut Vec<u32>) {
        self.query_any_order(lo, hi, out);
        seen.next(self.items.len());
        out.retain(|&i| seen.first(i));
    }

    fn query_any_order(&self, lo: &Vec3, hi: &Vec3, out: &mut Vec<u32>) {
        out.clear();
        if self.items.is_empty() {
            return;
        }
        let (a, b) = self.span(lo, hi);
        for x in a[0]..=b[0] {
            for y in a[1]..=b[1] {
                for z in a[2]..=b[2] {
                    let k = bucket([x, y, z], self.mask) as usize;
                    let r = self.start[k] as usize..self.start[k + 1] as usize;
                    out.extend_from_slice(&self.items[r]);
                }
            }
        }
    }
}

/// Which items a query has met, by generation: nothing to clear between queries.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Stamps {
    stamp: Vec<u32>,
    generation: u32,
}

impl Stamps {
    /// A new query over items numbered below `n` (at least).
    pub fn next_over(&mut self, n: usize) {
        self.next(n)
    }

    fn next(&mut self, n: usize) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.iter_mut().for_each(|s| *s = 0);
            self.generation = 1;
        }
        let need = self.stamp.len().max(n);
        self.stamp.resize(need, 0);
    }

    /// Whether this query meets item `i` for the first time (marks it met).
    pub fn first(&mut self, i: u32) -> bool {
        let s = &mut self.stamp[i as usize];
        let fresh = *s != self.generation;
        *s = self.generation;
        fresh
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_query_finds_every_box_it_overlaps() {
        let boxes: Vec<(Vec3, Vec3)> = (0..50)
            .map(|i| {
                let c = Vec3::new((i % 7) as Real * 0.013, (i / 7) as Real * 0.011, 0.0);
                (c, c + Vec3::repeat(0.004 + 0.001 * (i % 3) as Real))
            })
            .collect();
        let mut g = Grid::default();
        g.build(&boxes, 0.01);
        let mut out = Vec::new();
        for (qlo, qhi) in [
            (Vec3::zeros(), Vec3::repeat(0.02)),
            (Vec3::new(0.03, 0.01, -0.01), Vec3::new(0.05, 0.04, 0.01)),
        ] {
            g.query(&qlo, &qhi, &mut out);
            for (i, (lo, hi)) in boxes.iter().enumerate() {
                let meets = (0..3).all(|k| lo[k] <= qhi[k] && qlo[k] <= hi[k]);
                if meets {
                    assert!(out.contains(&(i as u32)), "box {i} missed");
                }
            }
        }
    }
}
