//! A short-sleeved shirt cut from the body itself: the body's torso between the hem and the neck and
//! its arms down to the sleeves' length are kept, moved off the skin (a clearance along the
//! normal, the torso below the armpit out to an elliptic section whose girth is the body's plus the
//! ease, so the shirt hangs from the bust instead of hugging the waist; the sleeves out from the arm
//! by their ease) and split into four triangles per triangle as often as asked. The rings and arm
//! loops the body is lofted from are planar, so cutting across them leaves four clean openings:
//! neck, hem and two sleeves.

use crate::gusset;
use crate::patterns::{Garment, PatternError, check};
use std::collections::HashMap;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::{Measurements, profile, smoothstep};
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::stages::Collider;

/// Settings of the shirt.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShirtParams {
    /// Ease (extra girth) at bust, waist and hip, m.
    pub ease: [Real; 3],
    /// Extra girth of the sleeves over the arm's, m.
    pub sleeve_ease: Real,
    /// Length of the sleeves from the shoulder joint along the arm, m.
    pub sleeve_length: Real,
    /// Height of the hem below the hip landmark, m (negative: above).
    pub hem_below_hip: Real,
    /// Rounds of splitting each triangle into four (each quadruples the triangles; the mannequin's
    /// surface at 0 gives about 3,600).
    pub subdivisions: u32,
}

impl Default for ShirtParams {
    fn default() -> Self {
        ShirtParams {
            ease: [0.10, 0.16, 0.12],
            sleeve_ease: 0.08,
            sleeve_length: 0.2,
            hem_below_hip: 0.02,
            subdivisions: 0,
        }
    }
}

/// An arm of the body in its rest pose: where the upper arm turns and the unit direction toward the
/// elbow.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arm {
    pub root: Vec3,
    pub dir: Vec3,
}

/// The body a shirt is cut from: its rest mesh, which arm (0 or 1) each vertex belongs to, if any,
/// and the arms.
#[derive(Clone, Debug, PartialEq)]
pub struct ShirtBody<'a> {
    pub mesh: &'a PolyMesh,
    pub arm_of: &'a [Option<u8>],
    pub arms: [Arm; 2],
}

/// Clearance of the cloth above the skin where no ease moves it farther, m at the default figure.
const CLEARANCE: Real = 0.006;

/// How far from the crease under each arm the cut surface is taken out for a gusset (m at the
/// default figure).
const GUSSET: Real = 0.035;

/// Below the armpit the torso's ease comes in from this far down over as much again (m at the
/// default figure): higher, it would push the shirt's side into the arm hanging beside it.
const ARM_CLEAR: Real = 0.04;

/// Where the sleeve's ease has fully come in, along the arm from where it leaves the torso, m.
const SLEEVE_RAMP: Real = 0.06;

/// The shirt cut from `body` for `m`'s measurements.
///
/// `collider` holds the body: whatever the shaping or a split left closer to it than the clearance
/// is lifted out along the surface's normal.
pub fn shirt(
    m: &Measurements,
    body: &ShirtBody,
    collider: &mut dyn Collider,
    p: &ShirtParams,
) -> Result<Garment, PatternError> {
    m.validate()?;
    for (name, v) in [
        ("ease.bust", p.ease[0]),
        ("ease.waist", p.ease[1]),
        ("ease.hip", p.ease[2]),
        ("sleeve_ease", p.sleeve_ease),
    ] {
        check(name, v, 0.0, 0.5)?;
    }
    check("sleeve_length", p.sleeve_length, 0.1, 0.7)?;
    check("hem_below_hip", p.hem_below_hip, -0.2, 0.05)?;
    check("subdivisions", p.subdivisions as Real, 0.0, 3.0)?;
    if body.arm_of.len() != body.mesh.positions.len() {
        return Err(PatternError::Cut(format!(
            "{} arm labels for {} body vertices",
            body.arm_of.len(),
            body.mesh.positions.len()
        )));
    }
    if let Some(v) = body.arm_of.iter().position(|a| a.is_some_and(|a| a > 1)) {
        return Err(PatternError::Cut(format!(
            "body vertex {v} is labelled arm {}: only arms 0 and 1 exist",
            body.arm_of[v].unwrap_or(0)
        )));
    }
    body.mesh
        .validate()
        .map_err(|e| PatternError::Cut(format!("body mesh: {e}")))?;
    let lm = m.landmarks();
    let sc = m.scale();
    let hem = lm.hip - p.hem_below_hip * sc;
    let neck = lm.neck - 0.004 * sc;
    let along = |v: usize, a: u8| {
        let arm = body.arms[a as usize];
        (body.mesh.positions[v] - arm.root).dot(&arm.dir)
    };
    let keep: Vec<bool> = (0..body.mesh.positions.len())
        .map(|v| {
            let y = body.mesh.positions[v].y;
            let sleeve = body.arm_of[v].is_none_or(|a| along(v, a) <= p.sleeve_length * sc);
            y >= hem && y <= neck && sleeve
        })
        .collect();
    let mut mesh = cut(body.mesh, &keep);
    let loops = crate::boundary_loops(&mesh).map_err(|e| PatternError::Cut(e.to_string()))?;
    let pieces = crate::components(&mesh);
    if loops.len() != 4 || pieces.iter().any(|&c| c != 0) {
        return Err(PatternError::Cut(format!(
            "{} openings in {} pieces, not 4 (neck, hem, two sleeves) in one: \
             the body is not shaped like the mannequin",
            loops.len(),
            pieces.iter().max().map_or(0, |c| c + 1)
        )));
    }
    let old_of: Vec<usize> = (0..keep.len()).filter(|&v| keep[v]).collect();
    let label = |i: u32| body.arm_of[old_of[i as usize]];
    let hole = sleeve_starts(&mesh, &label, &body.arms);
    let normals = vertex_normals(&mesh);
    let keys = m.torso_keys(48);
    let ease = |y: Real| {
        let e = [
            (lm.hip, [p.ease[2]]),
            (lm.waist, [p.ease[1]]),
            (lm.bust, [p.ease[0]]),
        ];
        profile(&e, y)[0]
    };
    for (i, q) in mesh.positions.iter_mut().enumerate() {
        let v = old_of[i];
        *q += normals[i] * (CLEARANCE * sc);
        match body.arm_of[v] {
            Some(a) => {
                let arm = body.arms[a as usize];
                let s = (*q - arm.root).dot(&arm.dir);
                let radial = *q - arm.root - arm.dir * s;
                let r = radial.norm();
                let ramp = smoothstep((s - hole[a as usize]) / (SLEEVE_RAMP * sc));
                // The ease goes over the arm, away from the torso beside it: the sleeve hangs
                // from there when the cloth moves.
                let up = (Vec3::y() - arm.dir * arm.dir.y).try_normalize(1e-9);
                let top = up.map_or(1.0, |u| 0.5 * (1.0 + radial.dot(&u) / r.max(1e-12)));
                let grow = p.sleeve_ease / std::f64::consts::TAU * ramp * top;
                if r > 1e-9 {
                    *q += radial * (grow / r);
                }
            }
            None => {
                let w = smoothstep((lm.armpit - ARM_CLEAR * sc - q.y) / (ARM_CLEAR * sc));
                let [a, b, c] = profile(&keys, q.y.max(lm.hip));
                let grow = ease(q.y) / std::f64::consts::TAU;
                let (a, b) = (a + grow, b + grow);
                let e = ((q.x / a).powi(2) + ((q.z - c) / b).powi(2)).sqrt();
                if w > 0.0 && e > 1e-9 && e < 1.0 {
                    let out = Vec3::new(q.x / e, q.y, c + (q.z - c) / e);
                    *q += (out - *q) * w;
                }
            }
        }
    }
    let labels: Vec<Option<u8>> = old_of.iter().map(|&v| body.arm_of[v]).collect();
    let arms = body.arms.map(|a| (a.root, a.dir));
    let (mut mesh, _) = gusset::underarm_gussets(&mesh, &labels, &arms, GUSSET * sc)?;
    lift(&mut mesh, collider, CLEARANCE * sc);
    for _ in 0..p.subdivisions {
        mesh = split_in_four(&mesh);
        // A new midpoint on a chord across a convex part of the body may lie inside it.
        lift(&mut mesh, collider, CLEARANCE * sc);
    }
    Ok(Garment {
        name: "shirt".into(),
        mesh,
    })
}

/// Each vertex closer to the body than `clearance` (or inside it) moved out along its normal, a
/// millimetre at a time up to 5 cm, until it is that far. Moving each to its closest point outside
/// would gather the vertices of a crease onto one line.
fn lift(mesh: &mut PolyMesh, collider: &mut dyn Collider, clearance: Real) {
    let normals = vertex_normals(mesh);
    for (x, n) in mesh.positions.iter_mut().zip(&normals) {
        for _ in 0..50 {
            match collider.signed_distance(x) {
                Some(d) if d < clearance => *x += n * 0.001,
                _ => break,
            }
        }
    }
}

/// Where each sleeve leaves the torso, along its arm: the mean of `along` over the arm's vertices
/// that share a triangle with the torso's (0 for an arm that has none).
fn sleeve_starts(
    mesh: &PolyMesh,
    label: &impl Fn(u32) -> Option<u8>,
    arms: &[Arm; 2],
) -> [Real; 2] {
    let mut sum = [(0.0, 0usize); 2];
    let (tris, _) = mesh.triangulate();
    for t in &tris {
        if !t.iter().any(|&v| label(v).is_none()) {
            continue;
        }
        for &v in t {
            if let Some(a) = label(v) {
                let arm = arms[a as usize];
                sum[a as usize].0 += (mesh.positions[v as usize] - arm.root).dot(&arm.dir);
                sum[a as usize].1 += 1;
            }
        }
    }
    sum.map(|(s, n)| if n > 0 { s / n as Real } else { 0.0 })
}

/// The triangles of `mesh` whose vertices are all kept, on the kept vertices (in their order).
pub(crate) fn cut(mesh: &PolyMesh, keep: &[bool]) -> PolyMesh {
    let mut new_of = vec![u32::MAX; keep.len()];
    let mut positions = Vec::new();
    for (v, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
        new_of[v] = positions.len() as u32;
        positions.push(mesh.positions[v]);
    }
    let (tris, _) = mesh.triangulate();
    let faces = tris
        .iter()
        .filter(|t| t.iter().all(|&v| keep[v as usize]))
        .map(|t| Face::Tri(t.map(|v| new_of[v as usize])))
        .collect();
    PolyMesh { positions, faces }
}

/// Area-weighted unit vertex normals of a triangle mesh (zero where a vertex has no area).
fn vertex_normals(mesh: &PolyMesh) -> Vec<Vec3> {
    let mut n = vec![Vec3::zeros(); mesh.positions.len()];
    let (tris, _) = mesh.triangulate();
    for t in &tris {
        let x = t.map(|v| mesh.positions[v as usize]);
        let a = (x[1] - x[0]).cross(&(x[2] - x[0]));
        for &v in t {
            n[v as usize] += a;
        }
    }
    n.iter()
        .map(|a| a.try_normalize(1e-30).unwrap_or_else(Vec3::zeros))
        .collect()
}

/// Each triangle split into four at its edges' midpoints (a conforming mesh stays conforming).
pub fn split_in_four(mesh: &PolyMesh) -> PolyMesh {
    let mut positions = mesh.positions.clone();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
    let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
        *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
            positions.push((positions[a as usize] + positions[b as usize]) * 0.5);
            (positions.len() - 1) as u32
        })
    };
    let (tris, _) = mesh.triangulate();
    let mut faces = Vec::with_capacity(4 * tris.len());
    for [a, b, c] in tris {
        let ab = midpoint(a, b, &mut positions);
        let bc = midpoint(b, c, &mut positions);
        let ca = midpoint(c, a, &mut positions);
        faces.extend([
            Face::Tri([a, ab, ca]),
            Face::Tri([ab, b, bc]),
            Face::Tri([ca, bc, c]),
            Face::Tri([ab, bc, ca]),
        ]);
    }
    PolyMesh { positions, faces }
}

#[cfg(test)]
#[path = "shirt_tests.rs"]
mod tests;
