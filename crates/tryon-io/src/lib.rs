//! tryon-io: file formats, every output written atomically (temporary file, then rename): GLB export
//! of the animated try-on ([`write_glb`]), shaded z-buffered PNG previews ([`render`], [`write_png`]),
//! and JSON reports ([`write_json`]).

pub mod atomic;
pub mod glb;
pub mod preview;

pub use atomic::write_atomic;
pub use glb::{AnimatedScene, BodyExport, GlbError, SkinnedExport, glb_bytes, write_glb};
pub use preview::{Camera, Image, PreviewError, PreviewMesh, render, write_png};

/// Writes `value` as pretty JSON, atomically.
pub fn write_json<T: serde::Serialize>(path: &std::path::Path, value: &T) -> std::io::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(std::io::Error::other)?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}
