//! [`CheckpointConfig`]: when `catmap run` saves its state for `--resume`.

use serde::{Deserialize, Serialize};

/// When checkpoints are written (always also on Ctrl-C). A config file lists only what it changes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CheckpointConfig {
    /// Write checkpoints to `OUT/checkpoint/` (on Ctrl-C as well).
    pub enabled: bool,
    /// While streaming: a checkpoint every this many ingested frames (0 = never).
    pub every_frames: u64,
    /// While training after the stream and in the category phase: a checkpoint every this many
    /// steps (0 = never; rounded up to whole chunks of 50 steps).
    pub every_steps: u64,
    /// Keep the last checkpoint after the run completed (it is deleted by default).
    pub keep: bool,
}

impl Default for CheckpointConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            every_frames: 50,
            every_steps: 1000,
            keep: false,
        }
    }
}
