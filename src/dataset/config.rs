//! [`StreamConfig`] and [`DatasetConfig`]: how frames are read and how their images are interpreted.

use serde::{Deserialize, Serialize};

/// Reader thread and channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StreamConfig {
    /// Capacity of the bounded channel between the reader thread and the mapper, in frames.
    pub channel_capacity: usize,
    /// Most frames the ingest system takes from the channel per tick.
    pub frames_per_tick: usize,
    /// Use every `stride`-th frame of the dataset (1 = all).
    pub stride: usize,
    /// Stop after this many frames (after striding); `None` = all.
    pub max_frames: Option<usize>,
}

impl Default for StreamConfig {
    fn default() -> Self {
        Self {
            channel_capacity: 8,
            frames_per_tick: 1,
            stride: 1,
            max_frames: None,
        }
    }
}

/// Interpretation of dataset images.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DatasetConfig {
    /// Raw depth units per metre (Replica and ScanNet: millimetres, 1000).
    pub depth_scale: f32,
    /// Depth beyond this is treated as invalid, metres.
    pub max_depth_m: f32,
}

impl Default for DatasetConfig {
    fn default() -> Self {
        Self {
            depth_scale: 1000.0,
            max_depth_m: 8.0,
        }
    }
}
