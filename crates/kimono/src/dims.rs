//! Tailoring dimensions of a woman's kimono (女物長着) from body measurements, by the standard-dimension
//! formulas Japanese tailors use. Each formula names its source:
//!
//! - [K] 小太郎きもの, "着物寸法の決め方" (kotaro-kimono.com/students-only/着物寸法の決め方/): 身丈 = 身長;
//!   後巾 = ヒップ/4 + 2 cm + 4 cm; 前巾 = 後巾 − 1寸5分 (ヒップ ≤ 100 cm) or − 1寸 (above);
//!   抱き巾 = バスト/4 + 2 cm, within 前巾 ± 3分; 衽巾 4寸 (4寸1分 from ヒップ 100 cm, 4寸2分 from
//!   105 cm); 合褄巾 = 衽巾 − 3分 (none taken off from ヒップ 100 cm); 褄下 = 身丈/2; 衽下がり 6寸
//!   (5寸5分 under 150 cm); 肩開き 2寸3分; 身八ツ口 4寸; 肩巾 = 裄 − 袖巾.
//! - [D] きもの大辞典, "寸法計算" (kimonodaijiten.jp/tools): 袖幅 = 裄 × 0.5 + 2.5分.
//! - [A] きものあきない, "女物の計算方法" and "女物標準寸法" (kimono-akinai.com/wasai-kiso2-1-1/,
//!   /wasai-kiso3/): 裄 = 身長 × 0.4 + 2 cm; 袖丈 = 身長 × 0.3; 袖口 6寸; 袖付 5寸5分 (6寸 for a tall
//!   or broad figure, 5寸–5寸3分 for one in the 140s); バチ衿 1寸5分 at the back centre, 2寸 at the tip.
//! - [J] j-dress, "寸法の割り出し方" (j-dress.com/post-3151/): 着丈 = 身長 × 0.83.
//! - [M] miyatama, "着物の寸法の割り出し方" (miyatama.net/2016/11/02/post-1005): 衿下 at most 82–83 cm;
//!   裄 limited by the bolt's width to about 68 cm.
//!
//! Lengths are in metres here; the sources give them in centimetres and in 鯨尺 (1 寸 = 3.788 cm,
//! 1 分 = 0.3788 cm).

use thiserror::Error;
use tryon_core::math::Real;

/// One 寸 of the 鯨尺 (the cloth-measuring foot), m.
pub const SUN: Real = 0.037_88;
/// One 分, a tenth of a 寸, m.
pub const BU: Real = SUN / 10.0;
/// Width of the bolt (反物) the kimono is cut from, m (about 1 尺).
pub const BOLT_WIDTH: Real = 0.38;

/// The wearer's measurements (metres). `yuki` (裄: back-neck centre to the wrist bone, arm held
/// 45° down) and `sleeve_length` (袖丈) are optional: by default they follow from the height [A].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wearer {
    pub height: Real,
    pub bust: Real,
    pub waist: Real,
    pub hip: Real,
    pub yuki: Option<Real>,
    pub sleeve_length: Option<Real>,
}

impl Wearer {
    /// A wearer from the four measurements, the rest by default.
    pub const fn new(height: Real, bust: Real, waist: Real, hip: Real) -> Self {
        Wearer {
            height,
            bust,
            waist,
            hip,
            yuki: None,
            sleeve_length: None,
        }
    }
}

/// Why measurements cannot be tailored: names the measurement, its value and what is allowed.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum TailorError {
    #[error("measurement `{name}` = {value} m is outside {min}..={max} m ({why})")]
    OutOfRange {
        name: &'static str,
        value: Real,
        min: Real,
        max: Real,
        why: &'static str,
    },
}

/// A kimono's tailoring dimensions (metres). The first fields are P2's Table 1 (sleeves the same
/// on both sides); the rest are what the pattern needs besides.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dimensions {
    /// 袖丈: sleeve length, shoulder fold to the sleeve's bottom.
    pub sleeve_length: Real,
    /// 袖幅: sleeve width, from the sleeve seam to the cuff edge.
    pub sleeve_width: Real,
    /// 袖付: the sleeve's attachment, shoulder fold down the sleeve seam.
    pub sleeve_attach: Real,
    /// 袖口: the sleeve's opening, shoulder fold down the cuff edge.
    pub sleeve_opening: Real,
    /// 着丈: worn length, back neck to hem, once the ohashori fold has taken up the rest.
    pub garment_length: Real,
    /// 肩幅: back centre to the sleeve seam along the shoulder.
    pub shoulder_width: Real,
    /// 前幅: front panel at the hem, okumi seam to side seam.
    pub front_width: Real,
    /// 後幅: back panel at the hem, back centre to side seam.
    pub back_width: Real,
    /// 抱幅: front panel at the bottom of the underarm opening (身八ツ口).
    pub holding_width: Real,
    /// 衿下 (褄下): the front edge from the collar's end to the hem.
    pub below_collar: Real,
    /// 衿幅 at the back centre (バチ衿).
    pub collar_width_back: Real,
    /// 衿幅 at the collar's end.
    pub collar_width_tip: Real,
    /// 合褄幅: the okumi's width where the collar ends.
    pub overlap_width: Real,
    /// 身丈: the cut length of the body, shoulder fold to hem (the worn length plus the ohashori).
    pub body_length: Real,
    /// 裄: shoulder width plus sleeve width.
    pub yuki: Real,
    /// 衽幅: the okumi's width at the hem.
    pub okumi_width: Real,
    /// 衽下がり: shoulder fold down to the okumi's tip (剣先).
    pub okumi_drop: Real,
    /// 肩開き: half the neck opening, back centre to where the collar leaves the shoulder.
    pub neck_half: Real,
    /// 身八ツ口: the underarm opening below the sleeve's attachment.
    pub underarm_opening: Real,
}

fn within(
    name: &'static str,
    value: Real,
    min: Real,
    max: Real,
    why: &'static str,
) -> Result<Real, TailorError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(value)
    } else {
        Err(TailorError::OutOfRange {
            name,
            value,
            min,
            max,
            why,
        })
    }
}

/// The tailoring dimensions for `w`.
pub fn tailor(w: &Wearer) -> Result<Dimensions, TailorError> {
    let adult = "an adult woman's kimono";
    let h = within("height", w.height, 1.40, 1.85, adult)?;
    let bust = within("bust", w.bust, 0.70, 1.30, adult)?;
    within("waist", w.waist, 0.50, 1.20, adult)?;
    // The back panel (hip/4 + 6 cm) must fit the bolt with a centimetre of seam to spare.
    let hip = within(
        "hip",
        w.hip,
        0.75,
        1.24,
        "the back width must fit a 38 cm bolt",
    )?;
    let yuki = match w.yuki {
        Some(y) => within(
            "yuki",
            y,
            0.55,
            0.70,
            "the sleeve must fit the bolt's width [M]",
        )?,
        None => 0.4 * h + 0.02, // [A]
    };
    let sleeve_length = match w.sleeve_length {
        Some(s) => within(
            "sleeve_length",
            s,
            0.35,
            0.75 * h,
            "up to a furisode's, 75% of the height",
        )?,
        None => 0.3 * h, // [A]
    };
    let sleeve_width = 0.5 * yuki + 2.5 * BU; // [D]
    let back_width = hip / 4.0 + 0.06; // [K]
    let front_width = back_width - if hip <= 1.0 { 15.0 * BU } else { SUN }; // [K]
    let holding_width = (bust / 4.0 + 0.02).clamp(front_width - 3.0 * BU, front_width + 3.0 * BU); // [K]
    let okumi_width = SUN
        * if hip >= 1.05 {
            4.2
        } else if hip >= 1.0 {
            4.1
        } else {
            4.0
        }; // [K]
    let overlap_width = if hip >= 1.0 {
        okumi_width
    } else {
        okumi_width - 3.0 * BU
    }; // [K]
    // [A]: 5寸–5寸3分 in the 140s, 5寸5分 standard, 6寸 tall (here from 1.65 m) or broad (hip 1 m).
    let sleeve_attach = SUN
        * if h < 1.50 {
            5.2
        } else if h >= 1.65 || hip >= 1.0 {
            6.0
        } else {
            5.5
        };
    Ok(Dimensions {
        sleeve_length,
        sleeve_width,
        sleeve_attach,
        sleeve_opening: 6.0 * SUN,           // [A]
        garment_length: 0.83 * h,            // [J]
        shoulder_width: yuki - sleeve_width, // [K]
        front_width,
        back_width,
        holding_width,
        below_collar: (h / 2.0).min(0.83), // [K], [M]
        collar_width_back: 1.5 * SUN,      // [A]
        collar_width_tip: 2.0 * SUN,       // [A]
        overlap_width,
        body_length: h, // [K], [A]
        yuki,
        okumi_width,
        okumi_drop: SUN * if h < 1.50 { 5.5 } else { 6.0 }, // [K]
        neck_half: 2.3 * SUN,                               // [K]
        underarm_opening: 4.0 * SUN,                        // [K]
    })
}

/// Names of P2's Table 1, in its order: the right sleeve's four, the left sleeve's four, then the
/// body's, the collar's width twice.
pub const TABLE_1: [&str; 17] = [
    "right sleeve length",
    "right sleeve width",
    "right sleeve attachment",
    "right sleeve opening",
    "left sleeve length",
    "left sleeve width",
    "left sleeve attachment",
    "left sleeve opening",
    "garment length",
    "shoulder width",
    "front width",
    "back width",
    "holding width",
    "front-panel length below the collar",
    "collar width (back)",
    "collar width (tip)",
    "overlap width",
];

impl Dimensions {
    /// Table 1's dimensions with their values, in [`TABLE_1`]'s order.
    pub fn table(&self) -> [(&'static str, Real); 17] {
        let d = self;
        let v = [
            d.sleeve_length,
            d.sleeve_width,
            d.sleeve_attach,
            d.sleeve_opening,
            d.sleeve_length,
            d.sleeve_width,
            d.sleeve_attach,
            d.sleeve_opening,
            d.garment_length,
            d.shoulder_width,
            d.front_width,
            d.back_width,
            d.holding_width,
            d.below_collar,
            d.collar_width_back,
            d.collar_width_tip,
            d.overlap_width,
        ];
        std::array::from_fn(|i| (TABLE_1[i], v[i]))
    }
}

#[cfg(test)]
#[path = "dims_tests.rs"]
mod tests;
