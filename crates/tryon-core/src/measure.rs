//! Body measurements (what a tailor takes) and the landmark heights derived from them. The parametric
//! mannequin (body-collide) and the garment patterns (garment-fit) both read these, so a garment sized
//! from a set of measurements fits the body built from the same set.

use crate::math::Real;
use thiserror::Error;

/// A tailor's measurements (metres). Girths are horizontal circumferences (a tape around the body).
#[derive(Clone, Copy, Debug, PartialEq)]
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
    #[error("measurement `{name}` = {value} m is outside the supported range {min}..={max} m")]
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
#[derive(Clone, Copy, Debug, PartialEq)]
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
            l.ankle, l.knee, l.crotch, l.hip, l.waist, l.bust, l.armpit, l.shoulder, l.neck, l.chin,
            l.top,
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
