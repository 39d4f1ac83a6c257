//! [`StreamConfig`] and [`DatasetConfig`]: how frames are read and how their images are interpreted.

use serde::{Deserialize, Serialize};

use crate::sensor::depth_smoothing::{BilateralDepth, DepthSmoothing};

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
    /// Live replay (`catmap run --live`).
    pub live: LiveConfig,
}

/// Live replay: the dataset streams at a sensor's rate, the mapper takes the newest frame and
/// trains in the time there is (`catmap::training::live_clock`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LiveConfig {
    /// Replay at the sensor's rate instead of waiting for the mapper (`--live`).
    pub enabled: bool,
    /// Frames per second of the replay (`--fps`); unset: 30 (the replay does not use the TUM
    /// reader's timestamps).
    pub fps: Option<f64>,
    /// Seconds of training after the last frame, before the final meshes.
    pub finish_seconds: f64,
    /// Least share of the frame interval that a tick with a frame trains, when the frames come
    /// faster than the mapper can map them (masks, clouds, registration).
    pub min_train_share: f64,
}

impl LiveConfig {
    /// The replay's rate when none is set.
    pub const DEFAULT_FPS: f64 = 30.0;

    /// The replay's frames per second.
    pub fn fps(&self) -> f64 {
        self.fps.unwrap_or(Self::DEFAULT_FPS)
    }

    /// Why the live settings are invalid, if they are.
    pub fn invalid(&self) -> Option<&'static str> {
        if self.fps.is_some_and(|f| !(f > 0.0 && f <= 1000.0)) {
            Some("stream.live.fps must be above 0 and at most 1000")
        } else if !(self.finish_seconds >= 0.0 && self.finish_seconds <= 86_400.0) {
            Some("stream.live.finish_seconds must be between 0 and 86400")
        } else if !(0.0..=0.9).contains(&self.min_train_share) {
            Some("stream.live.min_train_share must be between 0 and 0.9")
        } else {
            None
        }
    }
}

impl Default for LiveConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            fps: None,
            finish_seconds: 10.0,
            min_train_share: 0.5,
        }
    }
}

impl Default for StreamConfig {
    fn default() -> Self {
        Self {
            channel_capacity: 8,
            frames_per_tick: 1,
            stride: 1,
            max_frames: None,
            live: LiveConfig::default(),
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
    /// How depth images are smoothed before use: `none`, or `bilateral` for a depth camera's
    /// noise ([`crate::sensor::depth_smoothing`]; `catmap run --depth camera`).
    pub depth_smoothing: DepthSmoothing,
    /// The bilateral filter's parameters (used with `depth_smoothing = "bilateral"`).
    pub bilateral: BilateralDepth,
    /// How far a measured depth d may stray from the surface: this × d² metres (0 for exact
    /// depth). What a view says of a point ([`crate::objects::cell_evidence`]: seen free, at
    /// the surface, behind it) widens its margins by it, so that one noisy pixel among many
    /// views does not call a cell inside an object seen free (`catmap run --depth camera`:
    /// 0.0025, about 1.5 σ of a Kinect's axial noise at 3 m; at 0.005 a table's space under its
    /// top was no longer seen free and filled).
    pub depth_noise_per_m2: f32,
}

impl Default for DatasetConfig {
    fn default() -> Self {
        Self {
            depth_scale: 1000.0,
            max_depth_m: 8.0,
            depth_smoothing: DepthSmoothing::None,
            bilateral: BilateralDepth::default(),
            depth_noise_per_m2: 0.0,
        }
    }
}
