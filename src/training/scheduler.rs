//! [`StepScheduler`]: which fields take the next training steps.
//!
//! Every step of the batched model costs in proportion to the fields it trains, so the fast
//! schedule trains only the fields that gain from a step:
//! - a field seen in this tick's frames (its newest keyframe slot holds a new view) trains;
//! - a new keyframe also restarts its convergence test (the data changed);
//! - otherwise a field trains while its loss still falls ([`LossWindow`]) and stops once it
//!   has plateaued;
//! - a category member's own field, while its category field makes its mesh
//!   ([`FieldRole::Supporting`]), trains only on a new keyframe, at a low rate, to keep its
//!   uncertainty and re-registration current; a [`FieldRole::Frozen`] field never trains.
//!
//! The paper's schedule ([`SchedulePolicy::Paper`]) trains every field on every step, as the
//! fixed protocol does. The scheduler is pure: the mapper hands it the facts (roles,
//! sightings, losses) and applies its plans; the same facts give the same plans.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::facts::{FieldFacts, FieldKey};
use super::field_progress::{FieldProgress, FieldState};
use super::plateau::PlateauConfig;

/// How steps are given out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SchedulePolicy {
    /// Train what changes the map: seen, still improving; stop converged and replaced fields.
    Fast,
    /// The paper's fixed protocol: every field on every step.
    Paper,
}

/// The fields of a batch that take the next steps, ascending by batch index.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BatchPlan {
    /// Their batch indices.
    pub indices: Vec<usize>,
    /// Their keys, in the same order.
    pub keys: Vec<FieldKey>,
    /// Their learning-rate factors, in the same order.
    pub learning_rate_scales: Vec<f32>,
}

impl BatchPlan {
    /// The background field (index 0 of its own batch) at its full rate.
    pub fn background() -> Self {
        Self {
            indices: vec![0],
            keys: vec![FieldKey::Background],
            learning_rate_scales: vec![1.0],
        }
    }
}

/// Plans training steps field by field (see the module doc).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct StepScheduler {
    fields: BTreeMap<FieldKey, FieldProgress>,
}

impl StepScheduler {
    /// The fields that take the next steps, in key order, given this tick's `facts`. Fields
    /// missing from `facts` are not planned (their progress is kept).
    pub fn plan(&mut self, facts: &[FieldFacts], policy: SchedulePolicy, plateau: &PlateauConfig) -> Vec<FieldKey> {
        let mut planned: Vec<FieldKey> = facts
            .iter()
            .filter(|f| {
                let progress = self.fields.entry(f.key).or_default();
                let state = match policy {
                    SchedulePolicy::Paper => FieldState::Training,
                    SchedulePolicy::Fast => progress.advance(f, plateau),
                };
                if state == FieldState::Converged && progress.state != FieldState::Converged {
                    progress.converged_at = Some(progress.steps);
                }
                progress.state = state;
                state == FieldState::Training
            })
            .map(|f| f.key)
            .collect();
        planned.sort_unstable();
        planned.dedup();
        planned
    }

    /// [`StepScheduler::plan`] for fields that sit at batch indices: `facts` pairs each field's
    /// index with its facts; returns the planned fields ascending by index, with their keys and
    /// learning-rate factors — what a batched step takes.
    pub fn plan_batch(
        &mut self,
        facts: &[(usize, FieldFacts)],
        policy: SchedulePolicy,
        plateau: &PlateauConfig,
    ) -> BatchPlan {
        let plain: Vec<FieldFacts> = facts.iter().map(|(_, f)| *f).collect();
        let plan = self.plan(&plain, policy, plateau);
        let mut planned: Vec<(usize, FieldKey)> = facts
            .iter()
            .filter(|(_, f)| plan.binary_search(&f.key).is_ok())
            .map(|(index, f)| (*index, f.key))
            .collect();
        planned.sort_unstable();
        BatchPlan {
            indices: planned.iter().map(|(index, _)| *index).collect(),
            keys: planned.iter().map(|(_, key)| *key).collect(),
            learning_rate_scales: planned
                .iter()
                .map(|(_, key)| self.learning_rate_scale(*key, plateau))
                .collect(),
        }
    }

    /// Records that `key` took one step with total loss `loss`.
    pub fn record(&mut self, key: FieldKey, loss: f32, plateau: &PlateauConfig) {
        let progress = self.fields.entry(key).or_default();
        progress.steps += 1;
        progress.record(loss, plateau);
    }

    /// Records one batched step: field `keys[i]` took it with total loss `losses[i]`.
    pub fn record_step(&mut self, keys: &[FieldKey], losses: &[f32], plateau: &PlateauConfig) {
        for (&key, &loss) in keys.iter().zip(losses) {
            self.record(key, loss, plateau);
        }
    }

    /// The factor of `key`'s learning rate for its next steps (1 until its loss plateaus after
    /// the stream; see [`PlateauConfig::learning_rate_decays`]).
    pub fn learning_rate_scale(&self, key: FieldKey, plateau: &PlateauConfig) -> f32 {
        self.fields
            .get(&key)
            .map_or(1.0, |progress| plateau.learning_rate_scale(progress.decays))
    }

    /// Every field's progress, in key order.
    pub fn progress(&self) -> &BTreeMap<FieldKey, FieldProgress> {
        &self.fields
    }

    /// Forgets a field that no longer exists.
    pub fn forget(&mut self, key: FieldKey) {
        self.fields.remove(&key);
    }
}

#[cfg(test)]
#[path = "scheduler_tests.rs"]
mod tests;
