//! Body measurements (what a tailor takes) and the landmark heights derived from them. The parametric
//! mannequin (body-collide) and the garment patterns (garment-fit) both read these, so a garment sized
//! from a set of measurements fits the body built from the same set.

use crate::math::Real;
use thiserror::Error;

/// A tailor's measurements (metres). Girths are horizontal circumferences (a tape around the body).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Measurements {
    /// Standing height, floor to the top of the head.
    pub height: Real,
    /// Girth at the fullest part of the chest.
    pub bust: Real,
    /// Girth at the natural waist (the narrowest part of the torso).
    pub waist: Real,
    /// Girth at the fullest part of the seat.
    pub hip: Real,
    /// Shoulder point to shoulder point, straight across (biacromial).
    pub shoulder_width: Real,
    /// Shoulder point to wrist along the arm.
    pub arm_length: Real,
    /// Crotch to floor.
    pub inseam: Real,
}

impl Default for Measurements {
    /// A medium female figure (about EU size 38).
    fn default() -> Self {
        Measurements {
            height: 1.65,
            bust: 0.88,
            waist: 0.70,
            hip: 0.96,
            shoulder_width: 0.38,
            arm_length: 0.56,
            inseam: 0.76,
        }
    }
}

/// Why a set of measurements cannot make a body. Names the measurement and the allowed range.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MeasureError {
    #[error(
        "measurement `{name}` = {value} m is outside the supported range {min:.3}..={max:.3} m for this height"
    )]
    OutOfRange {
        name: &'static str,
        value: Real,
        min: Real,
        max: Real,
    },
    #[error("waist ({waist} m) must be smaller than both bust ({bust} m) and hip ({hip} m)")]
    WaistTooLarge { waist: Real, bust: Real, hip: Real },
}

/// Heights (y, metres above the floor) of the body's landmarks.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Landmarks {
    pub ankle: Real,
    pub knee: Real,
    pub crotch: Real,
    pub hip: Real,
    pub waist: Real,
    pub bust: Real,
    pub armpit: Real,
    pub shoulder: Real,
    pub neck: Real,
    pub chin: Real,
    pub top: Real,
}

impl Measurements {
    /// Checks every measurement against the range the mannequin supports (relative to height where
    /// proportions matter).
    pub fn validate(&self) -> Result<(), MeasureError> {
        let h = self.height;
        let check = |name: &'static str, value: Real, min: Real, max: Real| {
            if value.is_finite() && value >= min && value <= max {
                Ok(())
            } else {
                Err(MeasureError::OutOfRange {
                    name,
                    value,
                    min,
                    max,
                })
            }
        };
        check("height", h, 1.2, 2.2)?;
        check("bust", self.bust, 0.45 * h, 0.80 * h)?;
        check("waist", self.waist, 0.30 * h, 0.75 * h)?;
        check("hip", self.hip, 0.45 * h, 0.80 * h)?;
        check("shoulder_width", self.shoulder_width, 0.19 * h, 0.28 * h)?;
        check("arm_length", self.arm_length, 0.28 * h, 0.40 * h)?;
        check("inseam", self.inseam, 0.40 * h, 0.52 * h)?;
        if self.waist >= self.bust || self.waist >= self.hip {
            return Err(MeasureError::WaistTooLarge {
                waist: self.waist,
                bust: self.bust,
                hip: self.hip,
            });
        }
        Ok(())
    }

    /// Landmark heights from the height and inseam (standard anthropometric proportions).
    pub fn landmarks(&self) -> Landmarks {
        let h = self.height;
        let crotch = self.inseam;
        Landmarks {
            ankle: 0.045 * h,
            knee: 0.285 * h,
            crotch,
            hip: crotch + 0.045 * h,
            waist: 0.615 * h,
            bust: 0.72 * h,
            armpit: 0.745 * h,
            shoulder: 0.815 * h,
            neck: 0.84 * h,
            chin: 0.87 * h,
            top: h,
        }
    }

    /// Scale of lengths relative to the default figure (1 at 1.65 m).
    pub fn scale(&self) -> Real {
        self.height / 1.65
    }

    /// The torso's cross-sections at its control heights, ascending from the crotch to the chin:
    /// (height, [half-width, half-depth, z of the centre]). The sections are ellipses; at the hip,
    /// waist and bust heights a `samples`-gon of the ellipse has exactly the measured girth.
    pub fn torso_keys(&self, samples: usize) -> Vec<(Real, [Real; 3])> {
        let lm = self.landmarks();
        let sc = self.scale();
        let hip = girth_section(self.hip, 0.80, -0.012 * sc, samples);
        vec![
            (lm.crotch, [0.9 * hip[0], 0.9 * hip[1], hip[2]]),
            (lm.hip, hip),
            (lm.waist, girth_section(self.waist, 0.74, 0.0, samples)),
            (lm.bust, girth_section(self.bust, 0.76, 0.012 * sc, samples)),
            (
                lm.armpit,
                girth_section(0.93 * self.bust, 0.68, 0.0, samples),
            ),
            (
                lm.shoulder - 0.035 * sc,
                [
                    0.5 * self.shoulder_width - 0.005 * sc,
                    0.072 * sc,
                    -0.01 * sc,
                ],
            ),
            (
                lm.shoulder,
                [0.42 * self.shoulder_width, 0.066 * sc, -0.012 * sc],
            ),
            // The top of the shoulders is nearly flat beside the neck (a strap rests there).
            (lm.neck - 0.01 * sc, [0.11 * sc, 0.062 * sc, -0.012 * sc]),
            (lm.neck, [0.058 * sc, 0.06 * sc, -0.012 * sc]),
            (lm.chin, [0.055 * sc, 0.058 * sc, -0.01 * sc]),
        ]
    }
}

/// Cubic ease 3t^2 - 2t^3 on t clamped to [0, 1].
pub fn smoothstep(t: Real) -> Real {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Interpolates a piecewise profile of (key, values) with smoothstep between neighbouring keys
/// (keys ascending; constant beyond the ends): control values are met exactly.
pub fn profile<const N: usize>(keys: &[(Real, [Real; N])], y: Real) -> [Real; N] {
    if keys.is_empty() {
        return [0.0; N];
    }
    if y <= keys[0].0 {
        return keys[0].1;
    }
    for w in keys.windows(2) {
        let ((y0, v0), (y1, v1)) = (w[0], w[1]);
        if y <= y1 {
            let s = smoothstep((y - y0) / (y1 - y0));
            return std::array::from_fn(|k| v0[k] + (v1[k] - v0[k]) * s);
        }
    }
    keys[keys.len() - 1].1
}

/// Perimeter of the `samples`-gon sampling an ellipse of half-axes (1, aspect) at equal angles.
pub fn unit_ellipse_perimeter(aspect: Real, samples: usize) -> Real {
    let pt = |k: usize| {
        let t = std::f64::consts::TAU * k as Real / samples as Real;
        (t.cos(), aspect * t.sin())
    };
    (0..samples)
        .map(|k| {
            let (a, b) = (pt(k), pt(k + 1));
            ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt()
        })
        .sum()
}

/// [half-width, half-depth, z-centre] of an elliptic section of girth `g` (as a `samples`-gon)
/// and depth/width ratio `aspect`.
pub fn girth_section(g: Real, aspect: Real, c: Real, samples: usize) -> [Real; 3] {
    let a = g / unit_ellipse_perimeter(aspect, samples);
    [a, a * aspect, c]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_valid_and_landmarks_ascend() {
        let m = Measurements::default();
        m.validate().unwrap();
        let l = m.landmarks();
        let ys = [
            l.ankle, l.knee, l.crotch, l.hip, l.waist, l.bust, l.armpit, l.shoulder, l.neck,
            l.chin, l.top,
        ];
        assert!(ys.windows(2).all(|w| w[0] < w[1]), "{ys:?}");
    }

    #[test]
    fn out_of_range_names_the_measurement() {
        let m = Measurements {
            inseam: 2.0,
            ..Measurements::default()
        };
        let e = m.validate().unwrap_err().to_string();
        assert!(e.contains("inseam"), "{e}");
        let m = Measurements {
            waist: 1.0,
            ..Measurements::default()
        };
        assert!(matches!(
            m.validate(),
            Err(MeasureError::WaistTooLarge { .. })
        ));
    }
}
