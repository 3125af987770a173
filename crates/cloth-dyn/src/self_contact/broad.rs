//! The broad phase of self-contact, two ways to be measured against each other: the spatial hash
//! of `grid.rs` over triangles (edges found through their triangles), or two bounding volume
//! hierarchies (parry3d-f64's `Bvh`), one over triangles and one over edges, built once from the
//! first shape and refitted to each new one.

use super::grid::{Grid, Stamps};
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::math::Point;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use tryon_core::math::{Real, Vec3};

/// Which broad phase finds candidate pairs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BroadPhase {
    /// A spatial hash rebuilt each step (Teschner et al. 2003).
    Hash,
    /// Hierarchies of boxes refitted each step.
    #[default]
    Tree,
}

/// A thread's scratch space for queries.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Scratch {
    /// Candidate triangles of a vertex, or candidate edges of an edge.
    pub found: Vec<u32>,
    tris: Stamps,
    edges: Stamps,
}

/// The broad phase's state.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Broad {
    pub kind: BroadPhase,
    grid: Grid,
    tri_tree: Option<Bvh>,
    edge_tree: Option<Bvh>,
    /// Edge boxes, grown by their ends' reach.
    edge_boxes: Vec<(Vec3, Vec3)>,
}

fn aabb((lo, hi): &(Vec3, Vec3)) -> Aabb {
    Aabb::new(Point::from(*lo), Point::from(*hi))
}

fn refit(tree: &mut Option<Bvh>, boxes: &[(Vec3, Vec3)]) {
    match tree {
        Some(t) => {
            for (i, b) in boxes.iter().enumerate() {
                t.insert_or_update_partially(aabb(b), i as u32, 0.0);
            }
            t.refit_without_opt();
        }
        None => {
            let leaves: Vec<Aabb> = boxes.iter().map(aabb).collect();
            *tree = Some(Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves));
        }
    }
}

impl Broad {
    /// An empty broad phase of the given kind.
    pub fn new(kind: BroadPhase) -> Self {
        Broad {
            kind,
            ..Broad::default()
        }
    }

    /// Rebuilds over the triangles' boxes `tri_boxes` (grown by their corners' reach) and the
    /// edges `edges` at `x` with their ends' `reach`; `cell` is the hash's cell.
    pub fn build(
        &mut self,
        tri_boxes: &[(Vec3, Vec3)],
        (x, edges, reach): (&[Vec3], &[[u32; 2]], &[Real]),
        cell: Real,
    ) {
        match self.kind {
            BroadPhase::Hash => self.grid.build(tri_boxes, cell),
            BroadPhase::Tree => {
                refit(&mut self.tri_tree, tri_boxes);
                self.edge_boxes.clear();
                self.edge_boxes.extend(edges.iter().map(|&[a, b]| {
                    let (pa, pb) = (x[a as usize], x[b as usize]);
                    let r = reach[a as usize].max(reach[b as usize]);
                    (pa.inf(&pb).add_scalar(-r), pa.sup(&pb).add_scalar(r))
                }));
                refit(&mut self.edge_tree, &self.edge_boxes);
            }
        }
    }

    /// Triangles whose boxes may meet `lo..hi`, each once, into `sc.found`.
    pub fn triangles(&self, lo: &Vec3, hi: &Vec3, sc: &mut Scratch) {
        match (self.kind, &self.tri_tree) {
            (BroadPhase::Tree, Some(t)) => {
                sc.found.clear();
                let q = aabb(&(*lo, *hi));
                sc.found.extend(t.intersect_aabb(&q));
            }
            _ => self.grid.query_once(lo, hi, &mut sc.tris, &mut sc.found),
        }
    }

    /// Edges after `e` whose boxes may meet `lo..hi` (edge `e`'s box grown by its reach), each
    /// once and sorted, into `sc.found`; `tri_edges` gives each triangle's edges.
    pub fn edges(
        &self,
        e: u32,
        (lo, hi): (&Vec3, &Vec3),
        tri_edges: &[[u32; 3]],
        sc: &mut Scratch,
    ) {
        match (self.kind, &self.edge_tree) {
            (BroadPhase::Tree, Some(t)) => {
                sc.found.clear();
                let q = aabb(&(*lo, *hi));
                sc.found.extend(t.intersect_aabb(&q).filter(|&f| f > e));
            }
            _ => {
                self.grid.query_once(lo, hi, &mut sc.tris, &mut sc.found);
                sc.edges.next_over(tri_edges.len() * 3);
                let tris = std::mem::take(&mut sc.found);
                for &t in &tris {
                    for f in tri_edges[t as usize] {
                        if f > e && sc.edges.first(f) {
                            sc.found.push(f);
                        }
                    }
                }
            }
        }
        // Sorted, so the result is the same on any thread count.
        sc.found.sort_unstable();
    }
}
