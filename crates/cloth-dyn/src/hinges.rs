//! The quadratic bending model of Bergou, Wardetzky, Harmon, Zorin and Grinspun (2006), "A Quadratic
//! Bending Model for Inextensible Surfaces". For every interior edge (x0, x1) of the triangulated
//! cloth with opposite vertices x2 and x3, the discrete mean-curvature vector of the edge's
//! stencil is `y = sum_i K_i x_i` with the cotangent weights
//! `K = (c03 + c04, c01 + c02, -c01 - c03, -c02 - c04)` of the rest triangles, and the bending
//! energy is `E = (3 B / (A0 + A1)) |y|^2 / 2` (B the bending rigidity in N m, A0, A1 the rest areas).
//! The energy is quadratic in positions: the force `f_i = -(3 B / (A0 + A1)) K_i y` is linear, its
//! Jacobian is constant, and its largest frequency is known in advance. It resists a bend by the
//! angle, unlike a flexion spring (whose length changes only with the square of a small bend), so
//! soft cloth folds broadly instead of crumpling at the grid scale.
//!
//! The model assumes a flat rest shape (isometric bending of a plane): a curved rest mesh is bent
//! towards flat. It is exact for the drape's square and for flat pattern pieces.

use tryon_core::math::{Real, Vec3};

/// One stencil: four particles and their weights, already scaled by `sqrt(3 B / (A0 + A1))`, so
/// that `y = sum_i w_i x_i` and `f_i = -w_i y`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hinge {
    pub v: [u32; 4],
    pub w: [Real; 4],
}

/// Cotangent of the angle between `a` and `b` (0 for a degenerate pair).
fn cot(a: &Vec3, b: &Vec3) -> Real {
    let s = a.cross(b).norm();
    if s <= 1e-300 { 0.0 } else { a.dot(b) / s }
}

/// The hinges of a triangle mesh at its rest positions `x` with bending rigidity `rigidity` (N m).
/// Edges with one face, and stencils with a degenerate triangle, get none.
pub fn build_hinges(x: &[Vec3], triangles: &[[u32; 3]], rigidity: Real) -> Vec<Hinge> {
    use std::collections::HashMap;
    if rigidity <= 0.0 {
        return Vec::new();
    }
    // Each edge with the vertex opposite it in each of its (at most two) triangles.
    let mut opposite: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for t in triangles {
        for k in 0..3 {
            let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            opposite.entry((a.min(b), a.max(b))).or_default().push(c);
        }
    }
    let mut edges: Vec<_> = opposite.into_iter().filter(|(_, o)| o.len() == 2).collect();
    edges.sort_unstable_by_key(|(e, _)| *e);
    edges
        .into_iter()
        .filter_map(|((i0, i1), o)| {
            let (i2, i3) = (o[0], o[1]);
            let [x0, x1, x2, x3] = [i0, i1, i2, i3].map(|i| x[i as usize]);
            let (e0, e1, e2, e3, e4) = (x1 - x0, x2 - x0, x3 - x0, x2 - x1, x3 - x1);
            let a0 = 0.5 * e0.cross(&e1).norm();
            let a1 = 0.5 * e0.cross(&e2).norm();
            if !(a0 > 1e-300 && a1 > 1e-300) {
                return None;
            }
            let (c01, c02) = (cot(&e0, &e1), cot(&e0, &e2));
            let (c03, c04) = (cot(&-e0, &e3), cot(&-e0, &e4));
            let k = [c03 + c04, c01 + c02, -c01 - c03, -c02 - c04];
            let s = (3.0 * rigidity / (a0 + a1)).sqrt();
            let w = k.map(|k| k * s);
            w.iter().all(|w| w.is_finite()).then_some(Hinge {
                v: [i0, i1, i2, i3],
                w,
            })
        })
        .collect()
}

/// The curvature vector of one hinge at positions `x`.
#[inline]
pub fn curvature(h: &Hinge, x: &[Vec3]) -> Vec3 {
    x[h.v[0] as usize] * h.w[0]
        + x[h.v[1] as usize] * h.w[1]
        + x[h.v[2] as usize] * h.w[2]
        + x[h.v[3] as usize] * h.w[3]
}

/// Adds the bending forces `-w_i y` (scaled by `scale`) of every hinge at `x` into `force`.
#[inline]
pub fn add_forces(hinges: &[Hinge], x: &[Vec3], scale: Real, force: &mut [Vec3]) {
    for h in hinges {
        let y = curvature(h, x) * scale;
        for k in 0..4 {
            force[h.v[k] as usize] -= y * h.w[k];
        }
    }
}

/// Bending energy of `x` (J).
pub fn energy(hinges: &[Hinge], x: &[Vec3]) -> Real {
    hinges
        .iter()
        .map(|h| 0.5 * curvature(h, x).norm_squared())
        .sum()
}

/// Adds each particle's Gershgorin row sum of the bending Hessian (`|w_i| sum_j |w_j|` over its
/// hinges) into `rows`.
pub fn add_row_sums(hinges: &[Hinge], rows: &mut [Real]) {
    for h in hinges {
        let total: Real = h.w.iter().map(|w| w.abs()).sum();
        for k in 0..4 {
            rows[h.v[k] as usize] += h.w[k].abs() * total;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use tryon_core::mesh::grid_xz;

    fn sheet(n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let m = grid_xz(n, n, 1.0, 1.0, 0.0);
        let (t, _) = m.triangulate();
        (m.positions, t)
    }

    fn forces(h: &[Hinge], x: &[Vec3]) -> Vec<Vec3> {
        let mut f = vec![Vec3::zeros(); x.len()];
        add_forces(h, x, 1.0, &mut f);
        f
    }

    #[test]
    fn a_flat_sheet_has_no_bending_force_in_any_placement() {
        let (x, t) = sheet(5);
        let h = build_hinges(&x, &t, 1e-3);
        // One hinge per interior edge of the triangulation.
        let interior = {
            let mut e = std::collections::HashMap::new();
            for tri in &t {
                for k in 0..3 {
                    let (a, b) = (tri[k], tri[(k + 1) % 3]);
                    *e.entry((a.min(b), a.max(b))).or_insert(0) += 1;
                }
            }
            e.values().filter(|&&c| c == 2).count()
        };
        assert_eq!(h.len(), interior);
        let r = tryon_core::math::UnitQuat::from_euler_angles(0.3, -1.1, 0.7);
        let moved: Vec<Vec3> = x
            .iter()
            .map(|p| r * p + Vec3::new(0.2, -3.0, 1.0))
            .collect();
        for f in forces(&h, &moved) {
            assert!(f.norm() < 1e-12, "{f:?}");
        }
    }

    #[test]
    fn a_folded_sheet_is_pushed_back_flat_and_costs_energy() {
        let (x, t) = sheet(4);
        let h = build_hinges(&x, &t, 1e-3);
        // Fold along x = 0: the half x > 0 rotated up by 30 degrees about the z axis.
        let bent: Vec<Vec3> = x
            .iter()
            .map(|p| {
                if p.x > 1e-9 {
                    let a: Real = 30.0_f64.to_radians();
                    Vec3::new(p.x * a.cos(), p.x * a.sin(), p.z)
                } else {
                    *p
                }
            })
            .collect();
        assert!(energy(&h, &bent) > 0.0);
        let f = forces(&h, &bent);
        // Across the fold the raised side is pushed down and the crease up, towards flat.
        let at = |px: Real| {
            x.iter()
                .position(|p| (p.x - px).abs() < 1e-9 && p.z.abs() < 1e-9)
                .unwrap()
        };
        assert!(f[at(0.25)].y < 0.0, "{:?}", f[at(0.25)]);
        assert!(f[at(0.0)].y > 0.0, "{:?}", f[at(0.0)]);
    }

    proptest! {
        /// The force is minus the energy's gradient (finite differences), sums to zero and has no
        /// torque, for any shape of the sheet.
        #[test]
        fn force_is_the_energy_gradient_and_keeps_momenta(
            seed in proptest::collection::vec(-0.05f64..0.05, 3 * 16),
        ) {
            let (x0, t) = sheet(3);
            let h = build_hinges(&x0, &t, 2e-3);
            let x: Vec<Vec3> = x0
                .iter()
                .enumerate()
                .map(|(i, p)| p + Vec3::new(seed[3 * i], seed[3 * i + 1], seed[3 * i + 2]))
                .collect();
            let f = forces(&h, &x);
            let sum: Vec3 = f.iter().sum();
            let torque: Vec3 = x.iter().zip(&f).map(|(p, f)| p.cross(f)).sum();
            let scale = f.iter().map(|f| f.norm()).fold(1e-12, Real::max);
            prop_assert!(sum.norm() < 1e-12 * scale.max(1.0));
            prop_assert!(torque.norm() < 1e-12 * scale.max(1.0));
            let eps = 1e-6;
            for i in 0..x.len() {
                for d in 0..3 {
                    let mut xp = x.clone();
                    let mut xm = x.clone();
                    xp[i][d] += eps;
                    xm[i][d] -= eps;
                    let g = (energy(&h, &xp) - energy(&h, &xm)) / (2.0 * eps);
                    prop_assert!((f[i][d] + g).abs() < 1e-6 * scale.max(1e-3), "{i} {d}: {} vs {}", f[i][d], -g);
                }
            }
        }
    }
}
