//! The library's error type. Every variant names the file or value at fault and the reason.

use std::path::PathBuf;

/// Errors of the catmap library.
#[derive(Debug, thiserror::Error)]
pub enum CatmapError {
    /// A file or folder could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A dataset folder is not laid out as expected.
    #[error("{path}: {reason}")]
    Layout {
        /// The folder or file that is missing or malformed.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// An image could not be decoded or has the wrong size or format.
    #[error("{path}: bad image: {reason}")]
    Image {
        /// The image file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A text file (pose, intrinsics) could not be parsed.
    #[error("{path}:{line}: {reason}")]
    Parse {
        /// The text file.
        path: PathBuf,
        /// 1-based line number (0 when the file as a whole is at fault).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A configuration value is invalid.
    #[error("invalid config: {0}")]
    Config(String),
    /// A checkpoint is missing, torn or does not match this build.
    #[error("{path}: unusable checkpoint: {reason}")]
    Checkpoint {
        /// The checkpoint file at fault.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A geometric computation got input it cannot work with.
    #[error("degenerate input: {0}")]
    Degenerate(String),
}

impl CatmapError {
    /// Wraps an I/O error with the path it concerns.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }

    /// A checkpoint error for `path`.
    pub fn checkpoint(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Self::Checkpoint {
            path: path.into(),
            reason: reason.into(),
        }
    }

    /// A layout error for `path`.
    pub fn layout(path: impl Into<PathBuf>, reason: impl Into<String>) -> Self {
        Self::Layout {
            path: path.into(),
            reason: reason.into(),
        }
    }
}

/// Result alias for the library.
pub type Result<T, E = CatmapError> = std::result::Result<T, E>;
