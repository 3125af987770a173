//! One side of the kimono: the back and front halves of its body panel, its okumi and its sleeve,
//! sewn where a kimono is sewn, with the dimension sets that lie on them. The back centre is
//! shared by both sides and made first.

use crate::builder::{Builder, lerp};
use crate::dims::{BOLT_WIDTH, Dimensions};
use crate::levels::{Layout, Levels, row_heights};
use crate::mesh::{GAP, LAYER, Part, bolt_starts, sub};
use tryon_core::math::Real;

/// The edge the collar is sewn along on one side, from the collar's end up the okumi's front edge
/// and the panel's neck diagonal to the shoulder fold, then along the back neck to the back centre
/// (the last vertex). `back_from` is where the back neck starts.
#[derive(Clone, Debug)]
pub(crate) struct CollarEdge {
    pub ids: Vec<u32>,
    pub back_from: usize,
}

/// The back centre's vertices, hem to shoulder fold.
pub(crate) fn back_centre(b: &mut Builder, lv: &Levels, layout: &Layout) -> Vec<u32> {
    let y = row_heights(&lv.outer, &layout.rows);
    let top = y.len() - 1;
    (0..=top)
        .map(|r| b.vert(0.0, y[r], if r == top { 0.0 } else { -GAP }))
        .collect()
}

/// The panel's outline at height `y` of the flat kimono (one side, x ≥ 0).
struct Outline {
    shoulder: Real,
    back: Real,
    front: Real,
    holding: Real,
    neck: Real,
    opening_foot: Real,
    tip: Real,
    length: Real,
}

impl Outline {
    /// The side seam (and the back's outer edge).
    fn side(&self, y: Real) -> Real {
        if y <= self.opening_foot {
            lerp(self.back, self.shoulder, y / self.opening_foot)
        } else {
            self.shoulder
        }
    }

    /// The front's inner edge: the okumi seam, then the diagonal up to the neck point.
    fn front_inner(&self, y: Real) -> Real {
        if y <= self.opening_foot {
            let t = y / self.opening_foot;
            self.side(y) - lerp(self.front, self.holding, t)
        } else if y <= self.tip {
            self.shoulder - self.holding
        } else {
            let t = (y - self.tip) / (self.length - self.tip);
            lerp(self.shoulder - self.holding, self.neck, t)
        }
    }
}

/// One side (`left`: the wearer's left, +x, the upper front) and its dimension sets; returns the
/// edge its collar is sewn along.
pub(crate) fn side(
    b: &mut Builder,
    d: &Dimensions,
    lv: &Levels,
    layout: &Layout,
    left: bool,
    centre: &[u32],
) -> CollarEdge {
    let s: Real = if left { 1.0 } else { -1.0 };
    let at = layout.level_rows();
    let top = at[6];
    let (yo, yi) = (
        row_heights(&lv.outer, &layout.rows),
        row_heights(&lv.inner, &layout.rows),
    );
    let o = Outline {
        shoulder: d.shoulder_width,
        back: d.back_width,
        front: d.front_width,
        holding: d.holding_width,
        neck: d.neck_half,
        opening_foot: lv.outer[4],
        tip: lv.inner[5],
        length: d.body_length,
    };
    let starts = bolt_starts(d);
    let v_body = starts[if left { 3 } else { 2 }];
    let (nb, nf) = (layout.back_neck, layout.panel);
    let front_sub = if left {
        sub::LEFT_FRONT
    } else {
        sub::RIGHT_FRONT
    };
    let body = if left {
        Part::LeftBody
    } else {
        Part::RightBody
    };

    // The back half: the back centre, out to the side seam; across the shoulder fold, the neck's
    // columns then the panel's.
    let frac = |j: usize| {
        if j <= nb {
            d.neck_half * j as Real / nb as Real / d.shoulder_width
        } else {
            (d.neck_half + (d.shoulder_width - d.neck_half) * (j - nb) as Real / nf as Real)
                / d.shoulder_width
        }
    };
    let mut back = vec![vec![0u32; nb + nf + 1]; top + 1];
    let mut back_uv = vec![vec![[0.0; 2]; nb + nf + 1]; top + 1];
    for r in 0..=top {
        for j in 0..=nb + nf {
            let x = frac(j) * o.side(yo[r]);
            back_uv[r][j] = [x, v_body + yo[r]];
            back[r][j] = if j == 0 {
                centre[r]
            } else {
                let seam = r == top || (j == nb + nf && r <= at[4]);
                b.vert(s * x, yo[r], if seam { 0.0 } else { -GAP })
            };
        }
    }
    b.grid(&back, &back_uv, body, sub::BACK);

    // The front half: from the okumi seam (then the neck diagonal) out to the side seam; its top
    // row is the back's across the fold, its side seam the back's below the underarm opening.
    let mut front = vec![vec![0u32; nf + 1]; top + 1];
    let mut front_uv = vec![vec![[0.0; 2]; nf + 1]; top + 1];
    for r in 0..=top {
        for j in 0..=nf {
            let t = j as Real / nf as Real;
            let (x, y) = (
                lerp(o.front_inner(yi[r]), o.side(yo[r]), t),
                lerp(yi[r], yo[r], t),
            );
            front_uv[r][j] = [x, v_body + 2.0 * d.body_length - y];
            front[r][j] = if r == top {
                back[top][nb + j]
            } else if j == nf && r <= at[4] {
                back[r][nb + nf]
            } else {
                b.vert(s * x, y, GAP)
            };
        }
    }
    b.grid(&front, &front_uv, body, front_sub);

    let okumi_edge = okumi(b, d, layout, left, &front, &yi, &o);
    sleeve(b, d, lv, layout, left, &front, &back);

    // Dimension sets on the body (Table 1's on the left; the right's mirror them).
    let col = |g: &[Vec<u32>], j: usize, rows: std::ops::RangeInclusive<usize>| -> Vec<u32> {
        rows.map(|r| g[r][j]).collect()
    };
    if left {
        let band = at[2]..at[3];
        b.dimension(8, true, sub::BACK, centre, &|i| band.contains(&i));
    }
    let none = |_: usize| false;
    b.dimension(9, left, sub::BACK, &back[top], &none);
    b.dimension(10, left, front_sub, &front[0], &none);
    b.dimension(11, left, sub::BACK, &back[0], &none);
    b.dimension(12, left, front_sub, &front[at[4]], &none);
    let no = layout.okumi;
    b.dimension(13, left, front_sub, &col(&okumi_edge, no, 0..=at[1]), &none);
    b.dimension(16, left, front_sub, &okumi_edge[at[1]], &none);

    let mut ids = col(&okumi_edge, no, at[1]..=at[5]);
    ids.extend(col(&front, 0, at[5] + 1..=top));
    let back_from = ids.len();
    ids.extend((0..nb).rev().map(|j| back[top][j]));
    CollarEdge { ids, back_from }
}

/// The okumi: sewn to the front's inner edge from the hem to its tip (剣先), `okumi_width` wide at
/// the hem, the overlap width at the collar's end, nothing at the tip. Returns its grid.
fn okumi(
    b: &mut Builder,
    d: &Dimensions,
    layout: &Layout,
    left: bool,
    front: &[Vec<u32>],
    yi: &[Real],
    o: &Outline,
) -> Vec<Vec<u32>> {
    let s: Real = if left { 1.0 } else { -1.0 };
    let at = layout.level_rows();
    let no = layout.okumi;
    let v_ok = bolt_starts(d)[4];
    let tip = d.below_collar;
    let width = |y: Real| {
        if y <= tip {
            lerp(d.okumi_width, d.overlap_width, y / tip)
        } else {
            d.overlap_width * (o.tip - y) / (o.tip - tip)
        }
    };
    let mut ids = vec![vec![0u32; no + 1]; at[5] + 1];
    let mut uv = vec![vec![[0.0; 2]; no + 1]; at[5] + 1];
    for r in 0..=at[5] {
        // Above the collar's end the okumi narrows to its tip: a row keeps about as many columns
        // as its share of the rows left to the tip (the layout's, so every size has the same
        // topology), the rest fold onto its last (no slivers).
        let w = width(yi[r]);
        let live = if r <= at[1] {
            no
        } else {
            let left = (at[5] - r) as Real / (at[5] - at[1]) as Real;
            ((left * no as Real).round() as usize).clamp(1, no)
        };
        for j in 0..=no {
            let dist = w * j.min(live) as Real / live as Real;
            uv[r][j] = [if left { BOLT_WIDTH - dist } else { dist }, v_ok + yi[r]];
            ids[r][j] = if j == 0 || r == at[5] {
                front[r][0]
            } else if j > live {
                ids[r][live]
            } else {
                let x = o.front_inner(yi[r]) - dist;
                b.vert(s * x, yi[r], GAP + s * LAYER)
            };
        }
    }
    let part = if left {
        Part::LeftOkumi
    } else {
        Part::RightOkumi
    };
    let sub = if left {
        sub::LEFT_FRONT
    } else {
        sub::RIGHT_FRONT
    };
    b.grid(&ids, &uv, part, sub);
    ids
}

/// The sleeve: one piece folded over the shoulder line, front and back layers sewn along the
/// bottom and up the cuff edge to the opening, sewn to the panels along the attachment; the rest
/// of its seam edge (振り) is open. Adds its four dimension sets.
fn sleeve(
    b: &mut Builder,
    d: &Dimensions,
    lv: &Levels,
    layout: &Layout,
    left: bool,
    front: &[Vec<u32>],
    back: &[Vec<u32>],
) {
    let s: Real = if left { 1.0 } else { -1.0 };
    let (na, nw) = (layout.rows[5], layout.sleeve);
    let counts = [na, layout.sleeve_below];
    let (yin, yout) = (
        row_heights(&lv.sleeve_inner, &counts),
        row_heights(&lv.sleeve_outer, &counts),
    );
    let last = na + layout.sleeve_below;
    let top = front.len() - 1;
    let (l, sl) = (d.body_length, d.sleeve_length);
    let v0 = bolt_starts(d)[if left { 1 } else { 0 }];
    let mut layers: Vec<Vec<Vec<u32>>> = Vec::new();
    for (k, panel) in [front, back].into_iter().enumerate() {
        let outer = panel[0].len() - 1;
        let z = if k == 0 { GAP } else { -GAP };
        let mut ids = vec![vec![0u32; nw + 1]; last + 1];
        let mut uv = vec![vec![[0.0; 2]; nw + 1]; last + 1];
        for r in 0..=last {
            for j in 0..=nw {
                let t = j as Real / nw as Real;
                let (x, y) = (
                    d.shoulder_width + d.sleeve_width * t,
                    lerp(yin[r], yout[r], t),
                );
                uv[r][j] = [
                    d.sleeve_width * t,
                    v0 + if k == 0 { y - (l - sl) } else { sl + l - y },
                ];
                let shared = r == 0 || r == last || (j == nw && r >= na);
                ids[r][j] = if j == 0 && r <= na {
                    panel[top - r][outer]
                } else if k == 1 && shared {
                    layers[0][r][j]
                } else {
                    b.vert(s * x, y, if shared { 0.0 } else { z })
                };
            }
        }
        let part = if left {
            Part::LeftSleeve
        } else {
            Part::RightSleeve
        };
        let sub = if left {
            sub::LEFT_SLEEVE
        } else {
            sub::RIGHT_SLEEVE
        };
        b.grid(&ids, &uv, part, sub);
        layers.push(ids);
    }
    let f = &layers[0];
    let base = if left { 4 } else { 0 };
    let sub = if left {
        sub::LEFT_SLEEVE
    } else {
        sub::RIGHT_SLEEVE
    };
    let none = |_: usize| false;
    let column = |j: usize, n: usize| (0..=n).map(|r| f[r][j]).collect::<Vec<_>>();
    b.dimension(base, true, sub, &column(nw, last), &none);
    b.dimension(base + 1, true, sub, &f[0], &none);
    b.dimension(base + 2, true, sub, &column(0, na), &none);
    b.dimension(base + 3, true, sub, &column(nw, na), &none);
}
