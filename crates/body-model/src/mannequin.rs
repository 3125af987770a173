//! The parametric mannequin: a closed, manifold triangle body built from tailor's measurements, with a
//! 22-joint skeleton and smooth 4-influence skinning weights, standing in an A-pose (upper arms 45
//! degrees below horizontal, facing +Z, feet on y = 0).
//!
//! The surface is lofted from rings: a torso tube (crotch to the top of the head) whose cross-sections
//! are ellipses scaled so that the rings at the hip, waist and bust heights have exactly the requested
//! girths; two legs split off the crotch ring along a seam (each leg's first loop is half the crotch
//! ring plus the seam, so the surface stays manifold); and two arms leaving through holes cut in the
//! torso's side, each arm's first loop being the hole's boundary. Hands, head and soles are closed by
//! fans. Weights blend along each limb between consecutive joints and from the torso into each limb.

use crate::skin::SkinWeights;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::{Landmarks, MeasureError, Measurements, profile, smoothstep};
use tryon_core::mesh::{Face, PolyMesh};
use tryon_core::pose::Skeleton;

/// Joint names of the mannequin's skeleton (parents come first).
pub const JOINT_NAMES: [&str; 22] = tryon_core::pose::mannequin_joints::ALL;
const PARENTS: [Option<usize>; 22] = [
    None,
    Some(0),
    Some(1),
    Some(2),
    Some(3),
    Some(4),
    Some(3),
    Some(6),
    Some(7),
    Some(8),
    Some(3),
    Some(10),
    Some(11),
    Some(12),
    Some(0),
    Some(14),
    Some(15),
    Some(16),
    Some(0),
    Some(18),
    Some(19),
    Some(20),
];
const PELVIS: usize = 0;
const SPINE: [usize; 5] = [1, 2, 3, 4, 5];
/// Clavicle, upper-arm, forearm and hand joints of the left (0) and right (1) arm.
const ARM: [[usize; 4]; 2] = [[6, 7, 8, 9], [10, 11, 12, 13]];
/// Thigh, shin, foot and toe joints of the left (0) and right (1) leg.
const LEG: [[usize; 4]; 2] = [[14, 15, 16, 17], [18, 19, 20, 21]];

/// The angle of the rest pose's upper arms below horizontal (degrees).
pub const REST_ARM_ANGLE_DEG: Real = 45.0;
/// Samples around a torso ring (a multiple of 4: front and back centres are samples).
const RING: usize = 48;
/// Interior vertices of the crotch seam between the legs.
const SEAM: usize = 7;
/// Half-width of an arm hole in torso samples.
const HOLE_HALF: usize = 5;

/// A body built from measurements: mesh, skeleton and skinning weights.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Mannequin {
    pub measurements: Measurements,
    pub landmarks: Landmarks,
    /// Closed triangle mesh in the rest pose (outward-facing, counter-clockwise).
    pub mesh: PolyMesh,
    pub skeleton: Skeleton,
    /// Global joint positions in the rest pose.
    pub joint_rest: Vec<Vec3>,
    pub skin: SkinWeights,
}

/// Influences being accumulated for one vertex (merged and cut to 4 at the end).
type Infl = Vec<(usize, Real)>;

#[derive(Default, serde::Serialize, serde::Deserialize)]
struct Builder {
    pos: Vec<Vec3>,
    infl: Vec<Infl>,
    tris: Vec<[u32; 3]>,
}

impl Builder {
    fn vertex(&mut self, p: Vec3, w: Infl) -> u32 {
        self.pos.push(p);
        self.infl.push(w);
        (self.pos.len() - 1) as u32
    }

    /// Quads between two closed loops of equal length, facing away from the axis through their
    /// centroids. `skip(i)` leaves out quad i (a hole).
    fn strip(&mut self, a: &[u32], b: &[u32], skip: impl Fn(usize) -> bool) {
        let n = a.len();
        let ca = centroid(&self.pos, a);
        let cb = centroid(&self.pos, b);
        let axis = (cb - ca).try_normalize(1e-12).unwrap_or(Vec3::y());
        let mut score = 0.0;
        for i in 0..n {
            let q = [a[i], a[(i + 1) % n], b[(i + 1) % n], b[i]].map(|v| self.pos[v as usize]);
            let nrm = (q[2] - q[0]).cross(&(q[3] - q[1]));
            let mid = (q[0] + q[1] + q[2] + q[3]) / 4.0 - ca;
            score += nrm.dot(&(mid - axis * mid.dot(&axis)));
        }
        for i in (0..n).filter(|&i| !skip(i)) {
            let (a0, a1, b1, b0) = (a[i], a[(i + 1) % n], b[(i + 1) % n], b[i]);
            if score >= 0.0 {
                self.tris.push([a0, a1, b1]);
                self.tris.push([a0, b1, b0]);
            } else {
                self.tris.push([a0, b1, a1]);
                self.tris.push([a0, b0, b1]);
            }
        }
    }

    /// Closes a loop with a fan to `apex`, facing `outward`.
    fn fan(&mut self, ring: &[u32], apex: u32, outward: Vec3) {
        let n = ring.len();
        let c = self.pos[apex as usize];
        let mut score = 0.0;
        for i in 0..n {
            let (p, q) = (
                self.pos[ring[i] as usize],
                self.pos[ring[(i + 1) % n] as usize],
            );
            score += (p - c).cross(&(q - c)).dot(&outward);
        }
        for i in 0..n {
            let (p, q) = (ring[i], ring[(i + 1) % n]);
            self.tris.push(if score >= 0.0 {
                [apex, p, q]
            } else {
                [apex, q, p]
            });
        }
    }
}

fn centroid(pos: &[Vec3], ids: &[u32]) -> Vec3 {
    ids.iter().map(|&v| pos[v as usize]).sum::<Vec3>() / ids.len().max(1) as Real
}

/// Heights from `y0` to `y1` (both included) at about `step` apart.
fn fill(y0: Real, y1: Real, step: Real) -> Vec<Real> {
    let n = ((y1 - y0).abs() / step).ceil().max(1.0) as usize;
    (0..=n)
        .map(|i| y0 + (y1 - y0) * i as Real / n as Real)
        .collect()
}

/// Hat weights along a chain of (joint, coordinate) with ascending coordinates.
fn chain_weights(chain: &[(usize, Real)], s: Real) -> Infl {
    if s <= chain[0].1 {
        return vec![(chain[0].0, 1.0)];
    }
    for w in chain.windows(2) {
        if s <= w[1].1 {
            let t = smoothstep((s - w[0].1) / (w[1].1 - w[0].1));
            return vec![(w[0].0, 1.0 - t), (w[1].0, t)];
        }
    }
    vec![(chain[chain.len() - 1].0, 1.0)]
}

fn blend(a: &Infl, b: &Infl, t: Real) -> Infl {
    let mut out: Infl = a.iter().map(|&(j, w)| (j, w * (1.0 - t))).collect();
    out.extend(b.iter().map(|&(j, w)| (j, w * t)));
    out
}

/// Unwrapped angles of `pts` around `centre` in the plane (e1, e2), then blended toward uniform
/// spacing by `u` (0 = as given, 1 = uniform), keeping the loop's direction.
fn loop_angles(pts: &[Vec3], centre: Vec3, e1: Vec3, e2: Vec3) -> Vec<Real> {
    let mut out = Vec::with_capacity(pts.len());
    let mut prev: Option<Real> = None;
    for p in pts {
        let d = p - centre;
        let mut a = d.dot(&e2).atan2(d.dot(&e1));
        if let Some(q) = prev {
            while a - q > std::f64::consts::PI {
                a -= std::f64::consts::TAU;
            }
            while a - q < -std::f64::consts::PI {
                a += std::f64::consts::TAU;
            }
        }
        prev = Some(a);
        out.push(a);
    }
    out
}

fn uniform_angle(angles: &[Real], i: usize) -> Real {
    let n = angles.len() as Real;
    let last = angles[angles.len() - 1];
    let total = if last >= angles[0] {
        std::f64::consts::TAU
    } else {
        -std::f64::consts::TAU
    };
    angles[0] + total * i as Real / n
}

impl Mannequin {
    /// Builds the mannequin for `m` (validated first).
    pub fn new(m: &Measurements) -> Result<Self, MeasureError> {
        m.validate()?;
        let lm = m.landmarks();
        let sc = m.scale();
        let sections = m.torso_keys(RING);
        let hip_sec = sections[1].1;
        let head_c = lm.chin + 0.42 * (lm.top - lm.chin);
        let section = |y: Real| -> [Real; 3] {
            let neck = profile(&sections, y);
            let (ry, below) = if y > head_c {
                (lm.top - head_c, false)
            } else {
                (head_c - (lm.chin - 0.035 * sc), true)
            };
            let e = (y - head_c) / ry;
            if e.abs() >= 1.0 {
                return neck;
            }
            let f = (1.0 - e * e).sqrt();
            let head = [0.078 * sc * f, 0.098 * sc * f, 0.008 * sc];
            if below {
                [neck[0].max(head[0]), neck[1].max(head[1]), head[2]]
            } else {
                head
            }
        };

        let mut b = Builder::default();
        // Torso ring heights: the control heights exactly, filled in between.
        let mut ys: Vec<Real> = Vec::new();
        for w in sections.windows(2) {
            let f = fill(w[0].0, w[1].0, 0.018 * sc);
            ys.extend_from_slice(&f[..f.len() - 1]);
        }
        ys.extend(fill(lm.chin, lm.top - 0.008 * sc, 0.014 * sc));
        let ring_of = |y: Real| ys.iter().position(|&v| (v - y).abs() < 1e-12);
        let (Some(hole_lo), Some(_)) = (ring_of(lm.armpit), ring_of(lm.shoulder)) else {
            unreachable!("control heights are torso rings")
        };
        let hole_hi = ys
            .iter()
            .rposition(|&y| y <= lm.shoulder - 0.012 * sc)
            .unwrap_or(hole_lo + 3);

        // Joints.
        let arm_dir = |side: usize| {
            let s = if side == 0 { 1.0 } else { -1.0 };
            let a = REST_ARM_ANGLE_DEG.to_radians();
            Vec3::new(s * a.cos(), -a.sin(), 0.0)
        };
        let mut joints = vec![Vec3::zeros(); 22];
        joints[PELVIS] = Vec3::new(0.0, lm.crotch + 0.06 * sc, 0.0);
        joints[SPINE[0]] = Vec3::new(0.0, lm.waist - 0.05 * sc, -0.01 * sc);
        joints[SPINE[1]] = Vec3::new(0.0, lm.waist + 0.08 * sc, -0.01 * sc);
        joints[SPINE[2]] = Vec3::new(0.0, lm.bust + 0.02 * sc, -0.01 * sc);
        joints[SPINE[3]] = Vec3::new(0.0, lm.neck - 0.01 * sc, -0.012 * sc);
        joints[SPINE[4]] = Vec3::new(0.0, lm.chin + 0.01 * sc, -0.005 * sc);
        let torso_chain: Vec<(usize, Real)> = std::iter::once(PELVIS)
            .chain(SPINE)
            .map(|j| (j, joints[j].y))
            .collect();

        // Torso vertices (interior hole vertices are dropped when compacting).
        let hole_centre_sample = [0usize, RING / 2];
        let in_hole_cols = |k: usize, side: usize| {
            let d = (k + RING - hole_centre_sample[side] + HOLE_HALF) % RING;
            d < 2 * HOLE_HALF
        };
        let mut rings: Vec<Vec<u32>> = Vec::with_capacity(ys.len());
        let hip_band = lm.hip - lm.crotch;
        for &y in &ys {
            let [a, bb, c] = section(y);
            let ring: Vec<u32> = (0..RING)
                .map(|k| {
                    let t = std::f64::consts::TAU * k as Real / RING as Real;
                    let p = Vec3::new(a * t.cos(), y, c + bb * t.sin());
                    let mut w = chain_weights(&torso_chain, y);
                    let legs = 0.5 * smoothstep((lm.hip - y) / hip_band);
                    if legs > 0.0 {
                        let left = (0.5 + p.x / (0.12 * sc)).clamp(0.0, 1.0);
                        w = blend(&w, &vec![(LEG[0][0], left), (LEG[1][0], 1.0 - left)], legs);
                    }
                    b.vertex(p, w)
                })
                .collect();
            rings.push(ring);
        }
        for r in 0..ys.len() - 1 {
            let skip = |k: usize| {
                r >= hole_lo && r < hole_hi && (in_hole_cols(k, 0) || in_hole_cols(k, 1))
            };
            let (lo, hi) = (rings[r].clone(), rings[r + 1].clone());
            b.strip(&lo, &hi, skip);
        }
        let apex = b.vertex(
            Vec3::new(0.0, lm.top, section(lm.top - 1e-6)[2]),
            vec![(SPINE[4], 1.0)],
        );
        b.fan(&rings[ys.len() - 1].clone(), apex, Vec3::y());

        // Arms through the holes.
        for side in 0..2 {
            let centre = hole_centre_sample[side];
            let col = |o: isize| ((centre as isize + o).rem_euclid(RING as isize)) as usize;
            let h = HOLE_HALF as isize;
            let mut hole: Vec<u32> = Vec::new();
            hole.extend((-h..=h).map(|o| rings[hole_lo][col(o)]));
            hole.extend((hole_lo + 1..=hole_hi).map(|r| rings[r][col(h)]));
            hole.extend((-h..h).rev().map(|o| rings[hole_hi][col(o)]));
            hole.extend((hole_lo + 1..hole_hi).rev().map(|r| rings[r][col(-h)]));
            let hc = centroid(&b.pos, &hole);
            let d = arm_dir(side);
            let e1 = Vec3::new(-d.y * d.x.signum(), d.x.abs(), 0.0);
            let e2 = Vec3::z();
            let [_, ua, fa, hand] = ARM[side];
            let len = m.arm_length;
            let hand_len = 0.105 * m.height;
            joints[ARM[side][0]] = Vec3::new(
                if side == 0 { 0.025 } else { -0.025 } * sc,
                lm.shoulder - 0.03 * sc,
                -0.01 * sc,
            );
            joints[ua] = hc - d * 0.035 * sc;
            joints[fa] = hc + d * (0.54 * len);
            joints[hand] = hc + d * len;
            // Around the hole, the torso follows the arm partly.
            for (i, w) in b.infl.iter_mut().enumerate().take(apex as usize) {
                let dist = (b.pos[i] - hc).norm() / (0.1 * sc);
                if dist < 1.0 {
                    let f = 0.5 * (1.0 - dist) * (1.0 - dist);
                    *w = blend(w, &vec![(ua, 1.0)], f);
                }
            }
            let arm_chain = [(ua, 0.54 * len - 0.04 * sc), (fa, 0.54 * len + 0.04 * sc)];
            let radius = |t: Real| -> [Real; 2] {
                let keys = [
                    (0.0, [0.05 * sc, 0.05 * sc]),
                    (0.54 * len, [0.036 * sc, 0.036 * sc]),
                    (0.66 * len, [0.038 * sc, 0.040 * sc]),
                    (len, [0.021 * sc, 0.028 * sc]),
                    (len + 0.35 * hand_len, [0.014 * sc, 0.043 * sc]),
                    (len + 0.9 * hand_len, [0.010 * sc, 0.034 * sc]),
                ];
                profile(&keys, t)
            };
            let hole_pts: Vec<Vec3> = hole.iter().map(|&v| b.pos[v as usize]).collect();
            let hole_w: Vec<Infl> = hole.iter().map(|&v| b.infl[v as usize].clone()).collect();
            let ang = loop_angles(&hole_pts, hc, e1, e2);
            let mut ts = fill(0.025 * sc, len, 0.02 * sc);
            ts.extend(
                fill(len, len + 0.9 * hand_len, 0.018 * sc)
                    .into_iter()
                    .skip(1),
            );
            let mut prev = hole.clone();
            for &t in &ts {
                let u = smoothstep(t / (0.09 * sc));
                let [rx, rz] = radius(t);
                let limb = if t < len - 0.03 * sc {
                    chain_weights(&arm_chain, t)
                } else {
                    chain_weights(&[(fa, len - 0.03 * sc), (hand, len + 0.03 * sc)], t)
                };
                let ring: Vec<u32> = (0..hole.len())
                    .map(|i| {
                        let phi = ang[i] + (uniform_angle(&ang, i) - ang[i]) * u;
                        let ell = hc + d * t + e1 * (rx * phi.cos()) + e2 * (rz * phi.sin());
                        let p = (hole_pts[i] + d * t) * (1.0 - u) + ell * u;
                        let w = blend(&hole_w[i], &limb, smoothstep(t / (0.08 * sc)));
                        b.vertex(p, w)
                    })
                    .collect();
                b.strip(&prev, &ring, |_| false);
                prev = ring;
            }
            let tip = b.vertex(hc + d * (len + hand_len), vec![(hand, 1.0)]);
            b.fan(&prev, tip, d);
        }

        // Legs off the crotch ring, split along a seam from front to back.
        let r0 = &rings[0];
        let (kf, kb) = (RING / 4, 3 * RING / 4);
        let (pf, pb) = (b.pos[r0[kf] as usize], b.pos[r0[kb] as usize]);
        let seam: Vec<u32> = (1..=SEAM)
            .map(|i| {
                let p = pf + (pb - pf) * (i as Real / (SEAM + 1) as Real);
                let w = blend(
                    &chain_weights(&torso_chain, p.y),
                    &vec![(LEG[0][0], 0.5), (LEG[1][0], 0.5)],
                    0.5,
                );
                b.vertex(p, w)
            })
            .collect();
        let xl_top = 0.5 * hip_sec[0];
        for side in 0..2 {
            let s = if side == 0 { 1.0 } else { -1.0 };
            let mut lp: Vec<u32> = vec![r0[kf]];
            if side == 0 {
                lp.extend(&seam);
                lp.extend((kb..RING).chain(0..kf).map(|k| r0[k]));
            } else {
                lp.extend((kf + 1..=kb).map(|k| r0[k]));
                lp.extend(seam.iter().rev());
            }
            let [thigh, shin, foot, toe] = LEG[side];
            let xl = |y: Real| {
                s * (xl_top
                    + (0.85 * xl_top - xl_top)
                        * smoothstep((lm.crotch - y) / (lm.crotch - lm.ankle)))
            };
            joints[thigh] = Vec3::new(xl(lm.crotch), lm.crotch + 0.06 * sc, 0.0);
            joints[shin] = Vec3::new(xl(lm.knee), lm.knee, 0.0);
            joints[foot] = Vec3::new(xl(lm.ankle), lm.ankle, 0.0);
            joints[toe] = Vec3::new(xl(lm.ankle), 0.015 * sc, 0.13 * sc);
            let r_thigh = (0.58 * m.hip / std::f64::consts::TAU).min(xl_top - 0.006 * sc);
            let leg_r = [
                (lm.ankle, [0.22 * m.hip / std::f64::consts::TAU]),
                (lm.knee - 0.12 * sc, [0.37 * m.hip / std::f64::consts::TAU]),
                (lm.knee, [0.35 * m.hip / std::f64::consts::TAU]),
                (lm.knee + 0.45 * (lm.crotch - lm.knee), [0.85 * r_thigh]),
                (lm.crotch, [r_thigh]),
            ];
            let leg_chain = [
                (foot, lm.ankle + 0.03 * sc),
                (shin, lm.ankle + 0.06 * sc),
                (shin, lm.knee - 0.05 * sc),
                (thigh, lm.knee + 0.05 * sc),
            ];
            let pts: Vec<Vec3> = lp.iter().map(|&v| b.pos[v as usize]).collect();
            let w0: Vec<Infl> = lp.iter().map(|&v| b.infl[v as usize].clone()).collect();
            let centre0 = Vec3::new(xl(lm.crotch), lm.crotch, 0.0);
            let ang = loop_angles(&pts, centre0, Vec3::x(), Vec3::z());
            let mut prev = lp.clone();
            let mut hs = fill(lm.crotch, lm.ankle, 0.02 * sc);
            hs.remove(0);
            // Foot: (height, z offset of the section's centre, x radius, z radius).
            let foot_rings = [
                (0.6 * lm.ankle, 0.02, 0.036, 0.06),
                (0.3 * lm.ankle, 0.05, 0.043, 0.10),
                (0.0, 0.065, 0.045, 0.125),
            ];
            let n_leg = hs.len();
            hs.extend(foot_rings.iter().map(|f| f.0));
            for (j, &y) in hs.iter().enumerate() {
                let u = smoothstep((lm.crotch - y) / (0.1 * sc));
                let (cz, rx, rz) = if j < n_leg {
                    let r = profile(&leg_r, y)[0];
                    (0.0, r, r)
                } else {
                    let f = foot_rings[j - n_leg];
                    (f.1 * sc, f.2 * sc, f.3 * sc)
                };
                let limb = chain_weights(&leg_chain, y);
                let ring: Vec<u32> = (0..lp.len())
                    .map(|i| {
                        let phi = ang[i] + (uniform_angle(&ang, i) - ang[i]) * u;
                        let ell = Vec3::new(xl(y) + rx * phi.cos(), y, cz + rz * phi.sin());
                        let flat = Vec3::new(pts[i].x, y, pts[i].z);
                        let p = flat * (1.0 - u) + ell * u;
                        let mut w = blend(&w0[i], &limb, u);
                        if j >= n_leg {
                            let tw = smoothstep((p.z - 0.06 * sc) / (0.06 * sc));
                            w = blend(&vec![(foot, 1.0)], &vec![(toe, 1.0)], tw);
                        }
                        b.vertex(p, w)
                    })
                    .collect();
                b.strip(&prev, &ring, |_| false);
                prev = ring;
            }
            let sole = centroid(&b.pos, &prev);
            let sole = b.vertex(sole, vec![(foot, 1.0)]);
            b.fan(&prev, sole, -Vec3::y());
        }
        Ok(Self::finish(b, joints, *m, lm))
    }

    /// Drops unused vertices, cuts influences to the strongest 4 and assembles the skeleton.
    fn finish(b: Builder, joints: Vec<Vec3>, m: Measurements, lm: Landmarks) -> Self {
        let mut map = vec![u32::MAX; b.pos.len()];
        for t in &b.tris {
            for &v in t {
                map[v as usize] = 0;
            }
        }
        let mut positions = Vec::new();
        let mut infl = Vec::new();
        for (i, slot) in map.iter_mut().enumerate() {
            if *slot == 0 {
                *slot = positions.len() as u32;
                positions.push(b.pos[i]);
                infl.push(b.infl[i].clone());
            }
        }
        let faces = b
            .tris
            .iter()
            .map(|t| Face::Tri(t.map(|v| map[v as usize])))
            .collect();
        let skin = SkinWeights::from_influences(&infl);
        let rest_offsets = (0..joints.len())
            .map(|j| match PARENTS[j] {
                Some(p) => joints[j] - joints[p],
                None => joints[j],
            })
            .collect();
        Mannequin {
            measurements: m,
            landmarks: lm,
            mesh: PolyMesh { positions, faces },
            skeleton: Skeleton {
                names: JOINT_NAMES.iter().map(|s| s.to_string()).collect(),
                parents: PARENTS.to_vec(),
                rest_offsets,
            },
            joint_rest: joints,
            skin,
        }
    }
}
