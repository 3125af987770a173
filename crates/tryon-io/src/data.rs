//! Where the shared real-asset folder is: `TRYON_DATA` when set, else the first `shared/data` found
//! beside the current folder or one of its ancestors (CI puts `../shared` beside the checkout).

use std::path::{Path, PathBuf};

/// The environment variable that overrides the asset folder.
pub const DATA_ENV: &str = "TRYON_DATA";

/// The asset folder, searched from `start` upward when `TRYON_DATA` is not set.
pub fn data_root_from(start: &Path) -> Option<PathBuf> {
    if let Some(dir) = std::env::var_os(DATA_ENV) {
        return Some(PathBuf::from(dir));
    }
    let start = std::path::absolute(start).ok()?;
    start
        .ancestors()
        .map(|a| a.join("shared").join("data"))
        .find(|d| d.join("README.md").is_file())
}

/// The asset folder, searched from the current folder.
pub fn data_root() -> Option<PathBuf> {
    data_root_from(Path::new("."))
}
