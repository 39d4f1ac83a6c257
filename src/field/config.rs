//! Configuration of the per-object fields: encoding scales, sampling, optimiser, schedules.

use serde::{Deserialize, Serialize};

use super::{AdamWConfig, RaySamplerConfig};

/// Per-object (vMAP-style) fields and how they train.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FieldConfig {
    /// Train fields at all (off = the streaming core only: clouds, boxes, keyframes).
    pub enabled: bool,
    /// Offline protocol: read every frame first, then train `offline_iterations` steps.
    /// Online (false): `steps_per_frame` steps after each incoming frame.
    pub offline: bool,
    /// Training steps per incoming frame (online).
    pub steps_per_frame: usize,
    /// Training steps after the whole stream (offline; the paper's vMAP* uses 15 000).
    pub offline_iterations: usize,
    /// Online: refinement steps on the final keyframe windows once the stream has ended.
    pub final_steps: usize,
    /// AdamW learning rate.
    pub learning_rate: f32,
    /// AdamW decoupled weight decay.
    pub weight_decay: f32,
    /// Encoding scale of object fields (x' = x / scale); `None` = the dataset's (Replica 2.0, ScanNet 3.0).
    pub object_scale: Option<f32>,
    /// Encoding scale of the background field; `None` = the dataset's (Replica 5.0, ScanNet 10.0).
    pub background_scale: Option<f32>,
    /// Rays and samples of each object per step.
    pub object_rays: RaySamplerConfig,
    /// Rays and samples of the background per background step.
    pub background_rays: RaySamplerConfig,
    /// The background field takes one step every this many object steps (vMAP: 1; 0 = no background
    /// field, the default). The background is not evaluated, only meshed (`background.ply`,
    /// `scene.ply`), and one of its steps (H = 128, 1 200 rays) costs about as much as a step of
    /// all object fields: every 10th step it took ~40 % of the training time.
    pub background_every: usize,
}

impl Default for FieldConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            offline: false,
            steps_per_frame: 20,
            offline_iterations: 15_000,
            final_steps: 3_000,
            learning_rate: 1e-3,
            weight_decay: 0.013,
            object_scale: None,
            background_scale: None,
            object_rays: RaySamplerConfig::FAST_OBJECT,
            background_rays: RaySamplerConfig::BACKGROUND,
            background_every: 0,
        }
    }
}

impl FieldConfig {
    /// Replica's encoding scales (objects, background).
    pub const REPLICA_SCALES: (f32, f32) = (2.0, 5.0);
    /// ScanNet's encoding scales (objects, background).
    pub const SCANNET_SCALES: (f32, f32) = (3.0, 10.0);

    /// No fields: the streaming core only (clouds, boxes, keyframes), e.g. for ingest benchmarks.
    pub fn disabled() -> Self {
        Self {
            enabled: false,
            ..Self::default()
        }
    }

    /// Whether the background trains in the step after `steps_done` object steps (every
    /// `background_every`-th; never when 0).
    pub fn background_due(&self, steps_done: u64) -> bool {
        self.background_every > 0 && steps_done.is_multiple_of(self.background_every as u64)
    }

    /// Steps to run once the stream has ended: all of them offline, the refinement online.
    pub fn steps_after_stream(&self) -> usize {
        match (self.enabled, self.offline) {
            (false, _) => 0,
            (true, true) => self.offline_iterations,
            (true, false) => self.final_steps,
        }
    }

    /// The object encoding scale (Replica's when unset).
    pub fn object_scale(&self) -> f32 {
        self.object_scale.unwrap_or(Self::REPLICA_SCALES.0)
    }

    /// The background encoding scale (Replica's when unset).
    pub fn background_scale(&self) -> f32 {
        self.background_scale.unwrap_or(Self::REPLICA_SCALES.1)
    }

    /// Fills unset scales with `scales` (objects, background) — the dataset's defaults.
    pub fn with_default_scales(mut self, scales: (f32, f32)) -> Self {
        self.object_scale.get_or_insert(scales.0);
        self.background_scale.get_or_insert(scales.1);
        self
    }

    /// The optimiser settings (AdamW, PyTorch's betas and epsilon).
    pub fn optimiser(&self) -> AdamWConfig {
        AdamWConfig {
            lr: self.learning_rate,
            weight_decay: self.weight_decay,
            ..AdamWConfig::default()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_background_trains_every_nth_step_and_never_at_zero() {
        let every_three = FieldConfig {
            background_every: 3,
            ..FieldConfig::default()
        };
        let due: Vec<u64> = (0..8).filter(|&s| every_three.background_due(s)).collect();
        assert_eq!(due, vec![0, 3, 6]);
        let never = FieldConfig {
            background_every: 0,
            ..FieldConfig::default()
        };
        assert!((0..8).all(|s| !never.background_due(s)));
    }
}
