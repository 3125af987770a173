//! What every asset reader shares: a size-limited read of the whole file, the one error type of
//! "reading an asset file" (always naming the file, and the line where there is one), and number parsing.

use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Largest asset file any reader accepts (bytes). MakeHuman's biggest file is about 4 MB; CMU clips
/// are under 2 MB.
pub const MAX_FILE_BYTES: u64 = 256 << 20;

/// Why an asset file could not be read.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ReadError {
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: {size} bytes is more than the {limit}-byte limit for asset files")]
    TooLarge {
        file: PathBuf,
        size: u64,
        limit: u64,
    },
    #[error("{file}: not UTF-8 text (byte {offset})")]
    NotText { file: PathBuf, offset: usize },
    #[error("{file}:{line}: {message}")]
    Syntax {
        file: PathBuf,
        line: usize,
        message: String,
    },
    #[error("{file}:{line}:{column}: {message}")]
    Json {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{file}: unknown kind of file: expected {expected}")]
    UnknownKind {
        file: PathBuf,
        expected: &'static str,
    },
    #[error("{file}:{line}: {what} exceeds the limit of {limit}")]
    Limit {
        file: PathBuf,
        line: usize,
        what: &'static str,
        limit: usize,
    },
}

impl ReadError {
    /// The line the error points at, if any.
    pub fn line(&self) -> Option<usize> {
        match self {
            ReadError::Syntax { line, .. }
            | ReadError::Json { line, .. }
            | ReadError::Limit { line, .. } => Some(*line),
            _ => None,
        }
    }
}

/// Reads a whole text file, refusing files over [`MAX_FILE_BYTES`].
pub fn read_text(path: &Path) -> Result<String, ReadError> {
    let io = |source| ReadError::Io {
        file: path.to_path_buf(),
        source,
    };
    let f = fs::File::open(path).map_err(io)?;
    let size = f.metadata().map_err(io)?.len();
    if size > MAX_FILE_BYTES {
        return Err(ReadError::TooLarge {
            file: path.to_path_buf(),
            size,
            limit: MAX_FILE_BYTES,
        });
    }
    let mut bytes = Vec::with_capacity(size as usize);
    f.take(MAX_FILE_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    String::from_utf8(bytes).map_err(|e| ReadError::NotText {
        file: path.to_path_buf(),
        offset: e.utf8_error().valid_up_to(),
    })
}

/// A cursor for error messages: the file and a 1-based line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct At<'a> {
    pub file: &'a Path,
    pub line: usize,
}

impl At<'_> {
    pub fn err(&self, message: impl Into<String>) -> ReadError {
        ReadError::Syntax {
            file: self.file.to_path_buf(),
            line: self.line,
            message: message.into(),
        }
    }

    pub fn limit(&self, what: &'static str, limit: usize) -> ReadError {
        ReadError::Limit {
            file: self.file.to_path_buf(),
            line: self.line,
            what,
            limit,
        }
    }

    /// A finite number, or an error naming what was expected.
    pub fn real(&self, tok: Option<&str>, what: &str) -> Result<f64, ReadError> {
        let tok =
            tok.ok_or_else(|| self.err(format!("expected {what}, found the end of the line")))?;
        match tok.parse::<f64>() {
            Ok(x) if x.is_finite() => Ok(x),
            _ => Err(self.err(format!("expected {what} (a finite number), found `{tok}`"))),
        }
    }

    /// A mesh coordinate: a finite number within +-[`MAX_COORDINATE`].
    pub fn coordinate(&self, tok: Option<&str>, what: &str) -> Result<f64, ReadError> {
        let x = self.real(tok, what)?;
        match x.abs() <= MAX_COORDINATE {
            true => Ok(x),
            false => Err(self.err(format!(
                "{what} {x:e} is beyond +-1e6: no mesh in metres, centimetres or millimetres reaches it"
            ))),
        }
    }

    /// A non-negative integer.
    pub fn index(&self, tok: Option<&str>, what: &str) -> Result<u32, ReadError> {
        let tok =
            tok.ok_or_else(|| self.err(format!("expected {what}, found the end of the line")))?;
        tok.parse::<u32>()
            .map_err(|_| self.err(format!("expected {what} (a vertex index), found `{tok}`")))
    }
}

/// The largest mesh coordinate read (in the file's units).
pub const MAX_COORDINATE: f64 = 1e6;

/// Converts a serde_json error into a [`ReadError::Json`] for `file`.
pub(crate) fn json_error(file: &Path, e: serde_json::Error) -> ReadError {
    ReadError::Json {
        file: file.to_path_buf(),
        line: e.line(),
        column: e.column(),
        message: {
            let m = e.to_string();
            match m.rfind(" at line ") {
                Some(i) => m[..i].to_string(),
                None => m,
            }
        },
    }
}

/// A number as a person reads it: exponent form when it is huge or tiny.
pub(crate) fn short(v: f64) -> String {
    if v != 0.0 && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}
