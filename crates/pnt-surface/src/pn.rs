//! One PN triangle: ten cubic Bezier control points and six quadratic normal coefficients
//! (Vlachos et al. 2001, section 3).

use tryon_core::math::{Real, Vec3, unit};

/// The geometry and normal coefficients of one PN triangle with corners 1, 2, 3.
///
/// Positions: `b(w, u, v) = b300 w^3 + b030 u^3 + b003 v^3 + 3 b210 w^2 u + 3 b120 w u^2 +
/// 3 b201 w^2 v + 3 b021 u^2 v + 3 b102 w v^2 + 3 b012 u v^2 + 6 b111 w u v`, with `w`, `u`, `v` the
/// barycentric weights of corners 1, 2, 3. Normals: `n = n200 w^2 + n020 u^2 + n002 v^2 + n110 w u +
/// n011 u v + n101 w v`, normalised.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PnPatch {
    /// b300, b030, b003, b210, b120, b201, b021, b102, b012, b111.
    pub b: [Vec3; 10],
    /// n200, n020, n002, n110, n011, n101.
    pub n: [Vec3; 6],
}

/// Control point next to corner `pi` toward `pj`: `(2 Pi + Pj - w_ij Ni) / 3`, `w_ij = (Pj - Pi) . Ni`.
#[inline]
fn edge_point(pi: &Vec3, pj: &Vec3, ni: &Vec3) -> Vec3 {
    let w = (pj - pi).dot(ni);
    (pi * 2.0 + pj - ni * w) * (1.0 / 3.0)
}

/// Mid-edge normal: `Ni + Nj - v_ij (Pj - Pi)`, `v_ij = 2 (Pj - Pi).(Ni + Nj) / |Pj - Pi|^2`,
/// normalised (the average of the corners' normals on a degenerate edge).
#[inline]
fn edge_normal(pi: &Vec3, pj: &Vec3, ni: &Vec3, nj: &Vec3) -> Vec3 {
    let d = pj - pi;
    let l2 = d.norm_squared();
    let s = ni + nj;
    let h = if l2 > 1e-30 {
        s - d * (2.0 * d.dot(&s) / l2)
    } else {
        s
    };
    unit(&h, 1e-30).or_else(|| unit(&s, 1e-30)).unwrap_or(*ni)
}

impl PnPatch {
    /// The patch of a triangle from its corner positions and unit corner normals.
    pub fn new(p: [Vec3; 3], n: [Vec3; 3]) -> Self {
        let [p1, p2, p3] = p;
        let [n1, n2, n3] = n;
        let b210 = edge_point(&p1, &p2, &n1);
        let b120 = edge_point(&p2, &p1, &n2);
        let b021 = edge_point(&p2, &p3, &n2);
        let b012 = edge_point(&p3, &p2, &n3);
        let b102 = edge_point(&p3, &p1, &n3);
        let b201 = edge_point(&p1, &p3, &n1);
        let e = (b210 + b120 + b021 + b012 + b102 + b201) * (1.0 / 6.0);
        let v = (p1 + p2 + p3) * (1.0 / 3.0);
        let b111 = e + (e - v) * 0.5;
        PnPatch {
            b: [p1, p2, p3, b210, b120, b201, b021, b102, b012, b111],
            n: [
                n1,
                n2,
                n3,
                edge_normal(&p1, &p2, &n1, &n2),
                edge_normal(&p2, &p3, &n2, &n3),
                edge_normal(&p3, &p1, &n3, &n1),
            ],
        }
    }

    /// Position at barycentric weights `(w, u, v)` of corners 1, 2, 3.
    #[inline]
    pub fn position(&self, bary: [Real; 3]) -> Vec3 {
        let [w, u, v] = bary;
        let b = &self.b;
        let (w2, u2, v2) = (w * w, u * u, v * v);
        b[0] * (w2 * w)
            + b[1] * (u2 * u)
            + b[2] * (v2 * v)
            + b[3] * (3.0 * w2 * u)
            + b[4] * (3.0 * w * u2)
            + b[5] * (3.0 * w2 * v)
            + b[6] * (3.0 * u2 * v)
            + b[7] * (3.0 * w * v2)
            + b[8] * (3.0 * u * v2)
            + b[9] * (6.0 * w * u * v)
    }

    /// Unit normal at barycentric weights `(w, u, v)` (the corner normals' mean where the quadratic
    /// field vanishes).
    #[inline]
    pub fn normal(&self, bary: [Real; 3]) -> Vec3 {
        let [w, u, v] = bary;
        let n = &self.n;
        let m = n[0] * (w * w)
            + n[1] * (u * u)
            + n[2] * (v * v)
            + n[3] * (w * u)
            + n[4] * (u * v)
            + n[5] * (w * v);
        unit(&m, 1e-30)
            .or_else(|| unit(&(n[0] * w + n[1] * u + n[2] * v), 1e-30))
            .unwrap_or(n[0])
    }
}
