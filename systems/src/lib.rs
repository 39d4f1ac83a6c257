//! The catmap streaming mapper: frames, objects and categories as `bevy_ecs` entities, fed by a
//! dataset stream, logged live to Rerun.
//!
//! Systems are thin: they read components, call a `catmap::` function and write components.
//! [`schedule::build_schedule`] is the only place that orders them; [`mapper::Mapper`] is the facade.

// The ECS data, the stages, and the one schedule that orders them.
pub mod components;
pub mod failed_step;
pub mod resources;
pub mod run_state;
pub mod schedule;
pub mod stages;

// The facade, and the map as it is read out and saved.
pub mod categories_report;
mod checkpoint;
pub mod mapper;
pub mod snapshot;
pub mod summary;
pub mod training_report;

// Rerun: the entity paths logged to, the viewer layout, and recording files.
pub mod blueprint;
pub mod recording;
pub mod rerun_paths;
pub mod rrd_file;

pub use checkpoint::SavedMapper;
pub use mapper::{Mapper, MapperError, RunOutcome, RunPhase, RunProgress};
pub use snapshot::MapSnapshot;
