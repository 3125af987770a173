//! Bending toward the rest dihedral angles inside VBD's vertex steps. Every interior edge of the
//! triangulated cloth is a hinge with the energy `k/2 (theta - theta0)^2`, theta the signed angle
//! between its two triangles and theta0 that of the modelled (rest) shape, so a curved garment
//! keeps its curves and a fold keeps its side. The stiffness is the discrete-shells scaling
//! (Grinspun, Hirani, Desbrun and Schroeder 2003) of a bending rigidity `B` (N m):
//! `k = 3 B |e|^2 / (A0 + A1)`, with `|e|` the hinge edge's rest length and `A0`, `A1` its
//! triangles' rest areas, so the energy per area does not depend on the mesh's resolution. Each
//! vertex's Newton step takes the hinge's force on it, `-k (theta - theta0) d theta / d x_i`, and
//! the Gauss-Newton part of its Hessian, `k g g^T` with `g = d theta / d x_i` (positive
//! semi-definite; the angle's own curvature term is left out, as the VBD paper does).
//!
//! The angle is linearised about the step's start: at the start each hinge's angle and gradient
//! are found once (`begin`), and during the sweeps `theta = theta_start + sum_j g_j . (x_j -
//! x_j,start)`, kept up to date as vertices move (`moved`, `refresh`) instead of the exact angle
//! (two cross products, normalisations and an arctangent) at each of a hinge's four vertices in
//! every sweep. The exact evaluation took makehuman-dress-walk's cloth step from 29 to 96 ms a
//! frame; a step moves a vertex well under a millimetre against hinges of centimetres, where the
//! linear term is the angle to first order.
//!
//! Flexion springs (a spring across each pair of faces, P1's bending) encode the rest angle only
//! through a distance, which is the same for a fold and its mirror and changes only with the
//! square of a small bend.

use super::pairs::ALONE;
use crate::xpbd::constraints::dihedral;
use std::collections::HashMap;
use std::f64::consts::PI;
use tryon_core::math::{Real, Vec3};

/// Hinges with a triangle whose height over the hinge edge is under this share of the edge's
/// length are left out. A sliver's normal turns by a radian when its far vertex moves by its
/// height (0.5 mm on the hard case's sheet), where the angle linearised over a step means
/// nothing, and the discrete-shells stiffness grows as its area shrinks: with them the sliver
/// sheet of `vbd/tests.rs` stretched 1.61. A sliver's orientation is held by its pair
/// (`pairs.rs`). A regular grid's triangles have 0.5 (over a diagonal) and 1 (over a side).
pub const SLIVER: Real = 0.2;

/// One hinge: triangles (a, b, c) and (b, a, d) sharing the edge a-b, its rest angle and stiffness.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hinge {
    pub v: [u32; 4],
    pub rest: Real,
    pub k: Real,
}

/// The hinges of a cloth and, per vertex, the hinges it belongs to and its place in each (CSR).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hinges {
    pub hinges: Vec<Hinge>,
    offsets: Vec<u32>,
    refs: Vec<(u32, u8)>,
    /// Per hinge at the step's start: its angle less the rest angle, and the angle's gradient.
    start: Vec<(Real, [Vec3; 4])>,
    /// Per hinge, its linearised angle less the rest angle at the current positions.
    now: Vec<Real>,
}

impl Hinges {
    /// The hinges of `triangles` at rest positions `x` with bending rigidity `rigidity` (N m);
    /// none when `rigidity` is 0. Hinges with a degenerate rest triangle are left out.
    pub fn new(x: &[Vec3], triangles: &[[u32; 3]], rigidity: Real) -> Self {
        let mut hinges = Vec::new();
        if rigidity > 0.0 {
            for v in hinge_stencils(triangles) {
                let p = v.map(|i| x[i as usize]);
                let Some((rest, _)) = dihedral(p) else {
                    continue;
                };
                let e2 = (p[1] - p[0]).norm_squared();
                let area = |c: Vec3| 0.5 * (p[1] - p[0]).cross(&(c - p[0])).norm();
                let (a0, a1) = (area(p[2]), area(p[3]));
                // A triangle's height over the edge is 2 A / |e|; under SLIVER |e| it is a sliver.
                if a0.min(a1) < 0.5 * SLIVER * e2 {
                    continue;
                }
                let k = 3.0 * rigidity * e2 / (a0 + a1);
                if k.is_finite() {
                    hinges.push(Hinge { v, rest, k });
                }
            }
        }
        let mut lists: Vec<Vec<(u32, u8)>> = vec![Vec::new(); x.len()];
        for (h, hg) in hinges.iter().enumerate() {
            for (role, &v) in hg.v.iter().enumerate() {
                lists[v as usize].push((h as u32, role as u8));
            }
        }
        let mut offsets = vec![0u32];
        let mut refs = Vec::new();
        for l in lists {
            refs.extend(l);
            offsets.push(refs.len() as u32);
        }
        Hinges {
            start: vec![(0.0, [Vec3::zeros(); 4]); hinges.len()],
            now: vec![0.0; hinges.len()],
            hinges,
            offsets,
            refs,
        }
    }

    /// Whether there is any hinge.
    pub fn is_empty(&self) -> bool {
        self.hinges.is_empty()
    }

    /// Each hinge's angle and gradient at the step's start `x` (a degenerate hinge exerts
    /// nothing in this step).
    pub fn begin(&mut self, x: &[Vec3]) {
        for ((s, now), hg) in self.start.iter_mut().zip(&mut self.now).zip(&self.hinges) {
            *s = dihedral(hg.v.map(|k| x[k as usize]))
                .map_or((0.0, [Vec3::zeros(); 4]), |(a, g)| (wrap(a - hg.rest), g));
            *now = s.0;
        }
    }

    /// Vertex `i` moved by `dx`: the linearised angles of its hinges follow.
    pub fn moved(&mut self, i: usize, dx: &Vec3) {
        for &(h, role) in &self.refs[self.offsets[i] as usize..self.offsets[i + 1] as usize] {
            self.now[h as usize] += self.start[h as usize].1[role as usize].dot(dx);
        }
    }

    /// The linearised angles from scratch at positions `x` (the step started at `x0`), after
    /// moves `moved` did not see (the tethers' projection).
    pub fn refresh(&mut self, x: &[Vec3], x0: &[Vec3]) {
        for ((now, (c0, grad)), hg) in self.now.iter_mut().zip(&self.start).zip(&self.hinges) {
            *now = *c0;
            for (g, &v) in grad.iter().zip(&hg.v) {
                *now += g.dot(&(x[v as usize] - x0[v as usize]));
            }
        }
    }

    /// The hinges' force on vertex `i` at the current positions, added to `f`, and their
    /// Gauss-Newton Hessian on it, added to the symmetric outer part `o` (xx, xy, xz, yy, yz, zz).
    pub fn add(&self, i: usize, f: &mut Vec3, o: &mut [Real; 6]) {
        if self.is_empty() {
            return;
        }
        for &(h, role) in &self.refs[self.offsets[i] as usize..self.offsets[i + 1] as usize] {
            let hg = &self.hinges[h as usize];
            let g = self.start[h as usize].1[role as usize];
            *f -= g * (hg.k * self.now[h as usize]);
            super::add_outer(o, hg.k, &g);
        }
    }

    /// Adds to each block's neighbours (for the colouring) the blocks of every vertex sharing a
    /// hinge with one of its members: a hinge's four vertices must not be stepped at once.
    pub fn add_neighbours(&self, blocks: &[[u32; 2]], neighbours: &mut [Vec<u32>]) {
        let stencils: Vec<[u32; 4]> = self.hinges.iter().map(|h| h.v).collect();
        add_stencil_neighbours(&stencils, blocks, neighbours);
    }
}

/// Adds to each block's neighbours the blocks of the other vertices of every stencil one of its
/// members is in (a stencil's vertices must not be stepped at once; a repeated index is allowed).
pub fn add_stencil_neighbours(
    stencils: &[[u32; 4]],
    blocks: &[[u32; 2]],
    neighbours: &mut [Vec<u32>],
) {
    if stencils.is_empty() {
        return;
    }
    let vertices = blocks.iter().flatten().filter(|&&v| v != ALONE).count();
    let mut block_of = vec![0u32; vertices];
    for (b, members) in blocks.iter().enumerate() {
        for &v in members.iter().filter(|&&v| v != ALONE) {
            block_of[v as usize] = b as u32;
        }
    }
    for st in stencils {
        for &a in st {
            for &b in st {
                let (ba, bb) = (block_of[a as usize], block_of[b as usize]);
                if ba != bb {
                    neighbours[ba as usize].push(bb);
                }
            }
        }
    }
    for nb in neighbours.iter_mut() {
        nb.sort_unstable();
        nb.dedup();
    }
}

/// An angle difference brought into (-pi, pi].
fn wrap(a: Real) -> Real {
    if a > PI {
        a - 2.0 * PI
    } else if a <= -PI {
        a + 2.0 * PI
    } else {
        a
    }
}

/// The interior edges' stencils `[a, b, c, d]`: the edge a-b in the first triangle's winding and
/// the vertices opposite it in the first and second triangle. Edges with more than two triangles
/// take the first two.
fn hinge_stencils(triangles: &[[u32; 3]]) -> Vec<[u32; 4]> {
    let mut first: HashMap<(u32, u32), ([u32; 3], bool)> = HashMap::new();
    let mut out = Vec::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            match first.get_mut(&(a.min(b), a.max(b))) {
                None => {
                    first.insert((a.min(b), a.max(b)), ([a, b, c], false));
                }
                Some((s, used)) if !*used => {
                    *used = true;
                    out.push([s[0], s[1], s[2], c]);
                }
                Some(_) => {}
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles folded along the x axis by `angle` (rad) about it.
    fn folded(angle: Real) -> Vec<Vec3> {
        vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.5, 0.0, 1.0),
            Vec3::new(0.5, -angle.sin(), -angle.cos()),
        ]
    }

    #[test]
    fn a_hinge_at_its_rest_angle_exerts_nothing_and_a_bent_one_pushes_back() {
        let tris = [[0, 1, 2], [1, 0, 3]];
        let h = Hinges::new(&folded(0.4), &tris, 1e-3);
        assert_eq!(h.hinges.len(), 1);
        let mut h = h;
        let mut f = Vec3::zeros();
        let mut o = [0.0; 6];
        h.begin(&folded(0.4));
        h.add(3, &mut f, &mut o);
        assert!(f.norm() < 1e-12, "force at rest {f}");
        // Bend the wing further: the force on it must undo the bend (do work against it), both
        // when the step starts bent and when the bend happens within the step.
        let (x0, x1) = (folded(0.4), folded(0.6));
        for start in [&x1, &x0] {
            h.begin(start);
            h.refresh(&x1, start);
            let mut f = Vec3::zeros();
            h.add(3, &mut f, &mut o);
            assert!(
                f.dot(&(x0[3] - x1[3])) > 0.0,
                "force {f} does not undo the bend"
            );
        }
        assert!(o[0] + o[3] + o[5] > 0.0);
    }

    #[test]
    fn the_linearised_angle_matches_the_exact_one_for_a_small_move() {
        // From a 0.4 rad fold, move the wing by 1 mm of a unit hinge: the force of the linearised
        // angle is within 0.1% of the force of the exact one.
        let tris = [[0, 1, 2], [1, 0, 3]];
        let mut h = Hinges::new(&folded(0.4), &tris, 1.0);
        let (x0, x1) = (folded(0.7), folded(0.701));
        let force = |h: &mut Hinges, start: &[Vec3], incremental: bool| {
            h.begin(start);
            if incremental {
                h.moved(3, &(x1[3] - start[3]));
            } else {
                h.refresh(&x1, start);
            }
            let (mut f, mut o) = (Vec3::zeros(), [0.0; 6]);
            h.add(3, &mut f, &mut o);
            f
        };
        let exact = force(&mut h, &x1, false);
        for incremental in [false, true] {
            let lin = force(&mut h, &x0, incremental);
            assert!(
                (lin - exact).norm() < 1e-3 * exact.norm(),
                "{lin} vs {exact}"
            );
        }
    }

    #[test]
    fn a_sliver_gets_no_hinge() {
        let mut x = folded(0.3);
        x[3] = Vec3::new(0.5, -0.01, -0.1);
        assert!(Hinges::new(&x, &[[0, 1, 2], [1, 0, 3]], 1.0).is_empty());
        x[3] = Vec3::new(0.5, -0.01, -0.3);
        assert!(!Hinges::new(&x, &[[0, 1, 2], [1, 0, 3]], 1.0).is_empty());
    }

    #[test]
    fn the_stiffness_follows_the_discrete_shells_scaling() {
        // Edge length 1, both triangles of area 1/2: k = 3 B.
        let h = Hinges::new(&folded(0.0), &[[0, 1, 2], [1, 0, 3]], 2.0);
        assert!((h.hinges[0].k - 6.0).abs() < 1e-9);
        assert!(Hinges::new(&folded(0.0), &[[0, 1, 2], [1, 0, 3]], 0.0).is_empty());
    }

    #[test]
    fn hinge_vertices_become_neighbours_for_the_colouring() {
        let h = Hinges::new(&folded(0.3), &[[0, 1, 2], [1, 0, 3]], 1.0);
        let blocks: Vec<[u32; 2]> = (0..4).map(|i| [i, ALONE]).collect();
        let mut nb = vec![Vec::new(); 4];
        h.add_neighbours(&blocks, &mut nb);
        assert_eq!(nb[2], vec![0, 1, 3]);
        assert_eq!(nb[3], vec![0, 1, 2]);
    }
}
