//! A live frame as `tryon view SCENE` streams it to the page over its WebSocket: the same meshes
//! as a view.bin frame, with what the page plots and the state of the user's hand.

use tryon_core::math::{Real, Vec3};

/// Bytes before the positions in a frame message.
pub const FRAME_HEAD: usize = 32;
/// A frame message's first u32.
const FRAME_KIND: u32 = 1;

/// A depth in the body (m) as view.bin and live frames carry it: quarter millimetres, 0 outside,
/// 255 at 63.75 mm and deeper.
pub fn depth_code(depth_m: Real) -> u8 {
    match depth_m > 0.0 {
        true => (depth_m * 4000.0).round().min(255.0) as u8,
        false => 0,
    }
}

/// One live frame: what the page draws and plots.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LiveFrame {
    pub frame: u32,
    pub time: Real,
    /// Wall time of the frame's work (ms).
    pub ms: Real,
    /// The deepest garment vertex in the body (m); live, of the frame before (judged while
    /// this one was on its way).
    pub max_penetration_m: Real,
    pub max_stretch: Real,
    /// The coarse particle in the user's hand.
    pub grabbed: Option<u32>,
    pub body: Vec<Vec3>,
    /// The coarse cloth under a refined garment (empty when the garment is the coarse cloth).
    pub coarse: Vec<Vec3>,
    pub garment: Vec<Vec3>,
    /// Each garment vertex's depth inside the body in quarter millimetres (255: 63.75 mm or
    /// more); empty when not judged. Live, of the frame before, as `max_penetration_m`.
    pub depth: Vec<u8>,
}

/// A frame as the page reads it (little-endian): u32 kind (1), u32 frame, u32 ack (the last
/// request of the page applied before the frame was made), i32 grabbed particle (-1: none), f32
/// time, ms, max penetration (m) and max stretch; then f32 x, y, z of the body's, the coarse
/// cloth's and the garment's vertices; then one depth byte per garment vertex (or none), padded
/// with zeros to a multiple of 4.
pub fn encode_frame(f: &LiveFrame, ack: u32) -> Vec<u8> {
    let points = f.body.len() + f.coarse.len() + f.garment.len();
    let mut out = Vec::with_capacity(FRAME_HEAD + 12 * points + f.depth.len() + 3);
    let grabbed = f.grabbed.map_or(-1, |p| p as i32);
    for w in [FRAME_KIND, f.frame, ack, grabbed as u32] {
        out.extend_from_slice(&w.to_le_bytes());
    }
    for x in [f.time, f.ms, f.max_penetration_m, f.max_stretch] {
        out.extend_from_slice(&(x as f32).to_le_bytes());
    }
    for p in f.body.iter().chain(&f.coarse).chain(&f.garment) {
        for c in p.iter() {
            out.extend_from_slice(&(*c as f32).to_le_bytes());
        }
    }
    out.extend_from_slice(&f.depth);
    out.resize(out.len().next_multiple_of(4), 0);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depths_are_quarter_millimetres_clamped() {
        assert_eq!(depth_code(-0.01), 0);
        assert_eq!(depth_code(Real::NAN), 0);
        assert_eq!(depth_code(0.001), 4);
        assert_eq!(depth_code(0.0101), 40);
        assert_eq!(depth_code(1.0), 255);
    }

    #[test]
    fn a_frame_is_laid_out_as_the_page_reads_it() {
        let f = LiveFrame {
            frame: 3,
            time: 0.1,
            grabbed: Some(9),
            body: vec![Vec3::new(1.0, 2.0, 3.0)],
            garment: vec![Vec3::new(4.0, 5.0, 6.0); 2],
            depth: vec![7, 255],
            ..LiveFrame::default()
        };
        let b = encode_frame(&f, 5);
        assert_eq!(b.len(), FRAME_HEAD + 12 * 3 + 4);
        let u32_at = |k: usize| u32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap());
        let f32_at = |k: usize| f32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap());
        assert_eq!((u32_at(0), u32_at(1), u32_at(2), u32_at(3)), (1, 3, 5, 9));
        assert_eq!(f32_at(4), 0.1);
        assert_eq!(
            (f32_at(8), f32_at(10), f32_at(11), f32_at(16)),
            (1.0, 3.0, 4.0, 6.0)
        );
        assert_eq!(&b[FRAME_HEAD + 36..], &[7, 255, 0, 0]);
        let none = encode_frame(&LiveFrame::default(), 0);
        assert_eq!(u32_at_of(&none, 3), u32::MAX);
    }

    fn u32_at_of(b: &[u8], k: usize) -> u32 {
        u32::from_le_bytes(b[4 * k..4 * k + 4].try_into().unwrap())
    }
}
