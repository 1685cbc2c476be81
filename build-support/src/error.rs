//! Error type of the crate.

use std::io;
use std::path::PathBuf;

/// Longest part of rustc's stderr copied into a [`BuildError::CompileFailed`] message (bytes).
/// The whole stderr is always kept next to the failed source and in the error's `stderr` field.
pub(crate) const STDERR_IN_MESSAGE: usize = 16_000;

/// Everything that can go wrong while finding rustc, compiling a plugin or writing files.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// No usable rustc: `RUSTC` (or the explicit path) does not run, or no `rustc` is on `PATH`.
    #[error("rustc not found: {reason}")]
    RustcNotFound {
        /// What was tried and why it failed.
        reason: String,
    },

    /// rustc ran and rejected the source (or crashed).
    #[error(
        "compilation of the generated plugin failed ({status}); the source was kept in {}\n\
         rustc's stderr (also in {}):\n{}",
        source_path.display(),
        stderr_path.display(),
        truncate(stderr.trim_end())
    )]
    CompileFailed {
        /// The generated source, kept in the cache's `failed/` directory.
        source_path: PathBuf,
        /// rustc's complete stderr, kept beside the source.
        stderr_path: PathBuf,
        /// rustc's exit status, as text.
        status: String,
        /// rustc's complete stderr.
        stderr: String,
    },

    /// An I/O operation on `path` failed.
    #[error("I/O error on {}: {source}", path.display())]
    Io {
        /// The file or directory the operation was about.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },

    /// No cache directory: no override, no `RAILMBS_CACHE_DIR`, and no platform cache directory.
    #[error(
        "no cache directory for compiled plugins: pass one explicitly, or set RAILMBS_CACHE_DIR \
         ({detail})"
    )]
    NoCacheDir {
        /// Which platform variables were looked at.
        detail: String,
    },

    /// A build option or argument has an invalid value.
    #[error("invalid build option: {0}")]
    InvalidOption(String),
}

impl BuildError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: io::Error) -> Self {
        BuildError::Io {
            path: path.into(),
            source,
        }
    }
}

/// At most [`STDERR_IN_MESSAGE`] bytes of `s`, cut at a character boundary, with a note if cut.
fn truncate(s: &str) -> String {
    if s.len() <= STDERR_IN_MESSAGE {
        return s.to_owned();
    }
    let mut end = STDERR_IN_MESSAGE;
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    format!(
        "{}\n... ({} more bytes in the stderr file)",
        &s[..end],
        s.len() - end
    )
}
