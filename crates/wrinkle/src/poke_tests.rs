//! Fine collision against a body feature narrower than the fine lattice (`pokes`).

use crate::tests::{frame, linear_fine};
use crate::{Detail, DetailParams};
use tryon_core::frames::{Contact, FineSurface};
use tryon_core::math::{Real, Vec3};
use tryon_core::mesh::grid_xz;
use tryon_core::stages::Collider;

/// The ground y = 0 with one spike 6 mm tall at the origin, narrower than the fine lattice:
/// probes of the lattice's vertices see only the ground, and `pokes` reports the spike under any
/// listed triangle it lies under (a nipple under a shirt).
struct Spike;

const SPIKE: Real = 0.006;

impl Collider for Spike {
    fn name(&self) -> &'static str {
        "spike"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities {
            pokes: true,
            ..tryon_core::stages::Capabilities::NONE
        }
    }
    fn update(&mut self, _body: &tryon_core::frames::BodyFrame) {}
    fn resolve(&mut self, _points: &mut [Vec3], _contacts: &mut Vec<Contact>) {}
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
        let tip = Vec3::new(0.0, SPIKE, 0.0);
        for &t in which {
            let c = triangles[t as usize].map(|k| points[k as usize]);
            // Barycentric coordinates of the tip's vertical projection (the sheet is level).
            let area =
                |a: Vec3, b: Vec3, p: Vec3| (b.x - a.x) * (p.z - a.z) - (b.z - a.z) * (p.x - a.x);
            let full = area(c[0], c[1], c[2]);
            let w = [
                area(c[1], c[2], tip),
                area(c[2], c[0], tip),
                area(c[0], c[1], tip),
            ]
            .map(|x| x / full);
            let y: Real = (0..3).map(|k| c[k].y * w[k]).sum();
            let s = y - SPIKE;
            if w.iter().all(|&x| x >= 0.0) && s >= -depth && s < reach {
                out.push(tryon_core::stages::Poke {
                    triangle: t,
                    bary: w,
                    point: tip,
                    normal: Vec3::y(),
                });
            }
        }
    }
}

/// A level sheet 3 mm over the ground: every fine vertex is clear of it, but a 6 mm spike pokes
/// through between them. With `pokes` the sheet over the spike is lifted `skin` over its tip;
/// without, it stays where it was, pierced.
#[test]
fn a_spike_narrower_than_the_fine_triangles_is_covered() {
    let mesh = grid_xz(2, 2, 0.1, 0.1, 0.003);
    let x = mesh.positions.clone();
    let over_tip = |f: &FineSurface| {
        // The height of the fine surface over the origin: the triangle containing it.
        f.triangles
            .iter()
            .find_map(|t| {
                let c = t.map(|k| f.positions[k as usize]);
                let area = |a: Vec3, b: Vec3, p: Vec3| {
                    (b.x - a.x) * (p.z - a.z) - (b.z - a.z) * (p.x - a.x)
                };
                let full = area(c[0], c[1], c[2]);
                let o = Vec3::zeros();
                let w = [
                    area(c[1], c[2], o),
                    area(c[2], c[0], o),
                    area(c[0], c[1], o),
                ]
                .map(|v| v / full);
                w.iter()
                    .all(|&v| v >= -1e-12)
                    .then(|| (0..3).map(|k| c[k].y * w[k]).sum::<Real>())
            })
            .expect("a triangle over the origin")
    };
    for pokes in [false, true] {
        let mut fine = linear_fine(&mesh, &x, 2);
        let params = DetailParams {
            wrinkles: false,
            pokes,
            ..DetailParams::default()
        };
        let skin = params.skin;
        let mut d = Detail::new(&fine, &mesh.positions, params).unwrap();
        let coarse = frame(&x, vec![Vec3::zeros(); x.len()]);
        d.wrinkle(&coarse, &mut fine);
        d.fine_collision(&coarse, &mut fine, &mut Spike);
        let h = over_tip(&fine);
        if pokes {
            assert!(h >= SPIKE + skin - 1e-9, "covered at {h} m");
            assert!(d.stats.lifted > 0 && d.stats.lifted <= 3);
        } else {
            assert!((h - 0.003).abs() < 1e-12, "left at {h} m");
        }
        assert!(fine.positions.iter().all(|p| p.y >= 0.003 - 1e-12));
    }
}
