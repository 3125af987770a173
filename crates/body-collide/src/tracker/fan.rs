//! P1's inside test at a vertex's fan of faces, and the crease test for concave fans: the
//! geometric half of the nearest-vertex collider.

use super::{CREASE_REACH, Crease, FLAT, FanTest, Highest, Hit, NearestVertexCollider};
use tryon_core::math::{Real, Vec3, closest_point_on_triangle};
use tryon_core::stages::Probe;

impl NearestVertexCollider {
    /// P1's inside test at vertex `v` (offset by the thickness): inside when behind every face of
    /// the fan (with the face whose plane the point is nearest behind and its height over it),
    /// outside for sure when in front of every face, and undecided when behind some and in front
    /// of others (a convex fan says outside then; a concave one needs the crease test).
    #[inline]
    pub(super) fn fan_test(&self, p: &Vec3, v: u32) -> FanTest {
        let rel = p - self.body.positions[v as usize];
        let mut best = (u32::MAX, Real::NEG_INFINITY);
        let mut top = Highest(u32::MAX, Real::NEG_INFINITY);
        let mut front = 0usize;
        let mut lowest = Real::INFINITY;
        let faces = self.body.vertex_faces.row(v as usize);
        for &f in faces {
            let h = rel.dot(&self.body.face_normals[f as usize]);
            if h > top.1 {
                top = Highest(f, h);
            }
            lowest = lowest.min(h);
            if h >= self.thickness {
                front += 1;
            } else if h > best.1 {
                best = (f, h);
            }
        }
        if front == 0 && best.0 != u32::MAX {
            FanTest::Inside(best.0, best.1)
        } else if front == faces.len() {
            FanTest::Front(top, lowest)
        } else {
            FanTest::Mixed(top)
        }
    }

    /// Whether the fan of faces around `v` bounds a convex cone (every neighbour on or behind
    /// every face's plane), cached until the body moves. Behind part of a convex fan is outside.
    pub(super) fn fan_is_convex(&self, v: u32) -> bool {
        match self.fan_convex.get(v) {
            1 => return true,
            2 => return false,
            _ => {}
        }
        let x = self.body.positions[v as usize];
        let convex = self.body.vertex_faces.row(v as usize).iter().all(|&f| {
            let n = self.body.face_normals[f as usize];
            self.body.ring.row(v as usize).iter().all(|&w| {
                let r = self.body.positions[w as usize] - x;
                r.dot(&n) <= FLAT * r.norm()
            })
        });
        self.fan_convex.set(v, if convex { 1 } else { 2 });
        convex
    }

    /// P1's test, with the crease test where the fan is not convex: whether `p` is inside near
    /// vertex `v`, and where to move it. Over a convex fan P1's push along the nearest plane's
    /// normal is exact; in a fold it can land the point behind the fold's other side, so there the
    /// point goes to the closest point of the fan, `skin` out along the pseudo-normal.
    ///
    /// A point found outside gets `Err(clearance)`: a lower bound of its distance to the fan less
    /// `skin` (0 when unknown).
    #[inline]
    pub(super) fn inside_any(&self, p: &Vec3, v: u32, skin: Real) -> Result<Hit, Real> {
        match self.fan_test(p, v) {
            FanTest::Inside(f, h) => {
                let n = self.body.face_normals[f as usize];
                let convex = self.fan_is_convex(v);
                let p1 = Hit {
                    face: f,
                    height: h,
                    normal: n,
                    target: p + n * (skin - h),
                    settled: convex,
                };
                if convex {
                    Ok(p1)
                } else {
                    Ok(self.inside_crease(p, v, skin).ok().unwrap_or(p1))
                }
            }
            // Over a convex fan the height over the highest plane bounds the distance from below;
            // over any fan, the height over the lowest (the point is in front of every face).
            FanTest::Front(top, lowest) => Err(if self.fan_is_convex(v) {
                top.1 - skin
            } else {
                lowest - skin
            }),
            FanTest::Mixed(top) if self.fan_is_convex(v) => Err(top.1 - skin),
            // Moved less than `top.1 - skin`, the point stays in front of that plane (so never
            // behind every face), and less than its distance to the fan less `skin`, it keeps
            // clear of the fan.
            FanTest::Mixed(top) => self
                .inside_crease(p, v, skin)
                .map_err(|c| c.min(top.1 - skin)),
        }
    }

    /// The crease test: P1's test misses points inside a concave crease (shoulder against neck,
    /// arm against torso), where a point can be behind some faces of the fan and in front of
    /// others. Such a point is inside when it is behind the closest point of the fan, judged by the
    /// pseudo-normal there (the face normal, or the mean of the faces sharing the closest edge or
    /// vertex). Returns the face and the point's height over the closest point along that normal.
    ///
    /// Outside, `Err` holds the point's distance to the fan less `skin` (0 when not known).
    pub(super) fn inside_crease(&self, p: &Vec3, v: u32, skin: Real) -> Result<Hit, Real> {
        match self.crease(p, v, skin) {
            Crease::Inside(h) => Ok(h),
            Crease::Outside { clear, .. } => Err(clear),
            Crease::Unknown => Err(0.0),
        }
    }

    /// [`Self::inside_crease`], keeping the closest point of the fan when it was found.
    pub(super) fn crease(&self, p: &Vec3, v: u32, skin: Real) -> Crease {
        if (p - self.body.positions[v as usize]).norm_squared() > CREASE_REACH * CREASE_REACH {
            return Crease::Unknown;
        }
        let (f, q, bary) = self.body.closest_on_fan(p, v);
        if f == u32::MAX {
            return Crease::Unknown;
        }
        let outside = |clear| Crease::Outside {
            face: f,
            closest: q,
            clear,
        };
        let d2 = (p - q).norm_squared();
        let mut n = self.body.face_normals[f as usize];
        if bary.iter().any(|&b| b < 1e-9) {
            n = Vec3::zeros();
            for &g in self.body.vertex_faces.row(v as usize) {
                let [a, b, c] = self.body.corners(g as usize);
                let (qg, _) = closest_point_on_triangle(p, &a, &b, &c);
                if (p - qg).norm_squared() <= d2 * (1.0 + 1e-9) + 1e-24 {
                    n += self.body.face_normals[g as usize];
                }
            }
            n = match n.try_normalize(1e-12) {
                Some(n) => n,
                None => return outside(0.0),
            };
        }
        let h = (p - q).dot(&n);
        if h < skin {
            Crease::Inside(Hit {
                face: f,
                height: h,
                normal: n,
                target: q + n * skin,
                settled: false,
            })
        } else {
            outside(d2.sqrt() - skin)
        }
    }

    /// Whether `p` projects along face `f`'s normal into the face (its edges included).
    pub(super) fn projects_into(&self, f: u32, p: &Vec3) -> bool {
        let [a, b, c] = self.body.corners(f as usize);
        let n = self.body.face_normals[f as usize];
        let inside_edge = |u: &Vec3, w: &Vec3| (w - u).cross(&(p - u)).dot(&n) >= 0.0;
        inside_edge(&a, &b) && inside_edge(&b, &c) && inside_edge(&c, &a)
    }

    /// Barycentric coordinates of `q` (on or near the plane of triangle `f`), clamped into the triangle.
    pub(super) fn bary(&self, f: u32, q: &Vec3) -> [Real; 3] {
        let [a, b, c] = self.body.corners(f as usize);
        let (e1, e2, r) = (b - a, c - a, q - a);
        let (d11, d12, d22, r1, r2) = (
            e1.dot(&e1),
            e1.dot(&e2),
            e2.dot(&e2),
            r.dot(&e1),
            r.dot(&e2),
        );
        let det = d11 * d22 - d12 * d12;
        if !(det > 0.0) {
            return [1.0 / 3.0; 3];
        }
        let v = ((d22 * r1 - d12 * r2) / det).clamp(0.0, 1.0);
        let w = ((d11 * r2 - d12 * r1) / det).clamp(0.0, 1.0 - v);
        [1.0 - v - w, v, w]
    }

    /// The probe of point `p` at its nearest vertex `v`: P1's inside test there (and the crease
    /// test); outside, its distance to the vertex's fan, or over a convex fan, when already the
    /// height over one of its planes is `reach` or more, that height (no point of the fan is
    /// nearer).
    pub(super) fn probe_at(&self, p: &Vec3, v: u32, reach: Real) -> Probe {
        let mut closest_found: Option<(u32, Vec3)> = None;
        let top = match self.fan_test(p, v) {
            FanTest::Inside(f, h) => {
                return Probe {
                    distance: h,
                    normal: self.body.face_normals[f as usize],
                };
            }
            FanTest::Front(top, _) => top,
            FanTest::Mixed(top) => {
                if !self.fan_is_convex(v) {
                    match self.crease(p, v, 0.0) {
                        Crease::Inside(h) => {
                            return Probe {
                                distance: h.height,
                                normal: h.normal,
                            };
                        }
                        // Outside: the crease test found the fan's closest point already.
                        Crease::Outside { face, closest, .. } => {
                            closest_found = Some((face, closest));
                        }
                        Crease::Unknown => {}
                    }
                }
                top
            }
        };
        // Over a convex fan the height over the highest plane bounds the distance from below,
        // and is the distance when the point projects into that face.
        if top.0 != u32::MAX
            && self.fan_is_convex(v)
            && (top.1 >= reach || self.projects_into(top.0, p))
        {
            return Probe {
                distance: top.1,
                normal: self.body.face_normals[top.0 as usize],
            };
        }
        let (f, q) = closest_found.unwrap_or_else(|| {
            let (f, q, _) = self.body.closest_on_fan(p, v);
            (f, q)
        });
        let d = p - q;
        let n = d.norm();
        Probe {
            distance: n,
            normal: if n > 1e-12 {
                d / n
            } else {
                self.body.face_normals[f as usize]
            },
        }
    }
}
