//! The bolt's print: a repeating test pattern of squares with a circle in each, in which any
//! stretch or shear of the fabric shows (P2's squares and their aspect).

use tryon_core::math::Real;

/// One tile of the print spans this much of the fabric both ways, m: two squares each way, four
/// squares across the bolt.
pub const TILE: Real = 0.095;

/// Two dye colours and the ground.
const GROUND: [u8; 3] = [238, 226, 204];
const SQUARE: [u8; 3] = [176, 48, 52];
const RING: [u8; 3] = [32, 44, 112];

/// The tile as `px` x `px` RGB texels (row-major, the first row at v = 0).
pub fn print_tile(px: usize) -> Vec<u8> {
    let px = px.max(8);
    let mut rgb = Vec::with_capacity(px * px * 3);
    for y in 0..px {
        for x in 0..px {
            // Position in squares (two per tile each way).
            let (u, v) = (
                2.0 * (x as Real + 0.5) / px as Real,
                2.0 * (y as Real + 0.5) / px as Real,
            );
            let dark = (u.floor() as i64 + v.floor() as i64) % 2 == 0;
            let r = ((u.fract() - 0.5).powi(2) + (v.fract() - 0.5).powi(2)).sqrt();
            let c = if (r - 0.3).abs() < 0.05 {
                RING
            } else if dark {
                SQUARE
            } else {
                GROUND
            };
            rgb.extend_from_slice(&c);
        }
    }
    rgb
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tile_has_two_squares_each_way_with_rings() {
        let n = 64;
        let t = print_tile(n);
        assert_eq!(t.len(), n * n * 3);
        let at = |x: usize, y: usize| {
            [
                t[3 * (y * n + x)],
                t[3 * (y * n + x) + 1],
                t[3 * (y * n + x) + 2],
            ]
        };
        assert_eq!(at(1, 1), SQUARE, "a corner of the first square");
        assert_eq!(at(33, 1), GROUND, "the next square across");
        assert_eq!(at(33, 33), SQUARE, "diagonal squares match");
        assert_eq!(
            at(16, 16 - 10),
            RING,
            "0.3 of a square above the first square's centre"
        );
    }
}
