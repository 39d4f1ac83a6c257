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
    /// A configuration's text is not a configuration: TOML that does not parse, an unknown key,
    /// a value of the wrong type (the message names the key).
    #[error("invalid config: {0}")]
    ConfigSyntax(String),
    /// A configuration value (of a file, a flag or a spec) lies outside what it may be; the
    /// message names the key and what it must be.
    #[error("invalid config: {0}")]
    ConfigValue(String),
    /// A checkpoint is missing, torn or does not match this build.
    #[error("{path}: unusable checkpoint: {reason}")]
    Checkpoint {
        /// The checkpoint file at fault.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A tensor operation of candle failed.
    #[error("tensor operation: {0}")]
    Candle(#[from] candle_core::Error),
    /// A named tensor could not be built or read.
    #[error("tensor {name}: {source}")]
    Tensor {
        /// The tensor.
        name: String,
        /// The underlying error.
        #[source]
        source: candle_core::Error,
    },
    /// Tensors could not be encoded as safetensors.
    #[error("cannot encode tensors: {0}")]
    Encode(#[from] safetensors::SafeTensorError),
    /// A named part (a tensor of a field, a checkpoint or a reference) is missing.
    #[error("{part} is missing")]
    MissingPart {
        /// The part.
        part: String,
    },
    /// Two things that must agree in size or shape do not.
    #[error("{what}: expected {expected}, found {found}")]
    ShapeMismatch {
        /// What is mismatched.
        what: String,
        /// The size or shape wanted.
        expected: String,
        /// The size or shape given.
        found: String,
    },
    /// An index names nothing (a category's member, a field of a batch).
    #[error("{what} {index} does not exist (there are {len})")]
    NoSuchIndex {
        /// What is indexed.
        what: &'static str,
        /// The index given.
        index: usize,
        /// How many there are.
        len: usize,
    },
    /// An input has too few points (or members, correspondences) for the computation.
    #[error("{what}: {found}, at least {needed} needed")]
    TooFew {
        /// What is counted.
        what: String,
        /// The least the computation works with.
        needed: usize,
        /// How many there are.
        found: usize,
    },
    /// A point set holds a NaN or infinite coordinate.
    #[error("{what} has a NaN or infinite coordinate")]
    NonFinitePoint {
        /// The point set (and the point, where known).
        what: String,
    },
    /// A value the computation needs positive (or finite, or bounded) is not.
    #[error("{what} is {value}; it must {must}")]
    BadValue {
        /// The value's name.
        what: &'static str,
        /// The value.
        value: String,
        /// What it must be.
        must: &'static str,
    },
    /// Two evaluations to compare are not of the same scene.
    #[error("the two evaluations cover different objects; compare runs of the same scene")]
    DifferentScenes,
    /// The generator could not place a scene's objects in its room.
    #[error("could not place {objects} objects in a {width_m:.1} × {depth_m:.1} m room")]
    NoRoom {
        /// Objects to place.
        objects: usize,
        /// The room's width.
        width_m: f32,
        /// The room's depth.
        depth_m: f32,
    },
    /// The mapper's state broke an invariant it keeps (an entity without its component, a
    /// field without its owner): a bug, never bad input.
    #[error("broken invariant: {0}")]
    Invariant(String),
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

    /// A size or shape mismatch of `what`.
    pub fn mismatch(what: impl Into<String>, expected: impl std::fmt::Display, found: impl std::fmt::Display) -> Self {
        Self::ShapeMismatch {
            what: what.into(),
            expected: expected.to_string(),
            found: found.to_string(),
        }
    }

    /// `found` of `what` where the computation needs at least `needed`.
    pub fn too_few(what: impl Into<String>, needed: usize, found: usize) -> Self {
        Self::TooFew {
            what: what.into(),
            needed,
            found,
        }
    }

    /// The part `part` is missing.
    pub fn missing(part: impl Into<String>) -> Self {
        Self::MissingPart { part: part.into() }
    }

    /// Wraps a candle error with the tensor it concerns.
    pub fn tensor(name: impl Into<String>) -> impl FnOnce(candle_core::Error) -> Self {
        let name = name.into();
        move |source| Self::Tensor { name, source }
    }

    /// `what` is `value` (printed with `{:?}`) but must `must`.
    pub fn bad_value(what: &'static str, value: impl std::fmt::Debug, must: &'static str) -> Self {
        Self::BadValue {
            what,
            value: format!("{value:?}"),
            must,
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
