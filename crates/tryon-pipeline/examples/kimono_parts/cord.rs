//! The tie by a cord (included by `kimono_dress`): a closed tube around the body, part of the
//! collider, shrunk from outside the open kimono to the waist, while the cord row of the pattern is
//! drawn straight up (soft holds) so the hem leaves the floor and the length above folds over.

use tryon_core::frames::{BodyFrame, CoarseFrame};
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::{Measurements, smoothstep};
use tryon_core::mesh::PolyMesh;
use tryon_pipeline::scene::CollisionMethod;

const AROUND: usize = 64;
const TUBE: usize = 8;
/// The cord's radius, m.
const RHO: Real = 0.012;

/// A tube around an ellipse at height `y`: centre line semi-axes `a`, `b`, centred on z = `zc`.
fn tube(a: Real, b: Real, zc: Real, y: Real) -> Vec<Vec3> {
    let mut out = Vec::with_capacity(AROUND * TUBE);
    for i in 0..AROUND {
        let t = std::f64::consts::TAU * i as Real / AROUND as Real;
        let c = Vec3::new(a * t.cos(), y, zc + b * t.sin());
        let n = Vec3::new(b * t.cos(), 0.0, a * t.sin()).normalize();
        for k in 0..TUBE {
            let p = std::f64::consts::TAU * k as Real / TUBE as Real;
            out.push(c + (n * p.cos() + Vec3::y() * p.sin()) * RHO);
        }
    }
    out
}

/// The tube's triangles, offset by `first`, wound outward.
fn tube_triangles(first: u32) -> Vec<[u32; 3]> {
    let id = |i: usize, k: usize| first + ((i % AROUND) * TUBE + k % TUBE) as u32;
    let mut t = Vec::new();
    for i in 0..AROUND {
        for k in 0..TUBE {
            let (a, b, c, d) = (id(i, k), id(i + 1, k), id(i + 1, k + 1), id(i, k + 1));
            t.push([a, c, b]);
            t.push([a, d, c]);
        }
    }
    // Outward: the signed volume of the closed tube must be positive.
    let p = tube(0.3, 0.2, 0.0, 0.0);
    let vol: Real = t
        .iter()
        .map(|f| {
            let [x, y, z] = f.map(|v| p[(v - first) as usize]);
            x.dot(&y.cross(&z))
        })
        .sum();
    if vol < 0.0 {
        for f in &mut t {
            f.swap(1, 2);
        }
    }
    t
}

/// What the tie needs of the dressing.
pub struct CordJob<'a> {
    pub m: &'a Measurements,
    pub body: &'a [Vec3],
    pub body_triangles: &'a [[u32; 3]],
    /// The cord row's vertices (the pattern's cord level) and the height they go to.
    pub row: &'a [u32],
    pub goal: Real,
    /// Vertices not on the torso (sleeves), left out of the cord's start size.
    pub torso: &'a [bool],
    pub thickness: Real,
}

/// Ties the kimono in `frame` over `frames` frames (then 20 to settle) with `solver`; returns the
/// number of frames stepped.
pub fn tie(
    job: &CordJob,
    solver: &mut dyn tryon_core::stages::ClothSolver,
    frame: &mut CoarseFrame,
    frames: usize,
    fx: &tryon_pipeline::scene::EffectsSection,
    make: &dyn Fn(
        Vec<tryon_core::interact::Handle>,
    ) -> Box<dyn tryon_core::stages::ClothSolver>,
) -> usize {
    let n_body = job.body.len();
    let y0 = job.row.iter().map(|&v| frame.positions[v as usize].y).sum::<Real>()
        / job.row.len().max(1) as Real;
    let ease: Real = std::env::var("EASE").ok().and_then(|s| s.parse().ok()).unwrap_or(0.015);
    let end = |y: Real| {
        let s = tryon_core::measure::profile(&job.m.torso_keys(48), y);
        [s[0] + ease + RHO, s[1] + ease + RHO, s[2]]
    };
    // The start: the end ellipse scaled until every torso vertex near the height is inside.
    let e0 = end(y0);
    let mut scale: Real = 1.0;
    for (v, p) in frame.positions.iter().enumerate() {
        if job.torso[v] && (p.y - y0).abs() < 0.05 {
            let r = ((p.x / e0[0]).powi(2) + ((p.z - e0[2]) / e0[1]).powi(2)).sqrt();
            scale = scale.max(r);
        }
    }
    let s0 = scale + (0.03 + RHO) / e0[0].min(e0[1]);
    eprintln!("cord: row at {y0:.3} -> {:.3}; start scale {s0:.2}", job.goal);
    // The row is lifted straight up (held) over the first half with the cord open around it;
    // then let go, held up softly, while the cord closes at its height.
    let height = |tau: Real| y0 + (job.goal - y0) * smoothstep((tau / 0.5).min(1.0));
    let at = |tau: Real| {
        let y = height(tau);
        let e = end(y);
        let s = s0 + (1.0 - s0) * smoothstep(((tau - 0.5) / 0.4).clamp(0.0, 1.0));
        tube(e[0] * s, e[1] * s, e[2], y)
    };
    let start: Vec<Vec3> = job.row.iter().map(|&v| frame.positions[v as usize]).collect();
    let handles = job
        .row
        .iter()
        .zip(&start)
        .map(|(&v, p)| tryon_core::interact::Handle {
            particle: v,
            path: vec![(0.0, *p)],
        })
        .collect();
    let mut lifter = Some(make(handles));
    let mut positions: Vec<Vec3> = job.body.to_vec();
    positions.extend(at(0.0));
    let mut tris = job.body_triangles.to_vec();
    tris.extend(tube_triangles(n_body as u32));
    let mesh = PolyMesh::from_triangles(positions.clone(), &tris).expect("body and cord");
    let mut collider =
        tryon_pipeline::build::collider(CollisionMethod::Exact, &mesh, job.thickness, fx)
            .expect("collider");
    let k: Real = std::env::var("LIFT").ok().and_then(|s| s.parse().ok()).unwrap_or(2e3);
    let dt = 1.0 / 30.0;
    let mut prev = positions.clone();
    for f in 1..=frames + 20 {
        let tau = (f as Real / frames as Real).min(1.0);
        let mut now = job.body.to_vec();
        now.extend(at(tau));
        let vel = now.iter().zip(&prev).map(|(a, b)| (a - b) / dt).collect();
        collider.update(&BodyFrame {
            time: f as Real * dt,
            positions: now.clone(),
            velocities: vel,
        });
        prev = now;
        let y = height(tau);
        let up: Vec<Vec3> = job
            .row
            .iter()
            .map(|&v| {
                let p = frame.positions[v as usize];
                Vec3::new(p.x, y, p.z)
            })
            .collect();
        let rep = match lifter.as_mut() {
            Some(l) if tau < 0.5 => {
                let held: Vec<Vec3> = start.iter().map(|p| Vec3::new(p.x, y, p.z)).collect();
                l.hold_handles(0, &held);
                l.step_frame(frame, dt, collider.as_mut())
            }
            _ => {
                lifter = None;
                solver.anchor(job.row, &up, k);
                solver.step_frame(frame, dt, collider.as_mut())
            }
        };
        if f % 10 == 0 {
            let lag = job
                .row
                .iter()
                .map(|&v| (frame.positions[v as usize].y - y).abs())
                .sum::<Real>()
                / job.row.len().max(1) as Real;
            let hem = frame.positions.iter().map(|p| p.y).fold(Real::INFINITY, Real::min);
            eprintln!(
                "cord {f} tau {tau:.2} row lag {lag:.3} lowest {hem:.3} substeps {} rollbacks {}",
                rep.substeps, rep.rollbacks
            );
        }
    }
    frames + 20
}
