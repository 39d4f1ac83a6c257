//! A training step that failed: the run stops at the tick it failed in, with one error that names
//! the step and its objects ([`crate::MapperError::StepFailed`]), instead of warning at every
//! later step. A step fails only on a broken invariant (a shape mismatch, a field without its
//! owner), never on what the frames hold, so carrying on would train on a corrupt state.

use bevy_ecs::prelude::*;
use catmap::training::FieldKey;
use catmap::{CatmapError, ObjectId};

/// Which batched step failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrainingStep {
    /// The object fields' batch.
    ObjectFields,
    /// The background field.
    Background,
    /// The category fields' batch.
    CategoryFields,
}

impl std::fmt::Display for TrainingStep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::ObjectFields => "object-field training step",
            Self::Background => "background training step",
            Self::CategoryFields => "category-field training step",
        })
    }
}

/// A step's error and the fields it concerns: every field the step trained, or the one at fault
/// when the error could be traced to it.
#[derive(Debug)]
pub struct StepError {
    /// The fields.
    pub fields: Vec<FieldKey>,
    /// What went wrong.
    pub error: CatmapError,
}

/// A failed step: which, how many steps of its kind ran before it, and its error.
#[derive(Debug)]
pub struct StepFailure {
    /// The step.
    pub step: TrainingStep,
    /// Steps of that kind run before it.
    pub steps_before: u64,
    /// The error and its fields.
    pub error: StepError,
}

impl StepFailure {
    /// The objects whose fields the failure concerns.
    pub fn objects(&self) -> Vec<ObjectId> {
        self.error
            .fields
            .iter()
            .filter_map(|key| match key {
                FieldKey::Object(id) => Some(*id),
                FieldKey::Category(_) | FieldKey::Background => None,
            })
            .collect()
    }
}

impl std::fmt::Display for StepFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let fields: Vec<String> = self
            .error
            .fields
            .iter()
            .map(|key| match key {
                FieldKey::Object(id) => format!("object {id}"),
                FieldKey::Category(n) => format!("category field {n}"),
                FieldKey::Background => "the background".to_owned(),
            })
            .collect();
        write!(
            f,
            "{} {} ({}) failed: {}",
            self.step,
            self.steps_before + 1,
            fields.join(", "),
            self.error.error
        )
    }
}

/// The first step that failed, for the mapper to return; the systems that train run no more
/// steps once it is set.
#[derive(Resource, Debug, Default)]
pub struct FailedStep(pub Option<StepFailure>);

impl FailedStep {
    /// Records the failure of `step` (after `steps_before` of its kind) unless an earlier one is
    /// recorded.
    pub fn record(&mut self, step: TrainingStep, steps_before: u64, error: StepError) {
        if self.0.is_none() {
            self.0 = Some(StepFailure {
                step,
                steps_before,
                error,
            });
        }
    }

    /// Whether a step has failed.
    pub fn is_set(&self) -> bool {
        self.0.is_some()
    }
}
