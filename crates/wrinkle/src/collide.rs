//! Fine penetration removal (P1.4.2, hierarchical from the coarse contacts), blended normals
//! (P1.4.4, eqs. 13-14) and the length restoration error.

use crate::Detail;
use tryon_core::frames::{CoarseFrame, FineSurface, lattice_index, lattice_len};
use tryon_core::math::{Real, Vec3, unit, vertex_normals};
use tryon_core::stages::{Collider, LengthJudgement, RESTORED_WITHIN};

/// The distance bound of a vertex the collider knows nothing about (`Probe::FAR`): the
/// nearest-vertex tracker says so only beyond its cull margin (5 cm) of the body's box.
const UNKNOWN_FAR: Real = 0.05;

/// Least cosine between a poking body vertex's normal and the cloth's outward direction there for
/// the cloth to be lifted over it.
const FACING_OUT: Real = 0.5;

impl Detail {
    /// Probes the vertices in `self.which` and raises those within `skin` of the body. Each
    /// probed vertex's distance becomes its bound in `self.near` (0 once raised). Returns how many
    /// were raised.
    pub(crate) fn probe_and_raise(
        &mut self,
        fine: &mut FineSurface,
        collider: &mut dyn Collider,
    ) -> usize {
        let skin = self.params.skin;
        let margin = self.params.margin;
        let mut raised = 0;
        for pass in 0..2 {
            collider.probe_near(
                &fine.positions,
                &self.which,
                margin.max(skin),
                &mut self.probes,
            );
            let mut again = Vec::new();
            for (k, &v) in self.which.iter().enumerate() {
                let pr = self.probes[k];
                let v = v as usize;
                if pass == 0 {
                    self.near[v] = if pr.distance.is_finite() {
                        pr.distance
                    } else {
                        UNKNOWN_FAR
                    };
                }
                if !(pr.distance < skin)
                    || !pr.distance.is_finite()
                    || !tryon_core::math::is_finite(&pr.normal)
                {
                    continue;
                }
                self.near[v] = 0.0;
                let need = skin - pr.distance;
                let n = self.control[v];
                let along = n.dot(&pr.normal);
                if along > 0.25 {
                    let dh = need / along;
                    self.raise[v] += dh;
                    fine.positions[v] += n * dh;
                } else {
                    // The control direction runs along or into the body: leave along the body normal.
                    fine.positions[v] += pr.normal * need;
                }
                if pass == 0 {
                    raised += 1;
                    again.push(v as u32);
                }
            }
            if again.is_empty() {
                break;
            }
            self.which = again;
        }
        raised
    }

    /// P1.4.2: hierarchical fine penetration removal (see the crate docs). Level 0 probes every
    /// coarse vertex; each finer level's vertex is probed only when the body may be within
    /// `margin` of it: its distance is at least either parent's (the two vertices of the coarser
    /// level whose edge it halves) less its distance from that parent, and a contact's or raised
    /// vertex's bound is 0.
    pub fn fine_collision(
        &mut self,
        coarse: &CoarseFrame,
        fine: &mut FineSurface,
        collider: &mut dyn Collider,
    ) {
        if self.reference.len() != fine.positions.len() {
            self.take_reference(fine);
        }
        self.near.clear();
        self.near.resize(fine.positions.len(), UNKNOWN_FAR);
        self.which.clear();
        self.which.extend(0..self.coarse_vertices as u32);
        let mut probed = self.which.len();
        let mut raised = self.probe_and_raise(fine, collider);
        for c in &coarse.contacts {
            if (c.point as usize) < self.coarse_vertices {
                self.near[c.point as usize] = 0.0;
            }
        }
        let n = self.n;
        let mut visited = vec![false; fine.positions.len()];
        for l in 1..=n.trailing_zeros() {
            self.select_level(n >> l, &fine.positions, &mut visited);
            probed += self.which.len();
            raised += self.probe_and_raise(fine, collider);
        }
        self.stats.probed = probed;
        self.stats.raised = raised;
        self.stats.lifted = if self.params.pokes {
            self.lift_over_pokes(fine, collider)
        } else {
            0
        };
    }

    /// Lifts the fine surface over the body vertices under its triangles that are less than
    /// `skin` below it or poke through it (up to `margin`): features narrower than the fine
    /// triangles (a nipple, a shoulder's tip) that no test of the fine vertices sees. Only
    /// triangles whose corners the body may be within `margin` of are asked. Each corner moves
    /// along the body vertex's normal by its share of the lift (the smallest move that puts the
    /// point over the vertex `skin` out); a vertex under several pokes takes the largest move.
    /// Returns how many fine vertices moved.
    fn lift_over_pokes(&mut self, fine: &mut FineSurface, collider: &mut dyn Collider) -> usize {
        let (skin, margin) = (self.params.skin, self.params.margin);
        let near = &self.near;
        let tris: Vec<u32> = (0..fine.triangles.len() as u32)
            .filter(|&t| {
                let c = fine.triangles[t as usize];
                c.iter()
                    .all(|&v| near.get(v as usize).is_some_and(|&d| d < margin))
            })
            .collect();
        if tris.is_empty() {
            return 0;
        }
        let mut pokes = Vec::new();
        collider.pokes(
            &fine.positions,
            &fine.triangles,
            &tris,
            (skin, margin),
            &mut pokes,
        );
        let mut moves: Vec<(u32, Vec3)> = Vec::new();
        for pk in &pokes {
            let Some(&c) = fine.triangles.get(pk.triangle as usize) else {
                continue;
            };
            // Only a vertex whose outside is the cloth's outside: not the underside of an arm
            // over cloth on the torso, which would push the cloth into the torso.
            let out: Vec3 = (0..3)
                .map(|k| self.control[c[k] as usize] * pk.bary[k])
                .sum();
            if !(pk.normal.dot(&out) > FACING_OUT * out.norm()) {
                continue;
            }
            let q: Vec3 = (0..3)
                .map(|k| fine.positions[c[k] as usize] * pk.bary[k])
                .sum();
            let need = skin - pk.normal.dot(&(q - pk.point));
            let w2: Real = pk.bary.iter().map(|w| w * w).sum();
            if !(need > 0.0 && w2 > 0.0) {
                continue;
            }
            for k in 0..3 {
                moves.push((c[k], pk.normal * (pk.bary[k] * need / w2)));
            }
        }
        // The largest move per vertex, in a fixed order.
        moves.sort_by(|a, b| {
            a.0.cmp(&b.0)
                .then(b.1.norm_squared().total_cmp(&a.1.norm_squared()))
        });
        moves.dedup_by_key(|m| m.0);
        moves.retain(|(_, d)| d.norm_squared() > 0.0 && tryon_core::math::is_finite(d));
        for &(v, d) in &moves {
            fine.positions[v as usize] += d;
        }
        // A lift that put a vertex inside another part of the body is taken back.
        let moved: Vec<u32> = moves.iter().map(|m| m.0).collect();
        collider.probe(&fine.positions, &moved, &mut self.probes);
        let mut lifted = 0;
        for (k, &(v, d)) in moves.iter().enumerate() {
            let v = v as usize;
            if self.probes.get(k).is_some_and(|p| p.distance < 0.0) {
                fine.positions[v] -= d;
            } else {
                self.raise[v] += d.norm();
                lifted += 1;
            }
        }
        lifted
    }

    /// The vertices of the level whose lattice step is `s` that the body may be within `margin`
    /// of, into `self.which`; the others get their bound from their parents.
    fn select_level(&mut self, s: u32, x: &[Vec3], visited: &mut [bool]) {
        let (n, margin) = (self.n, self.params.margin);
        let per = lattice_len(n);
        self.which.clear();
        for f in 0..self.coarse_tris.len() {
            let lat = &self.lattice[f * per..(f + 1) * per];
            let at = |i: u32, j: u32| lat[lattice_index(n, i, j)] as usize;
            let mut j = 0;
            while j <= n {
                let mut i = 0;
                while i + j <= n {
                    let (oi, oj) = ((i / s) % 2 == 1, (j / s) % 2 == 1);
                    let v = at(i, j);
                    if (oi || oj) && !visited[v] {
                        visited[v] = true;
                        let (a, b) = match (oi, oj) {
                            (true, false) => (at(i - s, j), at(i + s, j)),
                            (false, true) => (at(i, j - s), at(i, j + s)),
                            _ => (at(i + s, j - s), at(i - s, j + s)),
                        };
                        let bound = (self.near[a] - (x[v] - x[a]).norm())
                            .max(self.near[b] - (x[v] - x[b]).norm());
                        if bound < margin {
                            self.which.push(v as u32);
                        } else {
                            self.near[v] = bound;
                        }
                    }
                    i += s;
                }
                j += s;
            }
        }
    }

    /// P1.4.4: blends the deformed surface's normals with the PN normals by height (eqs. 13-14).
    ///
    /// Where the height is zero the PN normal is kept as it is, so the deformed surface's normal
    /// (area-weighted over the vertex's triangles) is computed only where a vertex is raised.
    pub fn blend_normals(&mut self, fine: &mut FineSurface) {
        let gather = self.tri_count == fine.triangles.len()
            && self.vertex_tris.offsets.len() == fine.positions.len() + 1;
        if !gather {
            vertex_normals(&fine.positions, &fine.triangles, &mut self.deformed_normals);
        }
        let h = self.params.h_normal;
        let x = &fine.positions;
        // With many vertices to blend, each fine triangle's normal once (rather than once per
        // corner): a vertex's deformed normal is the sum over its row either way.
        let active = (0..x.len())
            .filter(|&i| self.height[i] + self.raise[i] > 0.0)
            .count();
        let faces = gather && 3 * active > fine.triangles.len();
        if faces {
            self.face_cross.clear();
            self.face_cross.extend(fine.triangles.iter().map(|t| {
                let [a, b, c] = t.map(|v| v as usize);
                (x[b] - x[a]).cross(&(x[c] - x[a]))
            }));
        }
        for i in 0..x.len() {
            let dh = self.height[i] + self.raise[i];
            let alpha = (dh / h).clamp(0.0, 1.0);
            let pn = self.control.get(i).copied().unwrap_or(fine.normals[i]);
            if !(alpha > 0.0) {
                fine.normals[i] = pn;
                continue;
            }
            let mut nd = if faces {
                let row = self.vertex_tris.row(i);
                let sum: Vec3 = row.iter().map(|&t| self.face_cross[t as usize]).sum();
                unit(&sum, 1e-30).unwrap_or(Vec3::y())
            } else if gather {
                let mut sum = Vec3::zeros();
                for &t in self.vertex_tris.row(i) {
                    let [a, b, c] = fine.triangles[t as usize];
                    let (a, b, c) = (a as usize, b as usize, c as usize);
                    sum += (x[b] - x[a]).cross(&(x[c] - x[a]));
                }
                unit(&sum, 1e-30).unwrap_or(Vec3::y())
            } else {
                self.deformed_normals[i]
            };
            // The deformed surface is built from the same triangles, so its normal faces the
            // PN normal's side; flip one that does not (a fold turned over).
            if nd.dot(&pn) < 0.0 {
                nd = -nd;
            }
            fine.normals[i] = unit(&(nd * alpha + pn * (1.0 - alpha)), 1e-30).unwrap_or(pn);
        }
    }

    /// Length restoration over the coarse edges that are compressed on the reference surface:
    /// mean of `|fine path length - rest| / rest` (with the path through `positions`), and how many
    /// edges counted.
    pub fn length_error(&self, positions: &[Vec3]) -> (Real, usize) {
        let j = self.length_judgement(positions);
        (j.error, j.edges)
    }

    /// [`Self::length_error`] through `positions` and through the reference surface, with the
    /// share of those edges back within [`RESTORED_WITHIN`] of rest through each.
    pub fn length_judgement(&self, positions: &[Vec3]) -> LengthJudgement {
        let mut j = LengthJudgement::default();
        for e in 0..self.edges.len() {
            let row = self.edge_fine.row(e);
            let path = |x: &[Vec3]| -> Real {
                row.windows(2)
                    .map(|w| (x[w[1] as usize] - x[w[0] as usize]).norm())
                    .sum()
            };
            let rest = self.edge_rest[e];
            if self.reference.len() != positions.len() || !(rest > 0.0) {
                continue;
            }
            let reference = (path(&self.reference) - rest) / rest;
            if reference < 0.0 {
                let output = (path(positions) - rest).abs() / rest;
                j.edges += 1;
                j.error += output;
                j.reference_error += -reference;
                j.restored += Real::from(output <= RESTORED_WITHIN);
                j.reference_restored += Real::from(-reference <= RESTORED_WITHIN);
            }
        }
        if j.edges > 0 {
            let n = j.edges as Real;
            (j.error, j.reference_error) = (j.error / n, j.reference_error / n);
            (j.restored, j.reference_restored) = (j.restored / n, j.reference_restored / n);
        }
        j
    }
}
