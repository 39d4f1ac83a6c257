//! Which fields train, and when (issue 17): the [`StepScheduler`] gives the steps of each tick
//! to the fields that gain from them and none to those that have converged or been replaced by
//! a category field; [`LossWindow`] tells when a loss has stopped falling.

pub mod config;
pub mod facts;
pub mod field_progress;
pub mod live_clock;
pub mod phase_end;
pub mod plateau;
pub mod run_phase;
pub mod scheduler;

pub use config::ScheduleConfig;
pub use facts::{
    ClassShare, ClassSizes, FieldFacts, FieldKey, FieldRole, LastSeen, MeshSource, Sighting, StreamPhase,
    category_field_facts, class_sizes, object_field_facts, takes_shape_priors,
};
pub use field_progress::{FieldProgress, FieldState};
pub use live_clock::{LiveClock, TickKind};
pub use phase_end::PhaseEnd;
pub use plateau::{LossWindow, PlateauConfig};
pub use run_phase::{CHUNK_STEPS, FinishClock, PhasePlan, RunPhase, TickBudget, TickSteps};
pub use scheduler::{BatchPlan, SchedulePolicy, StepScheduler};
