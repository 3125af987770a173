//! A drawn line followed across the mesh (Algorithm 1 step 1): each point snapped to the nearest
//! surface point, and each segment between two points traced from face to face along the plane
//! through both points that holds the surface normal there, recording every edge it crosses.

use crate::{FoldError, FoldLine};
use std::collections::HashMap;
use tryon_core::math::{Real, Vec3, closest_point_on_triangle};
use tryon_core::mesh::PolyMesh;

/// Where a line crosses a mesh edge: the point `a + t (b - a)` of the edge (a, b), a < b.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Crossing {
    pub a: u32,
    pub b: u32,
    pub t: Real,
    /// The line's segment (from its point `segment` to the next) that crosses here.
    pub segment: usize,
}

/// The crossings of every line, in order along each, and the source faces each line passes
/// through (the faces to be split into triangles).
pub(crate) struct Walked {
    pub tris: Vec<[u32; 3]>,
    pub tri_face: Vec<u32>,
    pub lines: Vec<Vec<Crossing>>,
    /// The triangles (of `tris`) each line passes through.
    pub visited: Vec<Vec<u32>>,
}

pub(crate) fn walk_all(
    mesh: &PolyMesh,
    lines: &[FoldLine],
    snap: Real,
) -> Result<Walked, FoldError> {
    let (tris, tri_face) = mesh.triangulate();
    let x = &mesh.positions;
    let mut across: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (k, t) in tris.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            across
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push(k as u32);
        }
    }
    let spheres = spheres(x, &tris);
    let mut around = vec![Vec::new(); x.len()];
    for (k, t) in tris.iter().enumerate() {
        for &v in t {
            around[v as usize].push(k as u32);
        }
    }
    let mut owner: HashMap<u32, usize> = HashMap::new();
    let mut out = Walked {
        tris: Vec::new(),
        tri_face,
        lines: Vec::new(),
        visited: Vec::new(),
    };
    for (f, l) in lines.iter().enumerate() {
        let snapped: Vec<(u32, Vec3)> = l
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| snap_point(x, &tris, &spheres, p, snap).ok_or(i))
            .collect::<Result<_, usize>>()
            .map_err(|point| FoldError::OffGarment {
                fold: f,
                point,
                distance: nearest_distance(x, &tris, &spheres, &l.points[point]),
                allowed: snap,
            })?;
        let mut w = Walker {
            x,
            tris: &tris,
            across: &across,
            around: &around,
            crossings: Vec::new(),
            visited: vec![snapped[0].0],
            cur: snapped[0].0,
            index: 0,
        };
        for (s, pair) in snapped.windows(2).enumerate() {
            w.index = s;
            w.segment(pair[0].1, pair[1])
                .map_err(|e| e.into_error(f, s))?;
        }
        if w.crossings.len() < 2 {
            return Err(FoldError::TooShort {
                fold: f,
                crossed: w.crossings.len(),
            });
        }
        for &t in &w.visited {
            if let Some(&other) = owner.get(&t)
                && other != f
            {
                return Err(FoldError::CrossesFold { fold: f, other });
            }
        }
        for &t in &w.visited {
            owner.insert(t, f);
        }
        out.lines.push(w.crossings);
        out.visited.push(w.visited);
    }
    out.tris = tris;
    Ok(out)
}

/// Each triangle's bounding sphere (centre, radius), for the nearest-triangle search.
fn spheres(x: &[Vec3], tris: &[[u32; 3]]) -> Vec<(Vec3, Real)> {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| x[v as usize]);
            let centre = (a + b + c) / 3.0;
            let r = (a - centre)
                .norm()
                .max((b - centre).norm())
                .max((c - centre).norm());
            (centre, r)
        })
        .collect()
}

/// The triangle nearest `p` and the nearest point on it, if within `snap`: started from the
/// triangle whose bounding sphere is nearest, then every triangle whose sphere could hold a
/// nearer point.
fn snap_point(
    x: &[Vec3],
    tris: &[[u32; 3]],
    spheres: &[(Vec3, Real)],
    p: &Vec3,
    snap: Real,
) -> Option<(u32, Vec3)> {
    let lower = |k: usize| ((p - spheres[k].0).norm() - spheres[k].1).max(0.0);
    let exact = |k: usize| {
        let [a, b, c] = tris[k].map(|v| x[v as usize]);
        let (q, _) = closest_point_on_triangle(p, &a, &b, &c);
        ((q - p).norm_squared(), k as u32, q)
    };
    let first = (0..tris.len()).min_by(|&i, &j| lower(i).total_cmp(&lower(j)))?;
    let mut best = exact(first);
    for k in 0..tris.len() {
        let l = lower(k);
        if l * l >= best.0 {
            continue;
        }
        let e = exact(k);
        if e.0 < best.0 {
            best = e;
        }
    }
    (best.0.sqrt() <= snap).then_some((best.1, best.2))
}

fn nearest_distance(x: &[Vec3], tris: &[[u32; 3]], s: &[(Vec3, Real)], p: &Vec3) -> Real {
    snap_point(x, tris, s, p, Real::INFINITY).map_or(Real::INFINITY, |(_, q)| (q - p).norm())
}

/// Why a segment could not be followed (made a [`FoldError`] with the fold and segment).
enum Stop {
    Edge,
    Crossed,
    Short,
}

impl Stop {
    fn into_error(self, fold: usize, segment: usize) -> FoldError {
        match self {
            Stop::Edge => FoldError::LeavesGarment { fold, segment },
            Stop::Crossed => FoldError::SelfCrossing { fold, segment },
            Stop::Short => FoldError::TooShort { fold, crossed: 0 },
        }
    }
}

struct Walker<'a> {
    x: &'a [Vec3],
    tris: &'a [[u32; 3]],
    across: &'a HashMap<(u32, u32), Vec<u32>>,
    /// Triangles around each vertex.
    around: &'a [Vec<u32>],
    crossings: Vec<Crossing>,
    visited: Vec<u32>,
    /// The triangle the walk is in.
    cur: u32,
    /// The segment being followed.
    index: usize,
}

impl Walker<'_> {
    /// The edge through which the plane (`side`) leaves triangle `cur` farthest along `d`, not
    /// `entry`: (progress along `d`, edge, where on it). A point on an edge leaves through that
    /// edge, at no progress.
    fn exit(
        &self,
        cur: u32,
        entry: Option<(u32, u32)>,
        side: &dyn Fn(u32) -> Real,
        pa: Vec3,
        d: Vec3,
    ) -> Option<(Real, (u32, u32), Real)> {
        let t = self.tris[cur as usize];
        let mut next: Option<(Real, (u32, u32), Real)> = None;
        for e in 0..3 {
            let (u, v) = (t[e].min(t[(e + 1) % 3]), t[e].max(t[(e + 1) % 3]));
            if entry == Some((u, v)) {
                continue;
            }
            let (su, sv) = (side(u), side(v));
            if (su >= 0.0) == (sv >= 0.0) {
                continue;
            }
            let s = su / (su - sv);
            let q = self.x[u as usize] + (self.x[v as usize] - self.x[u as usize]) * s;
            let progress = (q - pa).dot(&d);
            if next.is_none_or(|(p, _, _)| progress > p) {
                next = Some((progress, (u, v), s));
            }
        }
        next
    }

    /// Whether `p` lies on triangle `t` (within rounding).
    fn touches(&self, t: u32, p: Vec3) -> bool {
        let [a, b, c] = self.tris[t as usize].map(|v| self.x[v as usize]);
        let (q, _) = closest_point_on_triangle(&p, &a, &b, &c);
        (q - p).norm() <= 1e-9 * (1.0 + (b - a).norm())
    }

    /// The triangles sharing a corner with `t` that `p` lies on (within rounding).
    fn faces_at(&self, t: u32, p: Vec3) -> Vec<u32> {
        let mut out: Vec<u32> = self.tris[t as usize]
            .iter()
            .flat_map(|&v| self.around[v as usize].iter().copied())
            .filter(|&k| self.touches(k, p))
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    fn normal(&self, t: u32) -> Vec3 {
        let [a, b, c] = self.tris[t as usize].map(|v| self.x[v as usize]);
        (b - a)
            .cross(&(c - a))
            .try_normalize(1e-300)
            .unwrap_or_else(Vec3::zeros)
    }

    /// Follows the surface from `pa` (in or by the walk's triangle) to `pb` in triangle `tb`,
    /// recording the crossings.
    fn segment(&mut self, pa: Vec3, (tb, pb): (u32, Vec3)) -> Result<(), Stop> {
        let ta = self.cur;
        let d = pb - pa;
        let n = self.normal(ta) + self.normal(tb);
        let Some(m) = d.cross(&n).try_normalize(1e-12) else {
            return if ta == tb { Ok(()) } else { Err(Stop::Short) };
        };
        let side = |v: u32| m.dot(&(self.x[v as usize] - pa));
        let (mut cur, mut entry) = (ta, None::<(u32, u32)>);
        let before = self.crossings.len();
        for _ in 0..=self.tris.len() {
            // Arrived: in the end point's triangle, or one it lies on the edge or corner of.
            if cur == tb || self.touches(cur, pb) {
                break;
            }
            let mut next = self.exit(cur, entry, &side, pa, d);
            if entry.is_none() && next.is_none_or(|n| n.0 < -1e-9 * d.norm_squared()) {
                // A start on an edge or a vertex: leave from whichever face around it the plane
                // crosses farthest forward.
                for t in self.faces_at(cur, pa) {
                    let e = self.exit(t, None, &side, pa, d);
                    if let Some(e) = e
                        && next.is_none_or(|n| e.0 > n.0)
                    {
                        next = Some(e);
                        cur = t;
                    }
                }
                if !self.visited.contains(&cur) {
                    self.visited.push(cur);
                }
            }
            // No way on, or past the segment's end (its point lies by an edge of the plane's
            // path, not inside it): the segment ends here.
            let Some((_, edge, s)) = next.filter(|n| n.0 <= d.norm_squared() * 1.05) else {
                break;
            };
            let others = &self.across[&edge];
            let Some(&to) = others.iter().find(|&&o| o != cur) else {
                return Err(Stop::Edge);
            };
            if others.len() > 2 {
                return Err(Stop::Edge);
            }
            if self.visited.contains(&to) {
                return Err(Stop::Crossed);
            }
            self.crossings.push(Crossing {
                a: edge.0,
                b: edge.1,
                t: s.clamp(0.0, 1.0),
                segment: self.index,
            });
            self.visited.push(to);
            entry = Some(edge);
            cur = to;
        }
        self.cur = cur;
        if self.crossings.len() == before && ta != tb {
            return Err(Stop::Short);
        }
        Ok(())
    }
}
