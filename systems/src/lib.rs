//! The catmap streaming mapper: frames, objects and categories as `bevy_ecs` entities, fed by a
//! dataset stream, logged live to Rerun.
//!
//! Systems are thin: they read components, call a `catmap::` function and write components.
//! [`schedule::build_schedule`] is the only place that orders them; [`mapper::Mapper`] is the facade.

pub mod categories_report;
pub mod categorize;
pub mod category_fields;
mod checkpoint;
pub mod cleanup;
pub mod clouds;
pub mod components;
pub mod ingest;
pub mod log_categories;
pub mod log_rerun;
pub mod mapper;
pub mod meshes;
pub mod register;
pub mod resources;
pub mod rrd_file;
pub mod schedule;
pub mod segment;
pub mod snapshot;
pub mod track;
pub mod train;

pub use mapper::{Mapper, MapperError};
pub use snapshot::MapSnapshot;
pub mod summary;
