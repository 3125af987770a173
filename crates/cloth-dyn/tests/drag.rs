//! A user's drag on every garment solver (P4's interaction, live in `tryon view SCENE`): a
//! grabbed particle follows the moved target frame by frame, the cloth comes along, and once let
//! go the particle falls under gravity again.

use cloth_dyn::{
    ClothModel, ClothParams, ClothSim, Handle, IntegratorKind, VbdParams, VbdSim, XpbdParams,
    XpbdSim,
};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::grid_xz;
use tryon_core::stages::{ClothSolver, NoCollider};

fn solvers() -> Vec<(&'static str, Box<dyn ClothSolver>)> {
    let mesh = grid_xz(8, 8, 0.5, 0.5, 1.0);
    let params = ClothParams::default();
    let model = || ClothModel::build(&mesh, &params, vec![]).unwrap();
    vec![
        (
            "rk4",
            Box::new(ClothSim::new(model(), params.clone(), IntegratorKind::Rk4)),
        ),
        (
            "xpbd",
            Box::new(XpbdSim::new(model(), params.clone(), XpbdParams::default())),
        ),
        (
            "vbd",
            Box::new(VbdSim::new(
                model(),
                params.clone(),
                VbdParams::default(),
                0.002,
            )),
        ),
    ]
}

#[test]
fn a_dragged_particle_follows_the_target_and_falls_once_let_go() {
    let dt: Real = 1.0 / 30.0;
    for (name, mut solver) in solvers() {
        let mut frame = solver.initial_frame();
        let centre = 40; // the middle of the 9 x 9 grid
        let start = frame.positions[centre];
        // Lift the centre 0.2 m over 10 frames, each frame a new two-key path from where the
        // particle is to the next target, as the live server hands the page's drags on.
        for k in 1..=10 {
            let target = start + Vec3::new(0.0, 0.02 * k as Real, 0.0);
            let here = frame.positions[centre];
            solver.grab(Handle {
                particle: centre as u32,
                path: vec![(frame.time, here), (frame.time + dt, target)],
            });
            solver.step_frame(&mut frame, dt, &mut NoCollider);
            assert!(
                (frame.positions[centre] - target).norm() < 1e-9,
                "{name}: frame {k}: grabbed particle at {:?}, target {target:?}",
                frame.positions[centre]
            );
        }
        // Its neighbour, held by nothing, came up with it.
        let lifted = frame.positions[centre + 1].y - start.y;
        assert!(lifted > 0.05, "{name}: the neighbour rose only {lifted} m");
        let top = frame.positions[centre].y;
        solver.release(centre as u32);
        for _ in 0..10 {
            solver.step_frame(&mut frame, dt, &mut NoCollider);
        }
        let fell = top - frame.positions[centre].y;
        assert!(
            fell > 0.1,
            "{name}: let go, the particle fell only {fell} m"
        );
        assert!(
            frame
                .positions
                .iter()
                .all(|p| p.iter().all(|c| c.is_finite()))
        );
    }
}
