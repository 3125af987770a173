//! garment-fit: garments sized from the same measurements as the body. Today: coarse patterns (a
//! strapped one-piece dress of P1's size and a skirt) built as tubes whose sections are the body's
//! torso sections offset by the ease, and [`place_outside`] which clears any vertex the body still
//! holds through the `Collider` contract.

pub mod patterns;

pub use patterns::{DressParams, Garment, PatternError, SkirtParams, dress, place_outside, skirt};
