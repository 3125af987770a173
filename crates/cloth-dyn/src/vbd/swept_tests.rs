//! The swept test inside VBD's steps: only the paths that can reach the body are tested.

use super::tests::sim;
use super::*;
use tryon_core::mesh::grid_xz;

/// The floor y = 0, probed exactly, whose swept test stops a path crossing it downward; it
/// counts the paths it is given.
#[derive(Default)]
struct Floor {
    swept_paths: usize,
}

impl Collider for Floor {
    fn name(&self) -> &'static str {
        "test floor"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities {
            sweep: true,
            exact_distance: true,
            ..tryon_core::stages::Capabilities::NONE
        }
    }
    fn update(&mut self, _body: &tryon_core::frames::BodyFrame) {}
    fn resolve(&mut self, _points: &mut [Vec3], _contacts: &mut Vec<Contact>) {}
    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        Some(p.y)
    }
    fn probe(&mut self, points: &[Vec3], which: &[u32], out: &mut Vec<Probe>) {
        out.clear();
        out.extend(which.iter().map(|&k| Probe {
            distance: points[k as usize].y,
            normal: Vec3::y(),
        }));
    }
    fn sweep(
        &mut self,
        start: &[Vec3],
        end: &mut [Vec3],
        _span: [Real; 2],
        contacts: &mut Vec<Contact>,
    ) -> bool {
        self.swept_paths += start.len();
        for (k, (s, e)) in start.iter().zip(end.iter_mut()).enumerate() {
            if s.y >= 0.0 && e.y < 0.0 {
                e.y = 0.0;
                contacts.push(Contact {
                    point: k as u32,
                    face: 0,
                    bary: [1.0, 0.0, 0.0],
                    normal: Vec3::y(),
                    depth: 0.0,
                    body_velocity: Vec3::zeros(),
                });
            }
        }
        true
    }
}

#[test]
fn the_swept_test_takes_the_paths_that_can_reach_the_body_and_stops_them() {
    // A sheet thrown at the floor at 6 m/s from 10 cm: high up, no path reaches the floor and the
    // swept test is given none; at impact it is given the paths that do, and stops them.
    let mesh = grid_xz(8, 8, 0.5, 0.5, 0.1);
    let mut s = sim(&mesh, ClothParams::default(), VbdParams::default(), vec![]);
    let mut f = s.initial_frame();
    f.velocities.iter_mut().for_each(|v| v.y = -6.0);
    let mut floor = Floor::default();
    s.step_frame(&mut f, 1.0 / 120.0, &mut floor);
    assert_eq!(floor.swept_paths, 0, "5 cm a step, 10 cm up");
    for _ in 0..30 {
        s.step_frame(&mut f, 1.0 / 30.0, &mut floor);
        let lowest = f
            .positions
            .iter()
            .map(|p| p.y)
            .fold(Real::INFINITY, Real::min);
        assert!(lowest >= 0.0, "{lowest} m under the floor");
    }
    let steps = 1 + 30 * 4;
    assert!(floor.swept_paths > 0);
    assert!(
        floor.swept_paths < steps * f.positions.len() / 2,
        "{} paths",
        floor.swept_paths
    );
}
