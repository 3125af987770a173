//! Issue 21's hard cases for VBD's self-contact: a sheet dropped over a thin bar with one half
//! thrown into the other, and a tube twisted and squeezed by its ends. Each asserts no crossing
//! triangle pair at any frame (parry's GJK as judge) and finite state, and that without
//! self-contact the same run does cross (so the assertion can fail).

use super::tests::out_of_sphere;
use super::*;
use crate::self_contact::SelfParams;
use crate::self_contact::tests::crossings;
use tryon_core::mesh::{Face, PolyMesh, grid_xz};
use tryon_core::stages::NoCollider;

/// A thin horizontal bar along z through the origin.
struct Bar {
    r: Real,
}

impl Collider for Bar {
    fn name(&self) -> &'static str {
        "test bar"
    }
    fn capabilities(&self) -> tryon_core::stages::Capabilities {
        tryon_core::stages::Capabilities::NONE
    }
    fn update(&mut self, _body: &tryon_core::frames::BodyFrame) {}
    fn resolve(&mut self, points: &mut [Vec3], contacts: &mut Vec<Contact>) {
        // Out of the bar: out of the circle around its axis in the point's own plane.
        for (k, p) in points.iter_mut().enumerate() {
            out_of_sphere(k, p, Vec3::new(0.0, 0.0, p.z), self.r, contacts);
        }
    }
    fn signed_distance(&self, p: &Vec3) -> Option<Real> {
        Some(Vec3::new(p.x, p.y, 0.0).norm() - self.r)
    }
}

fn layers(on: bool) -> Option<SelfParams> {
    on.then(SelfParams::default)
}

/// Worst crossing count over the frames and whether the state stayed finite.
fn run(
    s: &mut VbdSim,
    (frames, dt): (usize, Real),
    collider: &mut dyn Collider,
    kick: impl Fn(&Vec3) -> Vec3,
) -> (usize, bool) {
    let mut f = s.initial_frame();
    for (v, p) in f.velocities.iter_mut().zip(&f.positions) {
        *v = kick(p);
    }
    let (mut worst, mut finite) = (0, true);
    let tris = s.model.triangles.clone();
    for k in 1..=frames {
        s.step_frame(&mut f, dt, collider);
        finite &= f.positions.iter().all(is_finite);
        if k % 3 == 0 || k == frames {
            worst = worst.max(crossings(&f.positions, &tris));
        }
    }
    (worst, finite)
}

fn sheet_over_bar(on: bool) -> (usize, bool) {
    // 60 cm by 30 cm, 2 cm cells, dropped 2 cm over a 5 mm bar; the half on -x is thrown toward
    // +x at the start, so once it hangs it swings into the other half.
    let mesh = grid_xz(30, 15, 0.6, 0.3, 0.02);
    let params = ClothParams::default();
    let model = ClothModel::build(&mesh, &params, vec![]).unwrap();
    let mut s =
        VbdSim::new(model, params, VbdParams::default(), 0.002).with_self_contact(layers(on));
    let kick = |p: &Vec3| Vec3::new(if p.x < -0.05 { 3.0 } else { 0.0 }, 0.0, 0.0);
    run(&mut s, (90, 1.0 / 30.0), &mut Bar { r: 0.005 }, kick)
}

#[test]
fn a_sheet_blown_together_over_a_thin_bar_does_not_pass_through_itself() {
    // Measured: 0 crossing pairs with self-contact, 309 at worst without.
    let (with, finite) = sheet_over_bar(true);
    assert!(finite);
    assert_eq!(with, 0, "crossing pairs with self-contact");
    let (without, _) = sheet_over_bar(false);
    assert!(without > 0, "the halves never met: the case tests nothing");
}

/// A tube of `around` by `along` quads, radius `r`, length `len`, along y from 0 up.
fn tube(around: u32, along: u32, r: Real, len: Real) -> PolyMesh {
    let mut positions = Vec::new();
    for j in 0..=along {
        for i in 0..around {
            let a = std::f64::consts::TAU * i as Real / around as Real;
            positions.push(Vec3::new(
                r * a.cos(),
                len * j as Real / along as Real,
                r * a.sin(),
            ));
        }
    }
    let mut faces = Vec::new();
    for j in 0..along {
        for i in 0..around {
            let (a, b) = (j * around + i, j * around + (i + 1) % around);
            faces.push(Face::Quad([a, a + around, b + around, b]));
        }
    }
    PolyMesh { positions, faces }
}

fn twisted_tube(on: bool) -> (usize, bool) {
    let (around, along, len) = (20u32, 16u32, 0.4);
    let mesh = tube(around, along, 0.05, len);
    // The top ring held; the bottom ring turned twice about the axis and lifted by a third of the
    // length over 2 s.
    let mut handles = Vec::new();
    for i in 0..around {
        let top = (along * around + i) as usize;
        handles.push(Handle {
            particle: top as u32,
            path: vec![(0.0, mesh.positions[top])],
        });
        let p = mesh.positions[i as usize];
        let path = (0..=60)
            .map(|k| {
                let s = k as Real / 60.0;
                let a = 2.0 * std::f64::consts::TAU * s;
                let (c, sn) = (a.cos(), a.sin());
                let q = Vec3::new(c * p.x - sn * p.z, len / 3.0 * s, sn * p.x + c * p.z);
                (2.0 * s, q)
            })
            .collect();
        handles.push(Handle { particle: i, path });
    }
    let params = ClothParams {
        gravity: Vec3::zeros(),
        ..ClothParams::default()
    };
    let model = ClothModel::build(&mesh, &params, handles).unwrap();
    let mut s =
        VbdSim::new(model, params, VbdParams::default(), 0.002).with_self_contact(layers(on));
    run(&mut s, (75, 1.0 / 30.0), &mut NoCollider, |_| Vec3::zeros())
}

#[test]
fn a_tube_twisted_and_squeezed_by_its_ends_does_not_pass_through_itself() {
    // Measured: 0 crossing pairs with self-contact, 1,203 at worst without.
    let (with, finite) = twisted_tube(true);
    assert!(finite);
    assert_eq!(with, 0, "crossing pairs with self-contact");
    let (without, _) = twisted_tube(false);
    assert!(
        without > 0,
        "the tube never touched itself: the case tests nothing"
    );
}
