//! tryon-io: file formats, every output written atomically (temporary file, then rename): GLB export
//! of the animated try-on, written as the run goes ([`GlbWriter`]), shaded z-buffered PNG previews ([`render`], [`write_png`]),
//! and JSON reports ([`write_json`]); readers of real assets ([`read_obj`] keeping vertex order,
//! MakeHuman [`read_mhskel`], [`read_mhw`], [`read_target`], [`read_binding`], and [`read_bvh`]).

pub mod animation;
pub mod atomic;
pub mod bvh;
pub mod cache;
pub mod data;
pub mod glb;
mod glb_layout;
pub mod inspect;
pub mod live_frame;
pub mod machine;
pub mod makehuman;
pub mod obj;
pub mod preview;
pub mod read;
pub mod textured;
pub mod usd;
pub mod view;

pub use animation::{GifState, GifWriter};
pub use atomic::{write_atomic, write_atomic_with};
pub use bvh::{guess_unit, parse_bvh, read_bvh};
pub use cache::{CacheError, Pc2State, Pc2Writer, read_pc2, write_obj_frame};
pub use data::{DATA_ENV, data_root, data_root_from};
pub use glb::{BodyExport, FramePose, GlbError, GlbHeader, GlbState, GlbWriter, SkinnedExport};
pub use live_frame::{FRAME_HEAD, LiveFrame, depth_code, encode_frame};
pub use makehuman::{MhRig, load_makehuman, read_binding, read_mhskel, read_mhw, read_target};
pub use obj::{parse_obj, read_obj};
pub use preview::{Camera, Image, PreviewError, PreviewMesh, garment_colour, render, write_png};
pub use read::ReadError;
pub use textured::{Texture, TexturedError, TexturedMesh, render_textured, write_textured_glb};
pub use usd::{UsdMesh, UsdState, UsdWriter};
pub use view::{ViewGarment, ViewHeader, ViewMesh, ViewWriter, read_view_header};

/// Writes `value` as pretty JSON, atomically.
pub fn write_json<T: serde::Serialize>(path: &std::path::Path, value: &T) -> std::io::Result<()> {
    let mut bytes = serde_json::to_vec_pretty(value).map_err(std::io::Error::other)?;
    bytes.push(b'\n');
    write_atomic(path, &bytes)
}
