//! Integrators behind cloth-dyn's own extension point. An integrator advances (x, v) by h given a
//! [`Derivative`] that returns accelerations; it owns only scratch memory.

use tryon_core::math::{Real, Vec3};

/// The right-hand side of x' = v, v' = a(x, v).
pub trait Derivative {
    /// Writes a(x, v) into `a`. `first` is true for the first evaluation of a step (at its start state).
    fn accelerations(&mut self, x: &[Vec3], v: &[Vec3], a: &mut [Vec3], first: bool);

    /// Writes `cx (da/dx) w + cv (da/dv) w` at (x, v) into `out`, for implicit integrators. The
    /// default takes a forward difference of [`Derivative::accelerations`] (two evaluations);
    /// force models with analytic Jacobians override it.
    fn jacobian_product(
        &mut self,
        x: &[Vec3],
        v: &[Vec3],
        w: &[Vec3],
        cx: Real,
        cv: Real,
        out: &mut [Vec3],
    ) {
        let n = x.len();
        let scale = w.iter().map(|q| q.norm()).fold(0.0, Real::max);
        if scale == 0.0 {
            out.fill(Vec3::zeros());
            return;
        }
        let eps = 1e-7 / scale;
        let xs: Vec<Vec3> = (0..n).map(|i| x[i] + w[i] * (eps * cx)).collect();
        let vs: Vec<Vec3> = (0..n).map(|i| v[i] + w[i] * (eps * cv)).collect();
        let mut a0 = vec![Vec3::zeros(); n];
        self.accelerations(x, v, &mut a0, false);
        self.accelerations(&xs, &vs, out, false);
        for i in 0..n {
            out[i] = (out[i] - a0[i]) / eps;
        }
    }

    /// Mass of each particle, zero where its motion is prescribed (pinned or handled). Implicit
    /// solves weight their equations by it and leave prescribed velocities alone. `None`: unit
    /// masses, nothing prescribed.
    fn masses(&self) -> Option<&[Real]> {
        None
    }
}

/// A time integrator for second-order particle systems.
pub trait Integrator: Send {
    /// Short name for reports.
    fn name(&self) -> &'static str;
    /// Largest |h * omega| for which an undamped oscillation stays bounded.
    fn stability_limit(&self) -> Real;
    /// Force evaluations per step.
    fn evaluations(&self) -> u32;
    /// Advances x and v by h in place.
    fn step(&mut self, f: &mut dyn Derivative, x: &mut [Vec3], v: &mut [Vec3], h: Real);
}

/// The integrators this crate offers, by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum IntegratorKind {
    Rk4,
    SymplecticEuler,
    /// Backward Euler linearised once per step (Baraff and Witkin 1998), solved by conjugate
    /// gradients.
    ImplicitEuler,
}

impl IntegratorKind {
    /// A fresh integrator of this kind.
    pub fn make(self) -> Box<dyn Integrator> {
        match self {
            IntegratorKind::Rk4 => Box::new(Rk4::default()),
            IntegratorKind::SymplecticEuler => Box::new(SymplecticEuler::default()),
            IntegratorKind::ImplicitEuler => Box::new(ImplicitEuler::default()),
        }
    }

    /// Parses "rk4", "symplectic_euler" or "implicit_euler".
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "rk4" => Some(IntegratorKind::Rk4),
            "symplectic_euler" => Some(IntegratorKind::SymplecticEuler),
            "implicit_euler" => Some(IntegratorKind::ImplicitEuler),
            _ => None,
        }
    }

    /// The name `parse` accepts.
    pub fn as_str(self) -> &'static str {
        match self {
            IntegratorKind::Rk4 => "rk4",
            IntegratorKind::SymplecticEuler => "symplectic_euler",
            IntegratorKind::ImplicitEuler => "implicit_euler",
        }
    }
}

fn resize(buf: &mut Vec<Vec3>, n: usize) {
    buf.resize(n, Vec3::zeros());
}

/// Classical fourth-order Runge-Kutta (P1 section 3.1).
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct Rk4 {
    xs: Vec<Vec3>,
    vs: Vec<Vec3>,
    a: Vec<Vec3>,
    dx: Vec<Vec3>,
    dv: Vec<Vec3>,
}

impl Integrator for Rk4 {
    fn name(&self) -> &'static str {
        "rk4"
    }
    fn stability_limit(&self) -> Real {
        2.8
    }
    fn evaluations(&self) -> u32 {
        4
    }
    fn step(&mut self, f: &mut dyn Derivative, x: &mut [Vec3], v: &mut [Vec3], h: Real) {
        let n = x.len();
        for b in [
            &mut self.xs,
            &mut self.vs,
            &mut self.a,
            &mut self.dx,
            &mut self.dv,
        ] {
            resize(b, n);
        }
        // Stage 1 at (x, v).
        f.accelerations(x, v, &mut self.a, true);
        for i in 0..n {
            self.dx[i] = v[i];
            self.dv[i] = self.a[i];
            self.xs[i] = x[i] + v[i] * (0.5 * h);
            self.vs[i] = v[i] + self.a[i] * (0.5 * h);
        }
        // Stages 2 and 3: evaluate at the stage state, then form the next one from (x, v).
        for (weight, next) in [(2.0, 0.5 * h), (2.0, h)] {
            f.accelerations(&self.xs, &self.vs, &mut self.a, false);
            for i in 0..n {
                let vk = self.vs[i];
                self.dx[i] += vk * weight;
                self.dv[i] += self.a[i] * weight;
                self.xs[i] = x[i] + vk * next;
                self.vs[i] = v[i] + self.a[i] * next;
            }
        }
        // Stage 4.
        f.accelerations(&self.xs, &self.vs, &mut self.a, false);
        let s = h / 6.0;
        for i in 0..n {
            x[i] += (self.dx[i] + self.vs[i]) * s;
            v[i] += (self.dv[i] + self.a[i]) * s;
        }
    }
}

/// Symplectic (semi-implicit) Euler: v += h a(x, v); x += h v.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub struct SymplecticEuler {
    a: Vec<Vec3>,
}

impl Integrator for SymplecticEuler {
    fn name(&self) -> &'static str {
        "symplectic_euler"
    }
    fn stability_limit(&self) -> Real {
        1.9
    }
    fn evaluations(&self) -> u32 {
        1
    }
    fn step(&mut self, f: &mut dyn Derivative, x: &mut [Vec3], v: &mut [Vec3], h: Real) {
        resize(&mut self.a, x.len());
        f.accelerations(x, v, &mut self.a, true);
        for i in 0..x.len() {
            v[i] += self.a[i] * h;
            x[i] += v[i] * h;
        }
    }
}

/// Backward Euler, linearised once per step as Baraff and Witkin (1998) do:
/// `(M - h dF/dv - h^2 dF/dx) dv = h (F0 + h dF/dx v)`, then `v += dv`, `x += h v`, with the system
/// solved by conjugate gradients preconditioned by the mass. Prescribed particles (mass 0 in
/// [`Derivative::masses`]) are filtered out of the solve, as Baraff and Witkin's constraint filter
/// does. Each CG iteration costs one Jacobian product (about one force evaluation).
#[derive(Debug, serde::Serialize, serde::Deserialize)]
pub struct ImplicitEuler {
    /// Relative residual at which CG stops.
    pub tolerance: Real,
    /// Most CG iterations per step.
    pub max_iterations: u32,
    /// CG iterations of the last step.
    pub last_iterations: u32,
    a: Vec<Vec3>,
    b: Vec<Vec3>,
    dv: Vec<Vec3>,
    r: Vec<Vec3>,
    z: Vec<Vec3>,
    p: Vec<Vec3>,
    q: Vec<Vec3>,
    weight: Vec<Real>,
}

impl Default for ImplicitEuler {
    fn default() -> Self {
        ImplicitEuler {
            tolerance: 1e-6,
            max_iterations: 100,
            last_iterations: 0,
            a: Vec::new(),
            b: Vec::new(),
            dv: Vec::new(),
            r: Vec::new(),
            z: Vec::new(),
            p: Vec::new(),
            q: Vec::new(),
            weight: Vec::new(),
        }
    }
}

fn dot(a: &[Vec3], b: &[Vec3]) -> Real {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

impl ImplicitEuler {
    /// q = A p with A = W (I - h dA/dv - h^2 dA/dx), W the masses (0 rows for prescribed particles).
    fn apply(&mut self, f: &mut dyn Derivative, x: &[Vec3], v: &[Vec3], h: Real) {
        f.jacobian_product(x, v, &self.p, h * h, h, &mut self.q);
        for i in 0..self.q.len() {
            self.q[i] = (self.p[i] - self.q[i]) * self.weight[i];
        }
    }
}

impl Integrator for ImplicitEuler {
    fn name(&self) -> &'static str {
        "implicit_euler"
    }
    fn stability_limit(&self) -> Real {
        Real::INFINITY
    }
    fn evaluations(&self) -> u32 {
        2 + self.last_iterations
    }
    fn step(&mut self, f: &mut dyn Derivative, x: &mut [Vec3], v: &mut [Vec3], h: Real) {
        let n = x.len();
        for b in [
            &mut self.a,
            &mut self.b,
            &mut self.dv,
            &mut self.r,
            &mut self.z,
            &mut self.p,
            &mut self.q,
        ] {
            resize(b, n);
        }
        self.weight.clear();
        match f.masses() {
            Some(m) if m.len() == n => self.weight.extend_from_slice(m),
            _ => self.weight.resize(n, 1.0),
        }
        f.accelerations(x, v, &mut self.a, true);
        // b = W (h a0 + h^2 dA/dx v).
        f.jacobian_product(x, v, v, h * h, 0.0, &mut self.b);
        for i in 0..n {
            self.b[i] = (self.a[i] * h + self.b[i]) * self.weight[i];
        }
        // Preconditioned CG from dv = 0 (prescribed rows stay 0: their weight is 0).
        self.dv.fill(Vec3::zeros());
        self.r.copy_from_slice(&self.b);
        let precond = |w: Real| if w > 0.0 { 1.0 / w } else { 0.0 };
        for i in 0..n {
            self.z[i] = self.r[i] * precond(self.weight[i]);
        }
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        let stop = self.tolerance * self.tolerance * rz.max(0.0);
        let mut iterations = 0;
        while iterations < self.max_iterations && rz > stop && rz > 0.0 {
            self.apply(f, x, v, h);
            let pq = dot(&self.p, &self.q);
            if !(pq > 0.0) {
                break;
            }
            let alpha = rz / pq;
            for i in 0..n {
                self.dv[i] += self.p[i] * alpha;
                self.r[i] -= self.q[i] * alpha;
                self.z[i] = self.r[i] * precond(self.weight[i]);
            }
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                self.p[i] = self.z[i] + self.p[i] * beta;
            }
            iterations += 1;
        }
        self.last_iterations = iterations;
        for i in 0..n {
            if self.weight[i] > 0.0 {
                v[i] += self.dv[i];
            }
            x[i] += v[i] * h;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// x'' = -w^2 x, one particle moving along X.
    struct Oscillator(Real);
    impl Derivative for Oscillator {
        fn accelerations(&mut self, x: &[Vec3], _v: &[Vec3], a: &mut [Vec3], _first: bool) {
            for i in 0..x.len() {
                a[i] = -x[i] * self.0 * self.0;
            }
        }
    }

    fn error_at(kind: IntegratorKind, h: Real) -> Real {
        let w = 3.0;
        let t_end = 2.0;
        let mut integ = kind.make();
        let mut x = vec![Vec3::new(1.0, 0.0, 0.0)];
        let mut v = vec![Vec3::zeros()];
        let steps = (t_end / h).round() as usize;
        for _ in 0..steps {
            integ.step(&mut Oscillator(w), &mut x, &mut v, h);
        }
        (x[0].x - (w * t_end).cos()).abs()
    }

    #[test]
    fn convergence_orders() {
        let (h1, h2) = (0.02, 0.01);
        let rk = error_at(IntegratorKind::Rk4, h1) / error_at(IntegratorKind::Rk4, h2);
        let se = error_at(IntegratorKind::SymplecticEuler, h1)
            / error_at(IntegratorKind::SymplecticEuler, h2);
        assert!(
            (13.0..19.0).contains(&rk),
            "RK4 error ratio {rk}, expected about 16"
        );
        assert!(
            (1.6..2.5).contains(&se),
            "symplectic Euler error ratio {se}, expected about 2"
        );
    }

    #[test]
    fn implicit_euler_is_first_order_and_unconditionally_stable() {
        let r = error_at(IntegratorKind::ImplicitEuler, 0.02)
            / error_at(IntegratorKind::ImplicitEuler, 0.01);
        assert!(
            (1.6..2.5).contains(&r),
            "implicit Euler error ratio {r}, expected about 2"
        );
        // h w = 30, far past every explicit limit: the amplitude decays instead of growing.
        let mut integ = IntegratorKind::ImplicitEuler.make();
        let (mut x, mut v) = (vec![Vec3::new(1.0, 0.0, 0.0)], vec![Vec3::zeros()]);
        for _ in 0..50 {
            integ.step(&mut Oscillator(3.0), &mut x, &mut v, 10.0);
            assert!(
                x[0].norm() <= 1.0 + 1e-9 && x[0].x.is_finite(),
                "{:?}",
                x[0]
            );
        }
    }

    #[test]
    fn names_round_trip() {
        for k in [
            IntegratorKind::Rk4,
            IntegratorKind::SymplecticEuler,
            IntegratorKind::ImplicitEuler,
        ] {
            assert_eq!(IntegratorKind::parse(k.as_str()), Some(k));
            assert_eq!(k.make().name(), k.as_str());
        }
        assert_eq!(IntegratorKind::parse("euler"), None);
    }
}
