//! The self-contact energy seen from one vertex, for a block solver: each stencil closer than
//! the thickness pushes apart by a quadratic penalty `k/2 (thickness - |d|)^2` on the offset
//! `d = sum w_k x_k` between the primitives' nearest points (found again at each evaluation), and rubs by IPC's lagged friction on the relative tangential motion since
//! detection, bounded by the normal force detection saw.

use super::SelfContacts;
use tryon_core::math::{Mat3, Real, Vec3};

impl SelfContacts {
    /// Adds vertex `i`'s share of the self-contact energy at positions `x` to its force `f` and
    /// Hessian `hess` (made positive semi-definite); `k` is its contact penalty (N/m) and `eps`
    /// the slip (m) below which friction sticks.
    pub fn add(&self, i: usize, x: &[Vec3], (k, eps): (Real, Real), f: &mut Vec3, hess: &mut Mat3) {
        let Some(r) = self.by_vertex_start.get(i..i + 2) else {
            return;
        };
        for &(s, slot) in &self.by_vertex[r[0] as usize..r[1] as usize] {
            let st = &self.stencils[s as usize];
            let th = st.thickness;
            if st.lambda == 0.0 {
                // Each primitive's points moved no farther than its farthest vertex: while the
                // pair cannot have come within the thickness, it adds nothing.
                let moved =
                    st.v.iter()
                        .map(|&v| (x[v as usize] - self.seen[v as usize]).norm_squared())
                        .fold(0.0, Real::max)
                        .sqrt();
                if st.gap - 2.0 * moved >= th {
                    continue;
                }
            }
            let w = st.weights(x);
            let wi = w[slot as usize];
            let d: Vec3 = (0..4).map(|m| x[st.v[m] as usize] * w[m]).sum();
            let l = d.norm();
            if l < th && l > 1e-12 {
                let n = d / l;
                *f += n * (k * (th - l) * wi);
                *hess += n * n.transpose() * (k * wi * wi);
            }
            let mu = self.params.friction;
            if mu > 0.0 && st.lambda > 0.0 {
                let moved: Vec3 = (0..4)
                    .map(|m| (x[st.v[m] as usize] - self.seen[st.v[m] as usize]) * w[m])
                    .sum();
                let nn = st.normal * st.normal.transpose();
                let u = moved - st.normal * st.normal.dot(&moved);
                let scale = mu * st.lambda / u.norm().max(eps);
                *f -= u * (scale * wi);
                *hess += (Mat3::identity() - nn) * (scale * wi * wi);
            }
        }
    }
}
