//! A bounding volume hierarchy of a body's triangles built for the cloth's per-substep queries:
//! eight children per node, their boxes in f32 lanes (`wide::f32x8`: one node's eight box
//! distances at once), the tree built once from the body's first shape and refitted to each new
//! one. Boxes are padded outward (`PAD`), so a box's f32 distance never exceeds the f64 distance
//! of a triangle inside it and nothing nearer is pruned: the nearest face found is the one a
//! search over every triangle in f64 finds (`tests::nearest_matches_brute_force`). Replaces
//! parry's binary `Bvh` in the exact collider (issue 67 item 3: 700 ns a query there).

use tryon_core::math::{Real, Vec3};
use wide::{CmpLe, f32x8};

/// Children per node.
const WIDE: usize = 8;
/// Most triangles in a leaf.
const LEAF: usize = 1;
/// A child slot with nothing in it.
const EMPTY: u32 = u32::MAX;
/// Marks a child that is a leaf: `LEAF_BIT | start << 3 | (count - 1)`.
const LEAF_BIT: u32 = 1 << 31;

/// One node: its children's boxes, per axis and lane, and the children.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
struct Node {
    lo: [[f32; WIDE]; 3],
    hi: [[f32; WIDE]; 3],
    child: [u32; WIDE],
}

impl Node {
    fn empty() -> Self {
        Node {
            lo: [[f32::INFINITY; WIDE]; 3],
            hi: [[f32::NEG_INFINITY; WIDE]; 3],
            child: [EMPTY; WIDE],
        }
    }
}

/// The tree (see the module docs).
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct FaceTree {
    /// Nodes, each after its parent (node 0 is the root).
    nodes: Vec<Node>,
    /// Face indices in leaf order.
    order: Vec<u32>,
}

/// A box corner in f32, moved outward by more than the rounding of the f64 value.
fn pad(x: Real, up: bool) -> f32 {
    let pad = 1e-5 + x.abs() * 1e-6;
    if up {
        (x + pad) as f32
    } else {
        (x - pad) as f32
    }
}

impl FaceTree {
    /// The tree of `triangles` over `positions` (the body's first shape).
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let centre = |f: u32| -> Vec3 {
            let t = triangles[f as usize];
            let c: Vec3 = t
                .iter()
                .map(|&v| positions.get(v as usize).copied().unwrap_or_default())
                .sum();
            let c = c / 3.0;
            if tryon_core::math::is_finite(&c) {
                c
            } else {
                Vec3::zeros()
            }
        };
        let centres: Vec<Vec3> = (0..triangles.len() as u32).map(centre).collect();
        let mut tree = FaceTree {
            nodes: Vec::new(),
            order: (0..triangles.len() as u32).collect(),
        };
        if !triangles.is_empty() {
            let mut order = std::mem::take(&mut tree.order);
            tree.build(&mut order, 0, &centres);
            tree.order = order;
        }
        tree.refit(positions, triangles);
        tree
    }

    /// Builds the node over `items` (which start at `start` in the leaf order); returns its index.
    fn build(&mut self, items: &mut [u32], start: usize, centres: &[Vec3]) -> u32 {
        let me = self.nodes.len();
        self.nodes.push(Node::empty());
        // Split the largest group at its median along its longest axis until there are eight
        // groups or every group fits a leaf.
        let mut groups: Vec<(usize, usize)> = vec![(0, items.len())];
        while groups.len() < WIDE {
            let Some((g, _)) = groups
                .iter()
                .enumerate()
                .filter(|(_, r)| r.1 > LEAF)
                .max_by_key(|(i, r)| (r.1, std::cmp::Reverse(*i)))
            else {
                break;
            };
            let (s, n) = groups[g];
            let part = &mut items[s..s + n];
            let axis = longest_axis(part, centres);
            let key = |f: &u32| (centres[*f as usize][axis], *f);
            part.select_nth_unstable_by(n / 2, |a, b| {
                let (ka, kb) = (key(a), key(b));
                ka.0.total_cmp(&kb.0).then(ka.1.cmp(&kb.1))
            });
            groups[g] = (s, n / 2);
            groups.insert(g + 1, (s + n / 2, n - n / 2));
        }
        for (k, &(s, n)) in groups.iter().enumerate() {
            let child = if n <= LEAF {
                LEAF_BIT | ((start + s) as u32) << 3 | (n as u32 - 1)
            } else {
                self.build(&mut items[s..s + n], start + s, centres)
            };
            self.nodes[me].child[k] = child;
        }
        me as u32
    }

    /// Takes a new shape of the same triangles: every box made again, from the leaves up.
    pub fn refit(&mut self, positions: &[Vec3], triangles: &[[u32; 3]]) {
        for i in (0..self.nodes.len()).rev() {
            for k in 0..WIDE {
                let c = self.nodes[i].child[k];
                let (lo, hi) = match c {
                    EMPTY => continue,
                    c if c & LEAF_BIT != 0 => self.leaf_box(c, positions, triangles),
                    c => {
                        let n = &self.nodes[c as usize];
                        let lo = std::array::from_fn(|a| {
                            n.lo[a].iter().copied().fold(f32::INFINITY, f32::min)
                        });
                        let hi = std::array::from_fn(|a| {
                            n.hi[a].iter().copied().fold(f32::NEG_INFINITY, f32::max)
                        });
                        (lo, hi)
                    }
                };
                for a in 0..3 {
                    self.nodes[i].lo[a][k] = lo[a];
                    self.nodes[i].hi[a][k] = hi[a];
                }
            }
        }
    }

    /// The padded box of a leaf's triangles (empty when a corner is not finite, so the leaf is
    /// never visited).
    fn leaf_box(&self, c: u32, positions: &[Vec3], triangles: &[[u32; 3]]) -> ([f32; 3], [f32; 3]) {
        let empty = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        let (mut lo, mut hi) = (
            Vec3::repeat(Real::INFINITY),
            Vec3::repeat(Real::NEG_INFINITY),
        );
        for &f in self.leaf(c) {
            for &v in &triangles[f as usize] {
                let Some(p) = positions
                    .get(v as usize)
                    .filter(|p| tryon_core::math::is_finite(p))
                else {
                    return empty;
                };
                lo = lo.inf(p);
                hi = hi.sup(p);
            }
        }
        (
            std::array::from_fn(|a| pad(lo[a], false)),
            std::array::from_fn(|a| pad(hi[a], true)),
        )
    }

    fn leaf(&self, c: u32) -> &[u32] {
        let start = ((c & !LEAF_BIT) >> 3) as usize;
        let n = (c & 7) as usize + 1;
        &self.order[start..start + n]
    }

    /// The face of least cost for `p`, among faces whose cost `leaf` gives (squared distance
    /// first) below `bound`: boxes farther than the best found so far are not entered, nearest
    /// first. `None` when no face costs less than `bound`.
    pub fn nearest<T>(
        &self,
        p: &Vec3,
        bound: Real,
        leaf: impl Fn(u32) -> (Real, T),
    ) -> Option<(u32, (Real, T))> {
        if self.nodes.is_empty() {
            return None;
        }
        let q = [p.x as f32, p.y as f32, p.z as f32].map(f32x8::splat);
        let zero = f32x8::splat(0.0);
        let mut best: Option<(u32, (Real, T))> = None;
        let mut best2 = bound;
        let mut stack: Vec<(f32, u32)> = Vec::with_capacity(64);
        stack.push((0.0, 0));
        while let Some((d2, node)) = stack.pop() {
            if d2 as Real > best2 {
                continue;
            }
            let n = &self.nodes[node as usize];
            let mut dist2 = zero;
            for a in 0..3 {
                let lo = f32x8::from(n.lo[a]);
                let hi = f32x8::from(n.hi[a]);
                let d = (lo - q[a]).max(zero) + (q[a] - hi).max(zero);
                dist2 += d * d;
            }
            let limit = f32x8::splat(best2.min(f32::MAX as Real) as f32);
            let mask = dist2.cmp_le(limit).move_mask();
            if mask == 0 {
                continue;
            }
            let dist2 = dist2.to_array();
            let mut near: [(f32, u32); WIDE] = [(0.0, 0); WIDE];
            let mut m = 0;
            for k in 0..WIDE {
                if mask & (1 << k) != 0 && n.child[k] != EMPTY {
                    near[m] = (dist2[k], n.child[k]);
                    m += 1;
                }
            }
            // Nearest first: its leaves shrink the bound for the others.
            let near = &mut near[..m];
            near.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let first_inner = stack.len();
            for &(d2, c) in near.iter() {
                if d2 as Real > best2 {
                    break;
                }
                if c & LEAF_BIT == 0 {
                    stack.push((d2, c));
                    continue;
                }
                for &f in self.leaf(c) {
                    let cost = leaf(f);
                    if cost.0 < best2 {
                        best2 = cost.0;
                        best = Some((f, cost));
                    }
                }
            }
            // Farthest on top last, so the nearest is searched next.
            stack[first_inner..].reverse();
        }
        best
    }
}

/// The axis along which `items`' centres spread most.
fn longest_axis(items: &[u32], centres: &[Vec3]) -> usize {
    let (mut lo, mut hi) = (
        Vec3::repeat(Real::INFINITY),
        Vec3::repeat(Real::NEG_INFINITY),
    );
    for &f in items {
        lo = lo.inf(&centres[f as usize]);
        hi = hi.sup(&centres[f as usize]);
    }
    let e = hi - lo;
    if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::math::closest_point_on_triangle;

    /// A bumpy closed-ish sheet of triangles and points around it (deterministic).
    fn mesh(n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as Real / n as Real, j as Real / n as Real);
                p.push(Vec3::new(x, y, 0.1 * (7.0 * x).sin() * (5.0 * y).cos()));
            }
        }
        let mut t = Vec::new();
        let w = (n + 1) as u32;
        for j in 0..n as u32 {
            for i in 0..n as u32 {
                let a = j * w + i;
                t.push([a, a + 1, a + w + 1]);
                t.push([a, a + w + 1, a + w]);
            }
        }
        (p, t)
    }

    fn d2(p: &Vec3, x: &[Vec3], t: [u32; 3]) -> Real {
        let (q, _) =
            closest_point_on_triangle(p, &x[t[0] as usize], &x[t[1] as usize], &x[t[2] as usize]);
        (q - p).norm_squared()
    }

    #[test]
    fn nearest_matches_brute_force() {
        let (mut x, t) = mesh(30);
        let mut tree = FaceTree::new(&x, &t);
        for round in 0..2 {
            if round == 1 {
                // A new shape: the tree refitted, not rebuilt.
                for v in &mut x {
                    v.z += 0.3 * v.x * v.y;
                    v.x += 0.05 * v.y;
                }
                tree.refit(&x, &t);
            }
            for k in 0..500 {
                let s = k as Real;
                let p = Vec3::new(
                    (s * 0.618).fract() * 1.2 - 0.1,
                    (s * 0.382).fract() * 1.2 - 0.1,
                    (s * 0.271).fract() * 0.4 - 0.2,
                );
                let brute = (0..t.len())
                    .map(|f| d2(&p, &x, t[f]))
                    .fold(Real::INFINITY, Real::min);
                let (_, (found, ())) = tree
                    .nearest(&p, Real::INFINITY, |f| (d2(&p, &x, t[f as usize]), ()))
                    .unwrap();
                assert_eq!(found.to_bits(), brute.to_bits(), "point {k}");
                // A bound below the nearest finds nothing; just above it finds it.
                assert!(
                    tree.nearest(&p, brute * 0.999, |f| (d2(&p, &x, t[f as usize]), ()))
                        .is_none()
                );
                assert!(
                    tree.nearest(&p, brute * 1.001 + 1e-12, |f| (
                        d2(&p, &x, t[f as usize]),
                        ()
                    ))
                    .is_some()
                );
            }
        }
    }

    #[test]
    fn a_face_with_a_non_finite_corner_is_never_visited() {
        let (mut x, t) = mesh(4);
        x[0] = Vec3::repeat(Real::NAN);
        let tree = FaceTree::new(&x, &t);
        let p = Vec3::new(0.5, 0.5, 0.3);
        let (f, _) = tree
            .nearest(&p, Real::INFINITY, |f| (d2(&p, &x, t[f as usize]), ()))
            .unwrap();
        assert!(!t[f as usize].contains(&0));
    }

    #[test]
    fn an_empty_tree_finds_nothing() {
        let tree = FaceTree::new(&[], &[]);
        assert!(
            tree.nearest(&Vec3::zeros(), Real::INFINITY, |_| (0.0, ()))
                .is_none()
        );
    }
}
