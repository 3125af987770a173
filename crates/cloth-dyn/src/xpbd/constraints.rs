//! The XPBD constraints of the cloth: distance on every edge of the triangulated mesh (stretch and,
//! through the diagonals, shear) and the dihedral angle across every interior edge (bending toward
//! the rest shape's angle, so a modelled garment keeps its folds and curves), with their greedy
//! colouring: no two constraints of one colour share a particle, so a colour can be solved in any
//! order, or in parallel, with the same result.

use tryon_core::math::{Real, Vec3};

/// A distance constraint between two particles.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Edge {
    pub i: u32,
    pub j: u32,
    pub rest: Real,
}

/// A dihedral-angle constraint: triangles (a, b, c) and (b, a, d) share the edge a-b; `c` and `d`
/// are the opposite vertices.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Hinge {
    pub v: [u32; 4],
    pub rest_angle: Real,
    /// Its compliance as a multiple of the solver's bending compliance.
    pub compliance_scale: Real,
}

/// The signed dihedral angle of a hinge at positions `p` = [a, b, c, d] (0 when flat; positive
/// when the wings fold toward the first triangle's normal), and its gradient with respect to
/// a, b, c and d (Bridson, Marino and Fedkiw 2003's formulas), or `None` when a triangle is
/// degenerate.
pub fn dihedral(p: [Vec3; 4]) -> Option<(Real, [Vec3; 4])> {
    let [a, b, c, d] = p;
    let e = b - a;
    let el2 = e.norm_squared();
    let n1 = (c - a).cross(&(c - b));
    let n2 = (d - b).cross(&(d - a));
    let (l1, l2) = (n1.norm_squared(), n2.norm_squared());
    if !(el2 > 1e-24 && l1 > 1e-24 && l2 > 1e-24) {
        return None;
    }
    // atan2 is unchanged by a positive factor on both arguments, so the normals need not be unit
    // and the edge is divided out once: one square root per hinge.
    let el = el2.sqrt();
    let angle = atan2(n1.cross(&n2).dot(&e) / el, n1.dot(&n2));
    // Gradients of the angle: the wings move along their normals, the edge's ends share the rest.
    let (k1, k2) = (1.0 / l1, 1.0 / l2);
    let gc = n1 * (el * k1);
    let gd = n2 * (el * k2);
    let ie = 1.0 / el;
    let ga = n1 * ((c - b).dot(&e) * ie * k1) + n2 * ((d - b).dot(&e) * ie * k2);
    let gb = -(n1 * ((c - a).dot(&e) * ie * k1) + n2 * ((d - a).dot(&e) * ie * k2));
    Some((angle, [-ga, -gb, -gc, -gd]))
}

/// The moves of a hinge's four particles (at `p`, inverse masses `w`) that satisfy its angle
/// constraint with compliance `alpha` (already over the step squared); none for a degenerate one.
pub fn hinge_move(p: [Vec3; 4], w: [Real; 4], hg: &Hinge, alpha: Real) -> [Vec3; 4] {
    let zero = [Vec3::zeros(); 4];
    let Some((angle, grad)) = dihedral(p) else {
        return zero;
    };
    let mut c = angle - hg.rest_angle;
    if c > std::f64::consts::PI {
        c -= 2.0 * std::f64::consts::PI;
    } else if c < -std::f64::consts::PI {
        c += 2.0 * std::f64::consts::PI;
    }
    let denom: Real = (0..4).map(|k| w[k] * grad[k].norm_squared()).sum();
    let a = alpha * hg.compliance_scale;
    if !(denom + a > 1e-20) {
        return zero;
    }
    let dl = -c / (denom + a);
    [0, 1, 2, 3].map(|k| grad[k] * (w[k] * dl))
}

/// `atan2(y, x)` to about 3e-9 rad, without a library call (the dihedral constraints take most of
/// an XPBD substep, and libm's atan2 was a third of them): the ratio is reduced to [0, 1] by
/// symmetry, to [0, tan(pi/12)] by atan(t) = pi/6 + atan((t sqrt3 - 1) / (t + sqrt3)), and there
/// the Taylor series to t^11 is within 3e-9 of atan.
pub fn atan2(y: Real, x: Real) -> Real {
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_6, PI};
    let (ax, ay) = (x.abs(), y.abs());
    if !(ax > 0.0 || ay > 0.0) {
        return if x.is_nan() || y.is_nan() {
            Real::NAN
        } else {
            0.0
        };
    }
    let (num, den, swap) = if ay > ax {
        (ax, ay, true)
    } else {
        (ay, ax, false)
    };
    let mut t = num / den;
    let mut base = 0.0;
    const TAN_PI_12: Real = 0.267_949_192_431_122_7;
    const SQRT3: Real = 1.732_050_807_568_877_2;
    if t > TAN_PI_12 {
        t = (t * SQRT3 - 1.0) / (t + SQRT3);
        base = FRAC_PI_6;
    }
    let t2 = t * t;
    let series = t
        * (1.0
            + t2 * (-1.0 / 3.0
                + t2 * (1.0 / 5.0 + t2 * (-1.0 / 7.0 + t2 * (1.0 / 9.0 + t2 * (-1.0 / 11.0))))));
    let mut r = base + series;
    if swap {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y < 0.0 { -r } else { r }
}

/// Greedy colouring of constraints over particles: returns the constraints' order (colour by
/// colour) and each colour's range in it. Deterministic: constraints are taken in index order.
pub fn colour(constraints: &[&[u32]], particles: usize) -> (Vec<u32>, Vec<std::ops::Range<usize>>) {
    let mut colour_of = vec![0u32; constraints.len()];
    // Per particle, the colours already used there (a bit set; more than 64 colours spill over).
    let mut used: Vec<u64> = vec![0; particles];
    let mut spill: Vec<Vec<u32>> = vec![Vec::new(); particles];
    let mut colours = 0u32;
    for (k, c) in constraints.iter().enumerate() {
        let mut taken = 0u64;
        for &v in c.iter() {
            taken |= used[v as usize];
        }
        let mut col = (!taken).trailing_zeros();
        if col >= 64 {
            col = 64;
            while c.iter().any(|&v| spill[v as usize].contains(&col)) {
                col += 1;
            }
        }
        for &v in c.iter() {
            if col < 64 {
                used[v as usize] |= 1 << col;
            } else {
                spill[v as usize].push(col);
            }
        }
        colour_of[k] = col;
        colours = colours.max(col + 1);
    }
    let mut order: Vec<u32> = (0..constraints.len() as u32).collect();
    order.sort_by_key(|&k| (colour_of[k as usize], k));
    let mut ranges = Vec::with_capacity(colours as usize);
    let mut start = 0;
    for col in 0..colours {
        let end = start + colour_of.iter().filter(|&&c| c == col).count();
        ranges.push(start..end);
        start = end;
    }
    (order, ranges)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dihedral_gradient_matches_finite_differences_and_the_angle_is_signed() {
        let p = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.1, 0.0),
            Vec3::new(0.4, 0.9, 0.2),
            Vec3::new(0.6, -0.8, 0.5),
        ];
        let (angle, grad) = dihedral(p).unwrap();
        let h = 1e-6;
        for v in 0..4 {
            for axis in 0..3 {
                let (mut q, mut r) = (p, p);
                q[v][axis] += h;
                r[v][axis] -= h;
                let fd = (dihedral(q).unwrap().0 - dihedral(r).unwrap().0) / (2.0 * h);
                assert!(
                    (fd - grad[v][axis]).abs() < 1e-6,
                    "vertex {v} axis {axis}: {fd} vs {}",
                    grad[v][axis]
                );
            }
        }
        // Flat wings: angle 0; folding d the other way flips the sign.
        let mut flat = p;
        flat[2].z = 0.0;
        flat[3].z = 0.0;
        assert!(dihedral(flat).unwrap().0.abs() < 1e-12);
        let mut other = p;
        other[3].z = -0.5;
        assert!(dihedral(other).unwrap().0.signum() != angle.signum());
        let degenerate = [p[0], p[1], p[0], p[3]];
        assert!(dihedral(degenerate).is_none());
    }

    #[test]
    fn the_polynomial_atan2_matches_the_library_all_round() {
        let mut worst: Real = 0.0;
        for k in 0..20_000 {
            let a = -3.2 + 6.4 * k as Real / 20_000.0;
            for r in [1e-9, 0.37, 1.0, 52.0] {
                let (y, x) = (r * a.sin(), r * a.cos());
                worst = worst.max((atan2(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 1e-8, "worst error {worst}");
        for (y, x) in [
            (0.0, 1.0),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (0.0, 0.0),
            (-0.0, -2.0),
        ] {
            let (want, got): (Real, Real) = (Real::atan2(y, x), atan2(y, x));
            assert!(
                (want - got).abs() < 1e-12 || (want.abs() - got.abs()).abs() < 1e-12,
                "{y}, {x}"
            );
        }
        assert!(atan2(Real::NAN, 1.0).is_nan() && atan2(1.0, Real::NAN).is_nan());
    }

    #[test]
    fn no_two_constraints_of_a_colour_share_a_particle() {
        // A strip of triangles: edges 0-1, 1-2, ..., and the diagonals.
        let edges: Vec<[u32; 2]> = (0..20u32).flat_map(|i| [[i, i + 1], [i, i + 2]]).collect();
        let refs: Vec<&[u32]> = edges.iter().map(|e| &e[..]).collect();
        let (order, ranges) = colour(&refs, 23);
        assert_eq!(order.len(), edges.len());
        assert_eq!(ranges.last().unwrap().end, edges.len());
        for r in &ranges {
            let mut seen = std::collections::HashSet::new();
            for &k in &order[r.clone()] {
                for &v in &edges[k as usize] {
                    assert!(seen.insert(v), "particle {v} twice in one colour");
                }
            }
        }
        assert!(ranges.len() <= 5, "{} colours for a strip", ranges.len());
    }
}
