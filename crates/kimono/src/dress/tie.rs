//! The tie: rows of the kimono are drawn by soft springs (the solver's anchors) onto rings
//! around the body, as hands and cords would: the cord's row to the cord's height above the
//! ankle, the ohashori band's head just above it (the cloth between hangs as the fold), the hem
//! to the ankle, and, when asked, the row that lands 7 cm under the bust onto a ring there (the
//! datejime, an under-bust tie, so the fronts cross at the chest instead of opening in a V to
//! the waist). Each panel's row is laid by arc length from the back centre, so the left
//! front wraps over the right. Springs, not held vertices: a held vertex led through another
//! layer would cross it (docs/decisions, *kimono dressing*), a spring gives way.

use crate::KimonoMesh;
use crate::mesh::sub;
use std::f64::consts::TAU;
use tryon_core::math::{Real, Vec3};
use tryon_core::measure::{Measurements, smoothstep};

/// The cord's room over the body (m) and the left front's over the right.
const EASE: Real = 0.02;
const LAYER: Real = 0.006;

/// Elliptic torso section at `y` grown by `grow`: half-width, half-depth, centre z.
fn section(m: &Measurements, y: Real, grow: Real) -> [Real; 3] {
    let s = tryon_core::measure::profile(&m.torso_keys(48), y);
    [s[0] + grow, s[1] + grow, s[2]]
}

/// The point at parameter angle `t` (0 = back centre, positive toward the wearer's left).
fn ring_point(e: [Real; 3], y: Real, t: Real) -> Vec3 {
    Vec3::new(e[0] * t.sin(), y, e[2] - e[1] * t.cos())
}

/// Parameter angle at arc length `u` from the back centre (signed, may pass the front centre).
fn angle_at_arc(e: [Real; 3], u: Real) -> Real {
    let n = 720;
    let step_t = TAU / n as Real;
    let (mut arc, mut prev) = (0.0, ring_point(e, 0.0, 0.0));
    let goal = u.abs();
    for k in 1..=2 * n {
        let t = step_t * k as Real;
        let p = ring_point(e, 0.0, t);
        let step = (p - prev).norm();
        if arc + step >= goal {
            let f = (goal - arc) / step.max(1e-12);
            return u.signum() * (t - step_t * (1.0 - f));
        }
        arc += step;
        prev = p;
    }
    u.signum() * 2.0 * TAU
}

/// What the tie works on.
#[derive(Debug)]
pub struct TieJob<'a> {
    pub m: &'a Measurements,
    pub rest: &'a [Vec3],
    pub base: &'a KimonoMesh,
    pub levels: &'a crate::Levels,
    pub frames: usize,
    pub hold_frames: usize,
    pub stiffness: Real,
    /// Whether the fourth row, under the bust, is tied.
    pub under_bust: bool,
}

/// One held vertex's way: from where it is to its place on its row's ring.
#[derive(Clone, Copy)]
struct Plan {
    from: Vec3,
    angle: Real,
    grow: Real,
    arc: Real,
    layer: Real,
    goal_y: Real,
    level: Option<Real>,
    ease: Real,
}

impl Plan {
    fn at(&self, m: &Measurements, tau: Real) -> Vec3 {
        let grow_end = self.ease + self.layer * LAYER;
        let e_end = section(m, self.level.unwrap_or(self.goal_y), grow_end);
        let t1 = angle_at_arc(e_end, self.arc);
        let y = self.from.y + (self.goal_y - self.from.y) * tau;
        let g0 = self.grow + self.layer * LAYER;
        let e = section(m, self.level.unwrap_or(y), g0 + (grow_end - g0) * tau);
        ring_point(e, y, self.angle + (t1 - self.angle) * tau)
    }
}

/// The torso's vertices (not sleeves, not collar) nearest to height `want` on the pattern, one
/// per column.
fn row(job: &TieJob, want: Real) -> Vec<u32> {
    let subs = job.base.sub_mesh_vertices();
    let in_sub = |k: u8, v: u32| subs[k as usize].binary_search(&v).is_ok();
    let torso = |v: u32| {
        ![sub::RIGHT_SLEEVE, sub::LEFT_SLEEVE, sub::COLLAR]
            .iter()
            .any(|&k| in_sub(k, v))
    };
    let mut best: Vec<((i64, i64), u32)> = Vec::new();
    for v in 0..job.rest.len() as u32 {
        let p = job.rest[v as usize];
        if !torso(v) || (p.y - want).abs() > 0.03 {
            continue;
        }
        let key = ((p.x * 1e4).round() as i64, (p.z * 1e4).round() as i64);
        match best.iter_mut().find(|e| e.0 == key) {
            Some(e) if (p.y - want).abs() < (job.rest[e.1 as usize].y - want).abs() => e.1 = v,
            Some(_) => {}
            None => best.push((key, v)),
        }
    }
    best.iter().map(|e| e.1).collect()
}

/// Whether `v` is on the wearer's left: the left front, or nearest a left-front vertex.
fn left_side(job: &TieJob, subs: &[Vec<u32>], v: u32) -> bool {
    let in_sub = |k: u8, v: u32| subs[k as usize].binary_search(&v).is_ok();
    let front = |w: u32| {
        !in_sub(sub::COLLAR, w) && (in_sub(sub::LEFT_FRONT, w) || in_sub(sub::RIGHT_FRONT, w))
    };
    if front(v) {
        return in_sub(sub::LEFT_FRONT, v);
    }
    let p = job.rest[v as usize];
    (0..job.rest.len() as u32)
        .filter(|&w| front(w))
        .min_by(|&a, &b| {
            (job.rest[a as usize] - p)
                .norm()
                .total_cmp(&(job.rest[b as usize] - p).norm())
        })
        .is_some_and(|w| in_sub(sub::LEFT_FRONT, w))
}

/// The held vertices, their plans and each row's size.
fn plan(job: &TieJob, positions: &[Vec3]) -> (Vec<u32>, Vec<Plan>, [usize; 4]) {
    let lm = job.m.landmarks();
    let lv = job.levels;
    let hem = job.rest.iter().map(|v| v.y).fold(Real::INFINITY, Real::min);
    let (y_hem, subs) = (lm.ankle + 0.01, job.base.sub_mesh_vertices());
    let y_cord = y_hem + lv.outer[2];
    let zr = job.rest.iter().map(|p| p.z).sum::<Real>() / job.rest.len().max(1) as Real;
    // The under-bust tie (datejime): the pattern's row that lands 7 cm under the bust, drawn
    // onto a ring there, the left front over the right, so the fronts cross at the chest.
    let y_ub = lm.bust - 0.07;
    let ub_pattern = hem + lv.outer[3] + (y_ub - (y_cord + 0.02));
    let rows = [
        (row(job, hem + lv.outer[2]), y_cord, None, EASE),
        (
            row(job, hem + lv.outer[3]),
            y_cord + 0.02,
            None,
            EASE + 0.012,
        ),
        (row(job, hem), y_hem, Some(lm.hip), 0.02),
        (
            match job.under_bust {
                true => row(job, ub_pattern),
                false => Vec::new(),
            },
            y_ub,
            None,
            EASE,
        ),
    ];
    let (mut held, mut plans, mut sizes) = (Vec::new(), Vec::<Plan>::new(), [0; 4]);
    for (k, (verts, goal_y, level, ease)) in rows.into_iter().enumerate() {
        sizes[k] = verts.len();
        let seam = verts
            .iter()
            .filter(|&&v| job.rest[v as usize].z < zr)
            .map(|&v| job.rest[v as usize].x)
            .fold(0.0, Real::max);
        let first = plans.len();
        for v in verts {
            let f = job.rest[v as usize];
            let (arc, layer) = if f.z < zr {
                (f.x, 0.0)
            } else if left_side(job, &subs, v) {
                (seam + (seam - f.x), 1.0)
            } else {
                (-(seam + (seam + f.x)), 0.0)
            };
            let p = positions[v as usize];
            let e = section(job.m, level.unwrap_or(p.y), 0.0);
            let mut angle = p.x.atan2(-(p.z - e[2]));
            if arc > 0.0 && angle < -0.5 {
                angle += TAU;
            }
            if arc < 0.0 && angle > 0.5 {
                angle -= TAU;
            }
            let r_body = ring_point(e, p.y, angle) - Vec3::new(0.0, p.y, e[2]);
            let r_now = Vec3::new(p.x, 0.0, p.z - e[2]).norm();
            let grow = (r_now - r_body.norm()).max(0.02);
            plans.push(Plan {
                from: p,
                angle,
                grow,
                arc,
                layer,
                goal_y,
                level,
                ease,
            });
            held.push(v);
        }
        // A row starts as one ring around its widest vertex.
        let widest = plans[first..]
            .iter()
            .map(|q| q.grow)
            .fold(0.0, Real::max)
            .min(0.15);
        plans[first..].iter_mut().for_each(|q| q.grow = widest);
    }
    (held, plans, sizes)
}

/// The tie's plan: the held rows' vertices and where each is drawn, frame by frame; a driver
/// anchors [`TiePlan::held`] to [`TiePlan::targets`] before each of [`TiePlan::frames`] steps.
#[derive(Clone)]
pub struct TiePlan {
    /// The held vertices, row after row (cord, band head, hem, under the bust).
    pub held: Vec<u32>,
    plans: Vec<Plan>,
    sizes: [usize; 4],
    m: Measurements,
    tie_frames: usize,
    /// Frames in all: drawn onto the rings, then held there.
    pub frames: usize,
    pub stiffness: Real,
}

impl std::fmt::Debug for TiePlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("TiePlan")
            .field("held", &self.held.len())
            .field("frames", &self.frames)
            .finish_non_exhaustive()
    }
}

impl TiePlan {
    /// The plan for the kimono whose vertices are at `positions` when the tie starts.
    pub fn new(job: &TieJob, positions: &[Vec3]) -> TiePlan {
        let (held, plans, sizes) = plan(job, positions);
        TiePlan {
            held,
            plans,
            sizes,
            m: *job.m,
            tie_frames: job.frames,
            frames: job.frames + job.hold_frames,
            stiffness: job.stiffness,
        }
    }

    /// The held vertices' targets at frame `f` of the tie (0: where the rows start).
    pub fn targets(&self, f: usize) -> Vec<Vec3> {
        let tau = match f {
            0 => 0.0,
            _ => smoothstep((f as Real / self.tie_frames.max(1) as Real).min(1.0)),
        };
        self.plans.iter().map(|p| p.at(&self.m, tau)).collect()
    }

    /// The first three rows' mean distance from their rings (cord, band head, hem) with the
    /// kimono at `positions` and the targets of the last frame, and the vertices that stay tied
    /// in a scene (the cord's, the band head's and the under-bust rows').
    pub fn finish(&self, positions: &[Vec3], targets: &[Vec3]) -> ([Real; 3], Vec<u32>) {
        let (held, sizes) = (&self.held, self.sizes);
        let mut lag = [0.0; 3];
        let mut at = 0;
        for (k, n) in sizes.iter().take(3).enumerate() {
            let d = held[at..at + n]
                .iter()
                .zip(&targets[at..at + n])
                .map(|(&v, t)| (positions[v as usize] - t).norm());
            lag[k] = d.sum::<Real>() / (*n).max(1) as Real;
            at += n;
        }
        let mut tied = held[..sizes[0] + sizes[1]].to_vec();
        tied.extend_from_slice(&held[sizes[0] + sizes[1] + sizes[2]..]);
        tied.sort_unstable();
        tied.dedup();
        (lag, tied)
    }
}
