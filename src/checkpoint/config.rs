//! [`CheckpointConfig`]: when `catmap run` saves its state for `--resume`.
//!
//! A checkpoint is due by count (every so many ingested frames while streaming, every so many
//! training steps after the stream) or by the wall clock (once a set number of seconds of work
//! has passed since the last checkpoint, or since the run or its resume started), whichever
//! comes first: a kill loses at most that many seconds. Checkpoints are taken only between
//! steps, and what a run computes does not depend on where they fall.

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
    /// steps (0 = never; rounded up to whole chunks of training steps).
    pub every_steps: u64,
    /// In every phase: a checkpoint once this many seconds of work have passed since the last
    /// one, or since the run (or its resume) started (0 = never).
    pub every_seconds: f64,
    /// Keep the last checkpoint after the run completed (it is deleted by default).
    pub keep: bool,
}

impl Default for CheckpointConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            every_frames: 50,
            every_steps: 1000,
            every_seconds: 20.0,
            keep: false,
        }
    }
}

/// Where a run stands when it asks whether a checkpoint is due.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunCount {
    /// Streaming: frames ingested so far.
    Frames(u64),
    /// Training after the stream: steps of the phase done, reported after whole chunks of
    /// `chunk` steps.
    Steps {
        /// Steps of the phase done.
        done: u64,
        /// Steps per chunk.
        chunk: u64,
    },
}

impl CheckpointConfig {
    /// Whether a checkpoint is due at `count`, `seconds_since_last` seconds after the last
    /// checkpoint (or the start of the run or its resume). Never when checkpoints are disabled.
    pub fn is_due(&self, count: RunCount, seconds_since_last: f64) -> bool {
        if !self.enabled {
            return false;
        }
        let by_count = match count {
            RunCount::Frames(done) => self.every_frames > 0 && done.is_multiple_of(self.every_frames),
            RunCount::Steps { done, chunk } => {
                let every = self.every_steps.div_ceil(chunk.max(1)) * chunk.max(1);
                every > 0 && done.is_multiple_of(every)
            }
        };
        let by_clock = self.every_seconds > 0.0 && seconds_since_last >= self.every_seconds;
        by_count || by_clock
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn only(every_frames: u64, every_steps: u64, every_seconds: f64) -> CheckpointConfig {
        CheckpointConfig {
            every_frames,
            every_steps,
            every_seconds,
            ..CheckpointConfig::default()
        }
    }

    #[test]
    fn frames_and_steps_count_whole_periods_steps_rounded_up_to_chunks() {
        let cfg = only(4, 75, 0.0);
        let due: Vec<u64> = (1..=12).filter(|&n| cfg.is_due(RunCount::Frames(n), 0.0)).collect();
        assert_eq!(due, [4, 8, 12]);
        let due: Vec<u64> = (1..=6)
            .map(|k| 50 * k)
            .filter(|&done| cfg.is_due(RunCount::Steps { done, chunk: 50 }, 0.0))
            .collect();
        assert_eq!(due, [100, 200, 300], "75 steps round up to two chunks of 50");
    }

    #[test]
    fn the_clock_makes_a_checkpoint_due_between_counts() {
        let cfg = only(50, 1000, 20.0);
        assert!(!cfg.is_due(RunCount::Frames(7), 19.9));
        assert!(cfg.is_due(RunCount::Frames(7), 20.0));
        assert!(cfg.is_due(RunCount::Steps { done: 150, chunk: 50 }, 31.0));
        assert!(!cfg.is_due(RunCount::Steps { done: 150, chunk: 50 }, 3.0));
    }

    #[test]
    fn zero_turns_a_cadence_off_and_disabled_checkpoints_are_never_due() {
        let cfg = only(0, 0, 0.0);
        assert!(!cfg.is_due(RunCount::Frames(50), 1e9));
        assert!(!cfg.is_due(RunCount::Steps { done: 1000, chunk: 50 }, 1e9));
        let off = CheckpointConfig {
            enabled: false,
            ..CheckpointConfig::default()
        };
        assert!(!off.is_due(RunCount::Frames(50), 1e9));
    }

    #[test]
    fn the_default_saves_at_least_every_twenty_seconds_of_work() {
        let cfg = CheckpointConfig::default();
        assert!(cfg.is_due(RunCount::Frames(1), 20.0));
        assert!(cfg.is_due(RunCount::Steps { done: 50, chunk: 50 }, 20.0));
        assert!(!cfg.is_due(RunCount::Frames(1), 10.0));
    }
}
