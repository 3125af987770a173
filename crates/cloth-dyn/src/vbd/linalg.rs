//! The small dense algebra of VBD's Newton steps.

use tryon_core::math::{Mat3, Real, Vec3, is_finite};

/// Adds `k d d^T` to a symmetric 3 x 3 matrix kept as its upper triangle `o` (xx, xy, xz, yy,
/// yz, zz).
#[inline]
pub(super) fn add_outer(o: &mut [Real; 6], k: Real, d: &Vec3) {
    o[0] += k * d.x * d.x;
    o[1] += k * d.x * d.y;
    o[2] += k * d.x * d.z;
    o[3] += k * d.y * d.y;
    o[4] += k * d.y * d.z;
    o[5] += k * d.z * d.z;
}

/// `h^-1 f` for a symmetric positive definite 3 x 3 `h` (Cramer's rule on its upper triangle);
/// zero where `h` is not positive definite (Sylvester's criterion) or the result is not finite.
/// It replaced nalgebra's general Cholesky, which runs once per vertex per sweep: the drape's
/// cloth step fell by 8% (`cargo bench --bench solvers`).
pub(super) fn solve_spd3(h: &Mat3, f: &Vec3) -> Vec3 {
    let (a, b, c) = (h[(0, 0)], h[(0, 1)], h[(0, 2)]);
    let (d, e, g) = (h[(1, 1)], h[(1, 2)], h[(2, 2)]);
    // Cofactors of the symmetric matrix [a b c; b d e; c e g].
    let (ca, cb, cc) = (d * g - e * e, c * e - b * g, b * e - c * d);
    let (cd, ce, cg) = (a * g - c * c, b * c - a * e, a * d - b * b);
    let det = a * ca + b * cb + c * cc;
    if !(a > 0.0 && cg > 0.0 && det > 0.0) {
        return Vec3::zeros();
    }
    let x = Vec3::new(
        ca * f.x + cb * f.y + cc * f.z,
        cb * f.x + cd * f.y + ce * f.z,
        cc * f.x + ce * f.y + cg * f.z,
    ) / det;
    if is_finite(&x) { x } else { Vec3::zeros() }
}
