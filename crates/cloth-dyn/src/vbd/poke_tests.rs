//! Tests of VBD against body features narrower than the cloth's cells (`pokes.rs`).

use super::tests::sim;
use super::*;
use tryon_core::mesh::grid_xz;

/// A floor (y = 0, outward +y) with one narrow spike of height `tip` at `at`: the spike is a
/// single body vertex, which only [`Collider::pokes`] can tell the cloth about.
struct SpikedFloor {
    at: Vec3,
}

impl Collider for SpikedFloor {
    fn name(&self) -> &'static str {
        "test spiked floor"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities {
            pokes: true,
            ..tryon_core::stages::Capabilities::NONE
        }
    }
    fn update(&mut self, _body: &tryon_core::frames::BodyFrame) {}
    fn resolve(&mut self, points: &mut [Vec3], _contacts: &mut Vec<Contact>) {
        points.iter_mut().for_each(|p| p.y = p.y.max(0.0));
    }
    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        Some(p.y)
    }
    fn pokes(
        &mut self,
        points: &[Vec3],
        triangles: &[[u32; 3]],
        which: &[u32],
        (reach, depth): (Real, Real),
        out: &mut Vec<tryon_core::stages::Poke>,
    ) {
        out.clear();
        for &t in which {
            let c = triangles[t as usize].map(|k| points[k as usize]);
            let n = (c[1] - c[0]).cross(&(c[2] - c[0]));
            let (a2, nt) = (n.norm(), n.normalize());
            let q = self.at + nt * nt.dot(&(c[0] - self.at));
            let w = |a: Vec3, b: Vec3| (b - a).cross(&(q - a)).dot(&nt) / a2;
            let bary = [w(c[1], c[2]), w(c[2], c[0]), w(c[0], c[1])];
            let s = q.y - self.at.y;
            if bary.iter().all(|&b| b >= 0.0) && s >= -depth && s < reach {
                out.push(tryon_core::stages::Poke {
                    triangle: t,
                    bary,
                    point: self.at,
                    normal: Vec3::y(),
                });
            }
        }
    }
}

/// How far the cloth's surface lies above a 6 mm spike after a 2 cm-cell sheet settles on the
/// floor over it for a second (negative: the spike pokes through).
fn cloth_over_spike(pokes: bool) -> Real {
    let mesh = grid_xz(10, 10, 0.2, 0.2, 0.002);
    let vbd = VbdParams {
        pokes,
        ..VbdParams::default()
    };
    let mut s = sim(&mesh, ClothParams::default(), vbd, vec![]);
    let mut f = s.initial_frame();
    // The middle of a cell, away from every particle.
    let mut floor = SpikedFloor {
        at: Vec3::new(0.01, 0.006, 0.01),
    };
    for _ in 0..30 {
        s.step_frame(&mut f, 1.0 / 30.0, &mut floor);
    }
    assert!(f.positions.iter().all(is_finite));
    let mut tris = Vec::new();
    floor.pokes(
        &f.positions,
        &s.model.triangles,
        &(0..s.model.triangles.len() as u32).collect::<Vec<_>>(),
        (1.0, 1.0),
        &mut tris,
    );
    let p = tris[0];
    let t = s.model.triangles[p.triangle as usize];
    let q: Vec3 = (0..3).map(|j| f.positions[t[j] as usize] * p.bary[j]).sum();
    q.y - p.point.y
}

#[test]
fn a_spike_narrower_than_the_cloths_cells_does_not_poke_through() {
    // The particles are held 2 mm off the floor, so alone the cloth lies 4 mm under the tip
    // (measured -4.0 mm); with pokes it is held 1 mm over it (measured 1.0 mm).
    let without = cloth_over_spike(false);
    assert!(
        without < -0.003,
        "without pokes the cloth is {without} m over the tip"
    );
    let with = cloth_over_spike(true);
    assert!(
        with > -0.0002,
        "with pokes the cloth is {with} m over the tip"
    );
}
