//! Where the kimono's pattern rows fall: the heights (above the hem, along the cut) that every
//! garment of the family puts a row of vertices at, and how many rows lie between them. The counts
//! are fixed once for a family ([`Layout`]), so kimonos tailored for any body share one topology:
//! that is what lets P2 blend them.

use crate::dims::{BU, Dimensions};
use thiserror::Error;
use tryon_core::math::Real;

/// How far above the collar's end the waist cord (腰紐) is tied, m: the cord sits 3–4 cm above it
/// ([M] in `dims`).
pub const CORD_ABOVE_TIP: Real = 0.035;

/// The okumi's tip (剣先) stays at least this far below the sleeve's attachment end, m.
const TIP_BELOW_ATTACH: Real = 5.0 * BU;

/// The heights of a kimono's pattern levels, m above the hem along the cut (the flat garment).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Levels {
    /// At the panels' outer edges (side seam, underarm opening, sleeve seam): hem, collar tip, the
    /// ohashori band's foot and head, the underarm opening's foot, the sleeve attachment's foot,
    /// the shoulder fold.
    pub outer: [Real; 7],
    /// At the panels' inner edges (back centre; the okumi seam, then the collar's diagonal): the
    /// same, but the okumi's tip in place of the sleeve attachment's foot.
    pub inner: [Real; 7],
    /// On the sleeve's seam edge: the shoulder fold, the attachment's foot, the sleeve's bottom.
    pub sleeve_inner: [Real; 3],
    /// On the sleeve's cuff edge: the shoulder fold, the opening's foot, the sleeve's bottom.
    pub sleeve_outer: [Real; 3],
}

/// Why a kimono's levels cannot be laid out.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum LevelError {
    #[error("the kimono's {what} ({value:.4} m) must be above its {below} ({limit:.4} m)")]
    Crossed {
        what: &'static str,
        value: Real,
        below: &'static str,
        limit: Real,
    },
}

/// The ohashori fold's depth: half the cut length the worn length does not use, m.
pub fn ohashori_depth(d: &Dimensions) -> Real {
    0.5 * (d.body_length - d.garment_length)
}

/// The okumi's tip below the shoulder fold, m.
pub fn okumi_drop(d: &Dimensions) -> Real {
    d.okumi_drop.max(d.sleeve_attach + TIP_BELOW_ATTACH)
}

impl Levels {
    /// The levels of a kimono tailored to `d`.
    pub fn new(d: &Dimensions) -> Result<Levels, LevelError> {
        let l = d.body_length;
        let tip = d.below_collar;
        let cord = tip + CORD_ABOVE_TIP;
        let band_top = cord + 2.0 * ohashori_depth(d);
        let opening_foot = l - d.sleeve_attach - d.underarm_opening;
        let names = [
            "hem",
            "collar's end",
            "waist cord",
            "ohashori band's head",
            "underarm opening's foot",
            "sleeve attachment's foot",
            "shoulder fold",
        ];
        let outer = [
            0.0,
            tip,
            cord,
            band_top,
            opening_foot,
            l - d.sleeve_attach,
            l,
        ];
        let inner = [0.0, tip, cord, band_top, opening_foot, l - okumi_drop(d), l];
        for (lv, names) in [
            (&outer, names),
            (&inner, {
                let mut n = names;
                n[5] = "okumi's tip";
                n
            }),
        ] {
            for k in 1..7 {
                if !(lv[k] > lv[k - 1]) {
                    return Err(LevelError::Crossed {
                        what: names[k],
                        value: lv[k],
                        below: names[k - 1],
                        limit: lv[k - 1],
                    });
                }
            }
        }
        let s = d.sleeve_length;
        for (what, v) in [
            ("sleeve's attachment", d.sleeve_attach),
            ("sleeve's opening", d.sleeve_opening),
        ] {
            if !(v < s) {
                return Err(LevelError::Crossed {
                    what: "sleeve's bottom",
                    value: l - s,
                    below: what,
                    limit: l - v,
                });
            }
        }
        Ok(Levels {
            outer,
            inner,
            sleeve_inner: [l, l - d.sleeve_attach, l - s],
            sleeve_outer: [l, l - d.sleeve_opening, l - s],
        })
    }
}

/// The rows and columns of a kimono family, fixed once: every kimono built with one layout has the
/// same vertices, faces and dimension edge sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Layout {
    /// Rows of the panels between consecutive levels.
    pub rows: [usize; 6],
    /// Columns of the back between the back centre and the neck point.
    pub back_neck: usize,
    /// Columns of the front panel (and of the back beyond the neck point).
    pub panel: usize,
    /// Columns of the okumi.
    pub okumi: usize,
    /// Columns of the sleeve across its width.
    pub sleeve: usize,
    /// Rows of the sleeve below its attachment.
    pub sleeve_below: usize,
    /// Columns of the collar across its width.
    pub collar: usize,
}

impl Layout {
    /// A layout whose edges are about `edge` long on a kimono tailored to `d`.
    pub fn for_dims(d: &Dimensions, edge: Real) -> Result<Layout, LevelError> {
        let lv = Levels::new(d)?;
        let n = |len: Real| ((len / edge).round() as usize).max(1);
        let rows = std::array::from_fn(|k| {
            n((lv.outer[k + 1] - lv.outer[k]).max(lv.inner[k + 1] - lv.inner[k]))
        });
        Ok(Layout {
            rows,
            back_neck: n(d.neck_half),
            panel: n(d.shoulder_width - d.neck_half).max(2),
            okumi: n(d.okumi_width).max(2),
            sleeve: n(d.sleeve_width).max(2),
            sleeve_below: n(d.sleeve_length - d.sleeve_attach.max(d.sleeve_opening)),
            collar: 2,
        })
    }

    /// Index of the first row of each level (the last entry is the top row).
    pub fn level_rows(&self) -> [usize; 7] {
        let mut r = [0; 7];
        for k in 0..6 {
            r[k + 1] = r[k] + self.rows[k];
        }
        r
    }
}

/// The heights of the rows of an edge whose levels are `lv`, the counts between them `rows`.
pub fn row_heights(lv: &[Real], rows: &[usize]) -> Vec<Real> {
    let mut y = vec![lv[0]];
    for k in 0..rows.len() {
        for i in 1..=rows[k] {
            let t = i as Real / rows[k] as Real;
            y.push(lv[k] + t * (lv[k + 1] - lv[k]));
        }
    }
    y
}
