//! Datasets as random-access frame sources: the Replica (vMAP layout), ScanNet and TUM RGB-D
//! (with per-frame mask folders) readers, and the built-in synthetic scenes, all behind
//! [`FrameSource`]; [`smoothed_depth`] smooths any source's depth.

pub mod camera_spec;
pub mod class_names;
pub mod classes;
pub mod config;
pub mod decode_guard;
pub mod images;
pub mod live_replay;
pub mod replica;
pub mod resize;
pub mod scannet;
pub mod smoothed_depth;
pub mod stream;
pub mod tum;

use crate::dataset::class_names::ClassNames;
use crate::error::Result;
use crate::ids::FrameIndex;
use crate::sensor::frame::{CameraIntrinsics, RgbdFrame};

/// A sequence of posed RGB-D frames that can be decoded in any order, from any thread.
pub trait FrameSource: Send + Sync {
    /// Number of frames in the sequence.
    fn len(&self) -> usize;
    /// True when the sequence has no frames.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Intrinsics shared by all frames.
    fn intrinsics(&self) -> CameraIntrinsics;
    /// Decodes frame `position` (0-based, < `len()`). The returned frame's `index` is its
    /// position in the dataset. Errors name the file and the reason.
    fn read_frame(&self, position: usize) -> Result<RgbdFrame>;
    /// Human-readable name for logs (usually the folder).
    fn name(&self) -> String;
    /// The names of the sequence's classes (default: Replica's, which the synthetic scenes use).
    fn class_names(&self) -> ClassNames {
        ClassNames::replica()
    }
}

impl<T: FrameSource + ?Sized> FrameSource for Box<T> {
    fn len(&self) -> usize {
        (**self).len()
    }
    fn intrinsics(&self) -> CameraIntrinsics {
        (**self).intrinsics()
    }
    fn read_frame(&self, position: usize) -> Result<RgbdFrame> {
        (**self).read_frame(position)
    }
    fn name(&self) -> String {
        (**self).name()
    }
    fn class_names(&self) -> ClassNames {
        (**self).class_names()
    }
}

/// The error of a reader asked for frame `position` of a sequence of `len` frames in `dir`.
pub fn position_out_of_range(dir: &std::path::Path, position: usize, len: usize) -> crate::error::CatmapError {
    crate::error::CatmapError::layout(
        dir,
        format!("frame position {position} is out of range: the sequence has {len} frames"),
    )
}

/// Converts a dataset position into the frame index stored on frames.
pub fn frame_index(position: usize) -> FrameIndex {
    FrameIndex(position as u64)
}
