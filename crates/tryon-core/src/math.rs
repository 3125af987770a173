//! Scalar and vector aliases (one nalgebra version, the one parry3d-f64 uses) and small geometric helpers.

/// The scalar used throughout the per-frame pipeline.
pub type Real = f64;
/// A 3-vector of `Real` (positions, velocities, forces).
pub type Vec3 = nalgebra::Vector3<Real>;
/// A unit quaternion of `Real`.
pub type UnitQuat = nalgebra::UnitQuaternion<Real>;
/// A 3x3 matrix of `Real` (rotations, skinning).
pub type Mat3 = nalgebra::Matrix3<Real>;
/// A rigid transform (rotation then translation).
pub type Iso3 = nalgebra::Isometry3<Real>;

/// Gravity of Earth, m/s^2, pointing down the Y axis (the project is Y-up).
pub const GRAVITY: Vec3 = Vec3::new(0.0, -9.81, 0.0);

/// True when all three components are finite.
#[inline]
pub fn is_finite(v: &Vec3) -> bool {
    v.x.is_finite() && v.y.is_finite() && v.z.is_finite()
}

/// Unnormalised normal of triangle (a, b, c): twice its area times the unit normal.
#[inline]
pub fn triangle_area_normal(a: &Vec3, b: &Vec3, c: &Vec3) -> Vec3 {
    (b - a).cross(&(c - a))
}

/// Closest point on triangle (a, b, c) to p, with its barycentric coordinates (Ericson, RTCD 5.1.5).
pub fn closest_point_on_triangle(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> (Vec3, [Real; 3]) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + ab * v, [1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + ac * w, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * w, [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// Area-weighted unit vertex normals of a triangle mesh into `out` (resized); a vertex with no
/// area around it gets +y.
/// `v` scaled to unit length, or `None` when its length is not above `min_len` (like nalgebra's
/// `try_normalize`, but one division instead of three: hot loops normalise millions of vectors).
#[inline]
pub fn unit(v: &Vec3, min_len: Real) -> Option<Vec3> {
    let l2 = v.norm_squared();
    (l2 > min_len * min_len).then(|| v * (1.0 / l2.sqrt()))
}

pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]], out: &mut Vec<Vec3>) {
    out.clear();
    out.resize(positions.len(), Vec3::zeros());
    for t in triangles {
        let [a, b, c] = t.map(|v| v as usize);
        let n = (positions[b] - positions[a]).cross(&(positions[c] - positions[a]));
        out[a] += n;
        out[b] += n;
        out[c] += n;
    }
    for n in out.iter_mut() {
        *n = unit(n, 1e-30).unwrap_or(Vec3::y());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_point_regions() {
        let a = Vec3::new(0.0, 0.0, 0.0);
        let b = Vec3::new(1.0, 0.0, 0.0);
        let c = Vec3::new(0.0, 1.0, 0.0);
        let (q, w) = closest_point_on_triangle(&Vec3::new(0.25, 0.25, 2.0), &a, &b, &c);
        assert!((q - Vec3::new(0.25, 0.25, 0.0)).norm() < 1e-15);
        assert!((w[0] - 0.5).abs() < 1e-15 && (w[1] - 0.25).abs() < 1e-15);
        let (q, w) = closest_point_on_triangle(&Vec3::new(-1.0, -1.0, 0.0), &a, &b, &c);
        assert_eq!(q, a);
        assert_eq!(w, [1.0, 0.0, 0.0]);
        let (q, _) = closest_point_on_triangle(&Vec3::new(1.0, 1.0, 0.0), &a, &b, &c);
        assert!((q - Vec3::new(0.5, 0.5, 0.0)).norm() < 1e-15);
    }
}
