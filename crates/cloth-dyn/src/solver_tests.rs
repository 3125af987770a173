//! Tests of the whole solver: conservation (proptest), rest, hard cases, handles, friction.

use crate::solver::contact_velocity;
use crate::{ClothModel, ClothParams, ClothSim, Handle, IntegratorKind};
use proptest::prelude::*;
use tryon_core::frames::CoarseFrame;
use tryon_core::math::{Real, Vec3, is_finite};
use tryon_core::mesh::grid_xz;
use tryon_core::stages::{ClothSolver, NoCollider};

fn sim(n: usize, params: ClothParams, kind: IntegratorKind, handles: Vec<Handle>) -> ClothSim {
    let model = ClothModel::build(&grid_xz(n, n, 1.0, 1.0, 0.5), &params, handles).unwrap();
    ClothSim::new(model, params, kind)
}

fn momentum(sim: &ClothSim, f: &CoarseFrame) -> Vec3 {
    f.velocities
        .iter()
        .zip(&sim.model.mass)
        .map(|(v, m)| v * *m)
        .sum()
}

fn kind_strategy() -> impl Strategy<Value = IntegratorKind> {
    prop_oneof![
        Just(IntegratorKind::Rk4),
        Just(IntegratorKind::SymplecticEuler)
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Internal forces cancel in pairs, so without external forces momentum is kept.
    #[test]
    fn momentum_is_conserved(n in 2usize..7, kind in kind_strategy(), seed in prop::collection::vec(-1.0..1.0f64, 6)) {
        let params = ClothParams { k_stretch: 20.0, k_compress: 2.0, spring_damping: 0.002, ..ClothParams::conservative() };
        let mut s = sim(n, params, kind, vec![]);
        let mut f = s.initial_frame();
        let h = 1.0 / n as Real;
        for (i, (x, v)) in f.positions.iter_mut().zip(f.velocities.iter_mut()).enumerate() {
            let w = ((i * 7919) % 13) as Real / 13.0 - 0.5;
            *x += Vec3::new(seed[0], seed[1], seed[2]) * (0.2 * h * w);
            *v = Vec3::new(seed[3], seed[4], seed[5]) + Vec3::new(w, -w, 0.5 * w);
        }
        let p0 = momentum(&s, &f);
        let scale: Real = f.velocities.iter().zip(&s.model.mass).map(|(v, m)| v.norm() * m).sum();
        for _ in 0..100 {
            let r = s.step_frame(&mut f, 1.0 / 60.0, &mut NoCollider);
            prop_assert_eq!(r.retries, 0);
        }
        let drift = (momentum(&s, &f) - p0).norm();
        prop_assert!(drift <= 1e-9 * scale.max(p0.norm()), "momentum drift {} of {}", drift, scale);
    }

    /// A mesh at its rest shape with no external force stays exactly there.
    #[test]
    fn rest_stays_at_rest(n in 1usize..8, kind in kind_strategy()) {
        let mut s = sim(n, ClothParams::conservative(), kind, vec![]);
        let mut f = s.initial_frame();
        for _ in 0..30 {
            s.step_frame(&mut f, 1.0 / 60.0, &mut NoCollider);
        }
        for (x, r) in f.positions.iter().zip(&s.model.rest_positions) {
            prop_assert!((x - r).norm() < 1e-12);
        }
        prop_assert!(f.velocities.iter().all(|v| v.norm() < 1e-12));
    }
}

#[test]
fn stiff_cloth_at_a_large_step_stays_finite_and_reports_retries() {
    let params = ClothParams {
        k_stretch: 1e6,
        auto_substep: false,
        max_substep: 1.0 / 30.0,
        max_strain: None,
        ..ClothParams::default()
    };
    let pin = vec![Handle {
        particle: 0,
        path: vec![(0.0, Vec3::new(-0.5, 0.5, -0.5))],
    }];
    let mut s = sim(6, params, IntegratorKind::Rk4, pin);
    let mut f = s.initial_frame();
    let mut retries = 0;
    for _ in 0..10 {
        let r = s.step_frame(&mut f, 1.0 / 30.0, &mut NoCollider);
        retries += r.retries;
        assert!(f.positions.iter().chain(&f.velocities).all(is_finite));
    }
    assert!(
        retries > 0,
        "a 1e6 N/m cloth at dt = 1/30 s must need retries"
    );
    // The same cloth with the stability bound needs none.
    let params = ClothParams {
        auto_substep: true,
        ..s.params.clone()
    };
    let mut s = sim(6, params, IntegratorKind::Rk4, vec![]);
    let mut f = s.initial_frame();
    let r = s.step_frame(&mut f, 1.0 / 30.0, &mut NoCollider);
    assert_eq!(r.retries, 0);
    assert!(
        r.substeps > 100,
        "stable substep should be tiny, got {} substeps",
        r.substeps
    );
}

#[test]
fn non_finite_input_is_rolled_back_and_reported() {
    let mut s = sim(3, ClothParams::default(), IntegratorKind::Rk4, vec![]);
    let mut f = s.initial_frame();
    f.positions[4].x = Real::NAN;
    f.velocities[5].y = Real::INFINITY;
    let r = s.step_frame(&mut f, 1.0 / 60.0, &mut NoCollider);
    assert_eq!(r.rollbacks, 2);
    assert_eq!(r.non_finite_events, 2);
    assert!(f.positions.iter().chain(&f.velocities).all(is_finite));
    // A bad frame length does nothing and does not panic.
    let before = f.clone();
    s.step_frame(&mut f, Real::NAN, &mut NoCollider);
    assert_eq!(f.positions, before.positions);
}

#[test]
fn handle_drags_its_particle_and_the_cloth_follows() {
    let path = vec![
        (0.0, Vec3::new(-0.5, 0.5, -0.5)),
        (1.0, Vec3::new(-0.5, 1.5, -0.5)),
    ];
    let handle = Handle { particle: 0, path };
    let params = ClothParams {
        gravity: Vec3::zeros(),
        ..ClothParams::default()
    };
    let mut s = sim(4, params, IntegratorKind::Rk4, vec![handle.clone()]);
    let mut f = s.initial_frame();
    for k in 1..=60 {
        s.step_frame(&mut f, 1.0 / 60.0, &mut NoCollider);
        let t = k as Real / 60.0;
        assert!((f.positions[0] - handle.position(t)).norm() < 1e-12);
    }
    // Weightless and free to bend, the sheet is dragged along: the strain limit keeps every particle
    // within 1.02 x its rest distance of the handle (sqrt 2 for the far corner) and lifts its centre.
    let reach = (f.positions[24] - f.positions[0]).norm();
    assert!(
        reach <= 1.02 * (2.0 as Real).sqrt() + 1e-9,
        "far corner {reach} m from the handle"
    );
    let mean_y = f.positions.iter().map(|p| p.y).sum::<Real>() / 25.0;
    assert!(
        mean_y > 0.7,
        "centre of the cloth at y = {mean_y}, should have risen from 0.5"
    );
}

#[test]
fn friction_is_coulomb() {
    let n = Vec3::y();
    // Moving into the surface at 1 m/s and sliding at 2 m/s: mu = 0.5 takes 0.5 m/s off the slide.
    let v = contact_velocity(Vec3::new(2.0, -1.0, 0.0), n, Vec3::zeros(), 0.5);
    assert!((v - Vec3::new(1.5, 0.0, 0.0)).norm() < 1e-15);
    // High friction sticks to the (moving) body.
    let vb = Vec3::new(0.0, 0.0, 0.3);
    let v = contact_velocity(Vec3::new(0.2, -1.0, 0.3), n, vb, 1.0);
    assert!((v - vb).norm() < 1e-15);
    // Leaving the surface is untouched.
    let v = contact_velocity(Vec3::new(2.0, 1.0, 0.0), n, Vec3::zeros(), 1.0);
    assert_eq!(v, Vec3::new(2.0, 1.0, 0.0));
}
