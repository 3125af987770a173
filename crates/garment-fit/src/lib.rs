//! garment-fit: garments sized from the same measurements as the body. Today: coarse patterns (a
//! strapped one-piece dress of P1's size and a skirt), a short-sleeved shirt cut from the body itself ([`shirt`]) built as tubes whose sections are the body's
//! torso sections offset by the ease, and [`place_outside`] which clears any vertex the body still
//! holds through the `Collider` contract; MakeHuman .mhclo garments refitted onto a morphed body
//! ([`fit_garment`]).

pub mod attach;
pub mod bands;
pub mod close;
mod gusset;
pub mod layer;
pub mod mhclo;
pub mod patterns;
pub mod pieces;
pub mod shirt;
pub mod weld;

#[cfg(test)]
mod testing;

pub use attach::{Attachment, Riding, apply_attachments, attach_small_pieces, components};
pub use bands::{boundary_loops, select_bands};
pub use close::{CloseError, close_openings};
pub use layer::{LayerPlacement, place_over};
pub use mhclo::{FitError, binding_scales, fit_garment, fit_garment_outside, fit_positions};
pub use patterns::{DressParams, Garment, PatternError, SkirtParams, dress, place_outside, skirt};
pub use pieces::place_pieces;
pub use shirt::{Arm, ShirtBody, ShirtParams, shirt, split_in_four};
pub use weld::{Welded, median_edge, weld_short_edges};

/// Union-find root of `a` with path halving (`parent[r] == r` at a root).
pub(crate) fn find_root(parent: &mut [usize], mut a: usize) -> usize {
    while parent[a] != a {
        parent[a] = parent[parent[a]];
        a = parent[a];
    }
    a
}
