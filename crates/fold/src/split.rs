//! The mesh subdivided along the lines (Algorithm 1 step 2): the quads a line passes through
//! split into triangles (the first in the quad's place, the second after the faces), then each crossed edge split at the crossing. An edge split turns each
//! triangle (p0, p1, p2) on the edge (p0, p1) into (p0, new, p2) and (new, p1, p2), so the mesh
//! stays conforming and manifold, and two crossings in a row are always joined by an edge: the
//! second lies on an edge of a triangle the first split made, which has the first as a corner.

use crate::path::{Crossing, Walked};
use crate::{Fold, FoldError, Folded};
use std::collections::{HashMap, HashSet};
use tryon_core::math::Real;
use tryon_core::mesh::{Face, PolyMesh};

/// Crossings this close along an edge (as a fraction of it) are the same point.
const SAME: Real = 1e-9;
/// A crossing this near an end of its edge (as a fraction of it) takes that vertex instead of a
/// new one: no sliver is cut off at a vertex, and a line drawn along the mesh's edges follows
/// them.
const AT_END: Real = 0.15;

pub(crate) fn split_along(mesh: &PolyMesh, w: &Walked) -> Result<Folded, FoldError> {
    let crossed: HashSet<u32> = w
        .visited
        .iter()
        .flatten()
        .map(|&t| w.tri_face[t as usize])
        .collect();
    // The faces in their order, a crossed quad as the two triangles the walk saw (the first in
    // the quad's place, the second after the mesh's faces).
    let mut faces = mesh.faces.clone();
    let mut first = HashSet::new();
    for (t, &fi) in w.tris.iter().zip(&w.tri_face) {
        if matches!(mesh.faces[fi as usize], Face::Quad(_)) && crossed.contains(&fi) {
            if first.insert(fi) {
                faces[fi as usize] = Face::Tri(*t);
            } else {
                faces.push(Face::Tri(*t));
            }
        }
    }
    let mut s = Splitter {
        positions: mesh.positions.clone(),
        incident: vec![Vec::new(); mesh.positions.len()],
        faces,
        done: HashMap::new(),
        made_on: Vec::new(),
    };
    for (k, f) in s.faces.iter().enumerate() {
        for &v in f.vertices() {
            s.incident[v as usize].push(k as u32);
        }
    }
    let n0 = mesh.positions.len();
    let mut folds = Vec::new();
    for (fold, line) in w.lines.iter().enumerate() {
        let mut ridge: Vec<u32> = Vec::new();
        for c in line {
            let v = s.split(c);
            if ridge.last() == Some(&v) {
                continue;
            }
            if ridge.contains(&v) {
                // Back at a vertex the line took before: it runs back along itself.
                let segment = c.segment;
                return Err(FoldError::SelfCrossing { fold, segment });
            }
            ridge.push(v);
        }
        folds.push(Fold { ridge, drawn: 0.0 });
    }
    let ring = crate::ring_of(&PolyMesh {
        positions: s.positions.clone(),
        faces: s.faces.clone(),
    });
    for f in &mut folds {
        f.ridge = joined(&f.ridge, &ring);
    }
    let n = s.positions.len();
    let mut is_new = vec![false; n];
    is_new[n0..].iter_mut().for_each(|b| *b = true);
    for f in &folds {
        for &v in &f.ridge {
            is_new[v as usize] = true;
        }
    }
    Ok(Folded {
        mesh: PolyMesh {
            positions: s.positions,
            faces: s.faces,
        },
        folds,
        is_new,
        region: vec![false; n],
        made_on: s.made_on,
    })
}

struct Splitter {
    positions: Vec<tryon_core::math::Vec3>,
    /// Triangles around each vertex.
    incident: Vec<Vec<u32>>,
    /// The mesh's faces; those on a split edge are triangles.
    faces: Vec<Face>,
    /// Per original edge, the crossings split into it so far: (t along it, vertex).
    done: HashMap<(u32, u32), Vec<(Real, u32)>>,
    /// Per added vertex, its original edge and t along it.
    made_on: Vec<(u32, u32, Real)>,
}

impl Splitter {
    /// The vertex at crossing `c`: made by splitting the part of its original edge it lies on,
    /// or the one already there.
    fn split(&mut self, c: &Crossing) -> u32 {
        if c.t <= AT_END {
            return c.a;
        }
        if c.t >= 1.0 - AT_END {
            return c.b;
        }
        let list = self.done.entry((c.a, c.b)).or_default();
        if let Some(&(_, v)) = list.iter().find(|(t, _)| (t - c.t).abs() < SAME) {
            return v;
        }
        let lo = list
            .iter()
            .filter(|(t, _)| *t < c.t)
            .max_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(c.a, |e| e.1);
        let hi = list
            .iter()
            .filter(|(t, _)| *t > c.t)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map_or(c.b, |e| e.1);
        let v = self.positions.len() as u32;
        list.push((c.t, v));
        let (xa, xb) = (self.positions[c.a as usize], self.positions[c.b as usize]);
        self.positions.push(xa + (xb - xa) * c.t);
        self.made_on.push((c.a, c.b, c.t));
        self.incident.push(Vec::new());
        self.split_edge(lo, hi, v);
        v
    }

    /// Splits every triangle on the edge (a, b) at the new vertex `v`.
    fn split_edge(&mut self, a: u32, b: u32, v: u32) {
        let on: Vec<u32> = self.incident[a as usize]
            .iter()
            .copied()
            .filter(|&f| self.faces[f as usize].vertices().contains(&b))
            .collect();
        for f in on {
            let Face::Tri(t) = self.faces[f as usize] else {
                continue; // a quad is never on a crossed edge (both its faces were crossed)
            };
            let Some(k) = (0..3).find(|&k| {
                let (p, q) = (t[k], t[(k + 1) % 3]);
                (p == a && q == b) || (p == b && q == a)
            }) else {
                continue;
            };
            let (p0, p1, p2) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            let g = self.faces.len() as u32;
            self.faces[f as usize] = Face::Tri([p0, v, p2]);
            self.faces.push(Face::Tri([v, p1, p2]));
            self.incident[p1 as usize].retain(|&x| x != f);
            self.incident[p1 as usize].push(g);
            self.incident[p2 as usize].push(g);
            self.incident[v as usize].extend([f, g]);
        }
    }
}

/// Most edges bridged between two ridge vertices that no edge joins.
const BRIDGE: usize = 6;

/// `ridge` with each pair of consecutive vertices that no edge joins (where a line starts again
/// from a corner of the mesh, through another face than it arrived in) bridged by the shortest
/// path of edges between them, when one of at most [`BRIDGE`] edges exists.
fn joined(ridge: &[u32], ring: &[Vec<u32>]) -> Vec<u32> {
    let mut out: Vec<u32> = Vec::with_capacity(ridge.len());
    for &v in ridge {
        if let Some(&u) = out.last()
            && !ring[u as usize].contains(&v)
            && let Some(path) = shortest(u, v, ring)
        {
            for &w in &path[1..path.len() - 1] {
                if !out.contains(&w) {
                    out.push(w);
                }
            }
        }
        if !out.contains(&v) {
            out.push(v);
        }
    }
    out
}

/// The vertices of a shortest path of edges from `a` to `b` (both included), if at most
/// [`BRIDGE`] edges long.
fn shortest(a: u32, b: u32, ring: &[Vec<u32>]) -> Option<Vec<u32>> {
    let mut from: HashMap<u32, u32> = HashMap::from([(a, a)]);
    let mut front = vec![a];
    for _ in 0..BRIDGE {
        let mut next = Vec::new();
        for &v in &front {
            for &u in &ring[v as usize] {
                if from.contains_key(&u) {
                    continue;
                }
                from.insert(u, v);
                if u == b {
                    let (mut path, mut at) = (vec![b], b);
                    while at != a {
                        at = from[&at];
                        path.push(at);
                    }
                    path.reverse();
                    return Some(path);
                }
                next.push(u);
            }
        }
        front = next;
    }
    None
}
