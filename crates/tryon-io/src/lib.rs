//! tryon-io: file formats. Today: shaded, z-buffered PNG previews of meshes, written atomically.

pub mod atomic;
pub mod preview;

pub use atomic::write_atomic;
pub use preview::{Camera, Image, PreviewError, PreviewMesh, render, write_png};
