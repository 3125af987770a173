//! Force evaluation: the hot loop. Springs follow P1 eq. (1),
//! `f_i = k (p_j - p_i) / L (|p_i - p_j| - L)` with k = k_stretch when longer than rest and k_compress
//! when shorter, plus viscous damping along the spring; then gravity, air drag relative to the wind
//! and velocity damping per particle.

use crate::model::ClothModel;
use crate::params::ClothParams;
use tryon_core::math::{Real, Vec3};

/// Spring forces (elastic, plus damping when `DAMP`) accumulated into `force`; when `RECORD`, the
/// elastic part alone is also accumulated into `elastic`. Both buffers are overwritten.
fn spring_forces<const DAMP: bool, const RECORD: bool>(
    model: &ClothModel,
    x: &[Vec3],
    v: &[Vec3],
    force: &mut [Vec3],
    elastic: &mut [Vec3],
) {
    force.fill(Vec3::zeros());
    if RECORD {
        elastic.fill(Vec3::zeros());
    }
    for s in &model.packed {
        let (i, j) = (s.i as usize, s.j as usize);
        let d = x[j] - x[i];
        let len2 = d.norm_squared();
        let stretch = len2.sqrt() - s.rest;
        let k = if stretch > 0.0 {
            s.stretch_per_rest
        } else {
            s.compress_per_rest
        };
        let fe = d * (k * stretch);
        let mut f = fe;
        if DAMP && len2 > 1e-24 {
            let dv = v[j] - v[i];
            f += d * (s.damping * dv.dot(&d) / len2);
        }
        force[i] += f;
        force[j] -= f;
        if RECORD {
            elastic[i] += fe;
            elastic[j] -= fe;
        }
    }
    if !model.hinges.is_empty() {
        crate::hinges::add_forces(&model.hinges, x, 1.0, force);
        if RECORD {
            crate::hinges::add_forces(&model.hinges, x, 1.0, elastic);
        }
    }
}

/// Accelerations of every particle at state (x, v). `force` is scratch; when `elastic` is given it
/// receives each particle's net elastic (spring) force.
pub fn accelerations(
    model: &ClothModel,
    params: &ClothParams,
    x: &[Vec3],
    v: &[Vec3],
    force: &mut [Vec3],
    elastic: Option<&mut [Vec3]>,
    a: &mut [Vec3],
) {
    let damp = params.spring_damping > 0.0;
    match (damp, elastic) {
        (true, Some(e)) => spring_forces::<true, true>(model, x, v, force, e),
        (false, Some(e)) => spring_forces::<false, true>(model, x, v, force, e),
        (true, None) => spring_forces::<true, false>(model, x, v, force, &mut []),
        (false, None) => spring_forces::<false, false>(model, x, v, force, &mut []),
    }
    external_and_accelerate(model, params, v, force, a);
}

/// Adds gravity, air drag and velocity damping, then divides by mass (0 for pinned and handled particles).
fn external_and_accelerate(
    model: &ClothModel,
    params: &ClothParams,
    v: &[Vec3],
    force: &[Vec3],
    a: &mut [Vec3],
) {
    // Only the terms a scene enables are evaluated: a disabled term costs no pass over the particles.
    let g = params.gravity;
    let (drag, wind, vd) = (params.air_drag, params.wind, params.velocity_damping);
    if g == Vec3::zeros() {
        for i in 0..a.len() {
            a[i] = force[i] * model.inv_mass[i];
        }
    } else {
        for i in 0..a.len() {
            a[i] = (force[i] + g * model.mass[i]) * model.inv_mass[i];
        }
    }
    if drag != 0.0 {
        for i in 0..a.len() {
            a[i] -= (v[i] - wind) * (drag * model.area[i] * model.inv_mass[i]);
        }
    }
    if vd != 0.0 {
        for i in 0..a.len() {
            a[i] -= v[i] * (vd * model.mass[i] * model.inv_mass[i]);
        }
    }
}

/// `cx (da/dx) w + cv (da/dv) w` at (x, v), analytically, for the implicit integrator. Each spring's
/// stiffness block is made positive semi-definite as Baraff and Witkin (1998) do: the transverse
/// term of a compressed spring (negative) is dropped, and so is a negative axial term, so the
/// implicit system stays symmetric positive definite and CG applies. Spring damping contributes its
/// velocity Jacobian; drag and velocity damping their diagonal ones.
#[allow(clippy::too_many_arguments)]
pub fn jacobian_product(
    model: &ClothModel,
    params: &ClothParams,
    x: &[Vec3],
    w: &[Vec3],
    cx: Real,
    cv: Real,
    force: &mut [Vec3],
    out: &mut [Vec3],
) {
    force.fill(Vec3::zeros());
    let damp = params.spring_damping > 0.0 && cv != 0.0;
    for s in &model.packed {
        let (i, j) = (s.i as usize, s.j as usize);
        let d = x[j] - x[i];
        let len = d.norm();
        if len < 1e-12 {
            continue;
        }
        let u = d / len;
        let k = if len > s.rest {
            s.stretch_per_rest
        } else {
            s.compress_per_rest
        };
        let dw = w[j] - w[i];
        let along = u.dot(&dw);
        let transverse = k * (len - s.rest).max(0.0);
        let axial = k * (2.0 * len - s.rest).max(0.0);
        let mut t = (dw - u * along) * (cx * transverse) + u * (cx * axial * along);
        if damp {
            t += u * (cv * s.damping * along);
        }
        force[i] += t;
        force[j] -= t;
    }
    // The bending force is linear in x: its Jacobian applied to w is the force at w.
    if cx != 0.0 {
        crate::hinges::add_forces(&model.hinges, w, cx, force);
    }
    let (drag, vd) = (params.air_drag, params.velocity_damping);
    for i in 0..out.len() {
        let im = model.inv_mass[i];
        let mut diag = 0.0;
        if drag != 0.0 {
            diag -= drag * model.area[i] * im;
        }
        if vd != 0.0 {
            diag -= vd * model.mass[i] * im;
        }
        out[i] = force[i] * im + w[i] * (cv * diag);
    }
}

/// An upper bound on the largest angular frequency of the linearised spring system (Gershgorin on
/// M^-1 K) and on the largest damping rate (M^-1 C), for choosing a stable substep.
pub fn stiffness_bounds(model: &ClothModel) -> (Real, Real) {
    let n = model.particle_count();
    let mut ksum = vec![0.0; n];
    let mut csum = vec![0.0; n];
    let s = &model.springs;
    for k in 0..s.len() {
        // dF/dx of eq. (1) along the spring is about k (2 len - L) / L; allow 20% over rest length.
        let kk = s.k_stretch[k].max(s.k_compress[k]) * 1.4;
        for p in [s.i[k] as usize, s.j[k] as usize] {
            ksum[p] += kk;
            csum[p] += s.damping[k];
        }
    }
    // Hinge rows already hold diagonal plus off-diagonal magnitudes; springs contribute k to each.
    let mut hsum = vec![0.0; n];
    crate::hinges::add_row_sums(&model.hinges, &mut hsum);
    let mut w2: Real = 0.0;
    let mut c: Real = 0.0;
    for i in 0..n {
        w2 = w2.max((2.0 * ksum[i] + hsum[i]) * model.inv_mass[i]);
        c = c.max(2.0 * csum[i] * model.inv_mass[i]);
    }
    (w2.sqrt(), c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use tryon_core::mesh::grid_xz;

    fn model(p: &ClothParams) -> ClothModel {
        ClothModel::build(&grid_xz(3, 3, 1.0, 1.0, 0.0), p, vec![]).unwrap()
    }

    #[test]
    fn stretched_spring_pulls_ends_together_asymmetrically() {
        let p = ClothParams {
            k_stretch: 100.0,
            k_compress: 1.0,
            ..ClothParams::conservative()
        };
        let mut m = model(&p);
        // Keep only the first structural spring to look at it alone.
        m.springs.i.truncate(1);
        m.packed.truncate(1);
        m.springs.j.truncate(1);
        let (i, j) = (m.springs.i[0] as usize, m.springs.j[0] as usize);
        let rest = m.springs.rest[0];
        let n = m.particle_count();
        let (mut f, mut e, mut a) = (
            vec![Vec3::zeros(); n],
            vec![Vec3::zeros(); n],
            vec![Vec3::zeros(); n],
        );
        let v = vec![Vec3::zeros(); n];
        for (scale, k) in [(1.1, 100.0), (0.9, 1.0)] {
            let mut x = m.rest_positions.clone();
            x[j] = x[i] + (x[j] - x[i]) * scale;
            accelerations(&m, &p, &x, &v, &mut f, Some(&mut e), &mut a);
            let d = x[j] - x[i];
            let expected = d * (k * (d.norm() - rest) / rest);
            assert!(
                (e[i] - expected).norm() < 1e-12,
                "force on i: {:?} vs {expected:?}",
                e[i]
            );
            assert!((e[i] + e[j]).norm() < 1e-15);
            // Stretched: i is pulled toward j; compressed: pushed away.
            assert_eq!(e[i].dot(&d) > 0.0, scale > 1.0);
        }
    }

    /// The analytic Jacobian product matches finite differences of the forces for stretched
    /// springs (where no definiteness clamp applies) and for the velocity terms.
    #[test]
    fn jacobian_product_matches_finite_differences() {
        let p = ClothParams {
            air_drag: 0.7,
            velocity_damping: 0.3,
            spring_damping: 0.05,
            bending_rigidity: 1e-3,
            ..ClothParams::default()
        };
        let m = model(&p);
        assert!(!m.hinges.is_empty());
        let n = m.particle_count();
        // Stretch the sheet by 10% with a small shear so every spring is longer than at rest.
        let x: Vec<Vec3> = m
            .rest_positions
            .iter()
            .map(|q| Vec3::new(q.x * 1.1 + 0.01 * q.z, q.y, q.z * 1.12))
            .collect();
        let v: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new((i as Real).sin(), 0.3, (i as Real * 0.7).cos()) * 0.1)
            .collect();
        let w: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new((i as Real * 1.3).cos(), (i as Real * 0.4).sin(), 0.2))
            .collect();
        let (mut f, mut a0, mut a1, mut out) = (
            vec![Vec3::zeros(); n],
            vec![Vec3::zeros(); n],
            vec![Vec3::zeros(); n],
            vec![Vec3::zeros(); n],
        );
        let eps = 1e-7;
        // Damping's dependence on x is left out of the Jacobian (as Baraff and Witkin do), so the
        // position part is compared at rest velocities.
        let still = vec![Vec3::zeros(); n];
        for (cx, cv) in [(1.0, 0.0), (0.0, 1.0)] {
            let v = if cx > 0.0 { &still } else { &v };
            accelerations(&m, &p, &x, v, &mut f, None, &mut a0);
            let xs: Vec<Vec3> = (0..n).map(|i| x[i] + w[i] * (eps * cx)).collect();
            let vs: Vec<Vec3> = (0..n).map(|i| v[i] + w[i] * (eps * cv)).collect();
            accelerations(&m, &p, &xs, &vs, &mut f, None, &mut a1);
            jacobian_product(&m, &p, &x, &w, cx, cv, &mut f, &mut out);
            for i in 0..n {
                let fd = (a1[i] - a0[i]) / eps;
                let tol = 1e-4 * fd.norm().max(1.0);
                assert!(
                    (out[i] - fd).norm() <= tol,
                    "particle {i} ({cx}, {cv}): {:?} vs {fd:?}",
                    out[i]
                );
            }
        }
    }

    #[test]
    fn gravity_drag_and_damping_act_on_free_particles() {
        let p = ClothParams {
            air_drag: 2.0,
            wind: Vec3::new(1.0, 0.0, 0.0),
            velocity_damping: 0.0,
            spring_damping: 0.0,
            ..ClothParams::default()
        };
        let m = model(&p);
        let n = m.particle_count();
        let x = m.rest_positions.clone();
        let v = vec![Vec3::zeros(); n];
        let (mut f, mut a) = (vec![Vec3::zeros(); n], vec![Vec3::zeros(); n]);
        accelerations(&m, &p, &x, &v, &mut f, None, &mut a);
        for i in 0..n {
            let drag = Vec3::new(2.0 * m.area[i] / m.mass[i], 0.0, 0.0);
            assert!(
                (a[i] - (p.gravity + drag)).norm() < 1e-9,
                "particle {i}: {:?}",
                a[i]
            );
        }
    }
}
