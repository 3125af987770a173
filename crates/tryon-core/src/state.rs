//! A stage's state between frames, as bytes for a checkpoint (`tryon run --resume`).
//!
//! A stage that can be checkpointed derives serde's traits on itself (and on what it holds) and
//! implements its trait's `save_state` and `restore_state` with [`whole_state!`]: the whole
//! object is written (postcard, floats as their exact bits), so no field that carries a frame's
//! result into the next can be forgotten; restoring replaces the freshly built object. A stage
//! that does not implement them cannot be checkpointed, and a run that has one says so instead of
//! writing checkpoints that would not resume to the same bytes.

use serde::Serialize;
use serde::de::DeserializeOwned;
use thiserror::Error;

/// Why a stage's state could not be restored.
#[derive(Debug, Error, PartialEq, Eq)]
#[non_exhaustive]
pub enum StateError {
    #[error("this stage cannot be checkpointed")]
    Unsupported,
    #[error("the stage's state does not decode: {0}")]
    Decode(String),
    #[error("the stage's state does not fit the stage built from the scene: {0}")]
    Mismatch(String),
}

/// The bytes of `value`.
pub fn encode<T: Serialize + ?Sized>(value: &T) -> Vec<u8> {
    // Writing into a vector fails only for types serde cannot describe (none derive that way).
    postcard::to_stdvec(value).unwrap_or_default()
}

/// The value `bytes` hold; every byte must be used.
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, StateError> {
    let (value, rest) =
        postcard::take_from_bytes(bytes).map_err(|e| StateError::Decode(e.to_string()))?;
    if !rest.is_empty() {
        return Err(StateError::Decode(format!(
            "{} bytes left over after the state",
            rest.len()
        )));
    }
    Ok(value)
}

/// FNV-1a over `bytes`: a checkpoint's check sum and a scene's fingerprint (stable across
/// builds and platforms, unlike std's hasher).
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// Implements a stage trait's `save_state` and `restore_state` over the whole object (which
/// derives serde's `Serialize` and `Deserialize`); see the module docs.
#[macro_export]
macro_rules! whole_state {
    () => {
        fn save_state(&self) -> Option<Vec<u8>> {
            Some($crate::state::encode(self))
        }
        fn restore_state(&mut self, state: &[u8]) -> Result<(), $crate::state::StateError> {
            *self = $crate::state::decode(state)?;
            Ok(())
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    #[test]
    fn values_come_back_bit_for_bit_and_bad_bytes_are_errors() {
        let v = vec![
            Vec3::new(0.1, -1e-300, 1.0 / 3.0),
            Vec3::new(f64::MAX, 0.0, -0.0),
        ];
        let back: Vec<Vec3> = decode(&encode(&v)).unwrap();
        let bits = |v: &[Vec3]| -> Vec<u64> { v.iter().flatten().map(|x| x.to_bits()).collect() };
        assert_eq!(bits(&back), bits(&v));
        let bytes = encode(&v);
        assert!(matches!(
            decode::<Vec<Vec3>>(&bytes[..bytes.len() - 3]),
            Err(StateError::Decode(_))
        ));
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(matches!(
            decode::<Vec<Vec3>>(&longer),
            Err(StateError::Decode(m)) if m.contains("left over")
        ));
    }

    #[test]
    fn fnv1a_matches_the_published_vectors() {
        // From the FNV authors' test suite (isthe.com/chongo/src/fnv/test_fnv.c).
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
