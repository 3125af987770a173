//! Local Laplacian smoothing of a fold (Algorithm 1 step 3, P3 3.4). Each round moves every
//! vertex of the fold's region a fraction `lambda` of the way to the mean of its neighbours, all
//! from the positions before the round. Under Taubin's hierarchical constraint a new vertex's
//! neighbours are only the new vertices it is joined to, so the ridge is smoothed along its
//! length and keeps its height, while the old vertices around it (which see every neighbour) are
//! drawn up to it; a new vertex with fewer than two new neighbours (a ridge's end) holds still.
//! Without the constraint every vertex sees all its neighbours, and the ridge sinks.

use crate::Folded;
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::PolyMesh;

/// One smoothing round's kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Round {
    /// Every vertex of the region sees all its neighbours.
    Plain,
    /// New vertices see only new neighbours (Taubin's hierarchical constraint).
    Constrained,
}

/// One round over the vertices with `region` set, with neighbours `ring`.
pub fn smooth_round(
    x: &mut [Vec3],
    ring: &[Vec<u32>],
    is_new: &[bool],
    region: &[bool],
    round: Round,
    lambda: Real,
) {
    let n = x.len().min(ring.len()).min(is_new.len()).min(region.len());
    let moved: Vec<(usize, Vec3)> = (0..n)
        .filter(|&v| region[v])
        .filter_map(|v| {
            let sees = |u: &&u32| {
                (**u as usize) < n && (round == Round::Plain || !is_new[v] || is_new[**u as usize])
            };
            let near: Vec<u32> = ring[v].iter().filter(sees).copied().collect();
            if near.is_empty() || (is_new[v] && round == Round::Constrained && near.len() < 2) {
                return None;
            }
            let mean = near.iter().map(|&u| x[u as usize]).sum::<Vec3>() / near.len() as Real;
            Some((v, x[v] + (mean - x[v]) * lambda))
        })
        .collect();
    for (v, p) in moved {
        if p.iter().all(|c| c.is_finite()) {
            x[v] = p;
        }
    }
}

/// The vertices smoothing may move: the new ones and `rings` rings of old ones around them, less
/// old vertices on the mesh's open boundary (smoothing would pull a hem in).
pub(crate) fn region(f: &Folded, rings: u32) -> Vec<bool> {
    let ring = crate::ring_of(&f.mesh);
    let boundary = boundary_vertices(&f.mesh);
    let mut inside = f.is_new.clone();
    let mut front: Vec<u32> = (0..inside.len() as u32)
        .filter(|&v| inside[v as usize])
        .collect();
    for _ in 0..rings {
        let mut next = Vec::new();
        for &v in &front {
            for &u in &ring[v as usize] {
                if !inside[u as usize] {
                    inside[u as usize] = true;
                    next.push(u);
                }
            }
        }
        front = next;
    }
    for (v, b) in boundary.iter().enumerate() {
        if *b && !f.is_new[v] {
            inside[v] = false;
        }
    }
    inside
}

/// Per vertex, whether it lies on an edge with one face.
pub(crate) fn boundary_vertices(mesh: &PolyMesh) -> Vec<bool> {
    let mut count: std::collections::HashMap<(u32, u32), u32> = Default::default();
    for f in &mesh.faces {
        let vs = f.vertices();
        for k in 0..vs.len() {
            let (a, b) = (vs[k], vs[(k + 1) % vs.len()]);
            *count.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut out = vec![false; mesh.positions.len()];
    for ((a, b), c) in count {
        if c == 1 {
            out[a as usize] = true;
            out[b as usize] = true;
        }
    }
    out
}
