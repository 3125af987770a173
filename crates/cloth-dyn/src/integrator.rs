//! Integrators behind cloth-dyn's own extension point. An integrator advances (x, v) by h given a
//! [`Derivative`] that returns accelerations; it owns only scratch memory.

use tryon_core::math::{Real, Vec3};

/// The right-hand side of x' = v, v' = a(x, v).
pub trait Derivative {
    /// Writes a(x, v) into `a`. `first` is true for the first evaluation of a step (at its start state).
    fn accelerations(&mut self, x: &[Vec3], v: &[Vec3], a: &mut [Vec3], first: bool);
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
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorKind {
    Rk4,
    SymplecticEuler,
}

impl IntegratorKind {
    /// A fresh integrator of this kind.
    pub fn make(self) -> Box<dyn Integrator> {
        match self {
            IntegratorKind::Rk4 => Box::new(Rk4::default()),
            IntegratorKind::SymplecticEuler => Box::new(SymplecticEuler::default()),
        }
    }

    /// Parses "rk4" or "symplectic_euler".
    pub fn parse(s: &str) -> Option<Self> {
        match s {
            "rk4" => Some(IntegratorKind::Rk4),
            "symplectic_euler" => Some(IntegratorKind::SymplecticEuler),
            _ => None,
        }
    }

    /// The name `parse` accepts.
    pub fn as_str(self) -> &'static str {
        match self {
            IntegratorKind::Rk4 => "rk4",
            IntegratorKind::SymplecticEuler => "symplectic_euler",
        }
    }
}

fn resize(buf: &mut Vec<Vec3>, n: usize) {
    buf.resize(n, Vec3::zeros());
}

/// Classical fourth-order Runge-Kutta (P1 section 3.1).
#[derive(Debug, Default)]
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
#[derive(Debug, Default)]
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
    fn names_round_trip() {
        for k in [IntegratorKind::Rk4, IntegratorKind::SymplecticEuler] {
            assert_eq!(IntegratorKind::parse(k.as_str()), Some(k));
            assert_eq!(k.make().name(), k.as_str());
        }
        assert_eq!(IntegratorKind::parse("euler"), None);
    }
}
