//! Sweeps: a spec of synthetic scenes × sensor noise × modes × schedules × mapper seeds
//! ([`spec`]), the commands and files that hand its jobs to an existing engine ([`engines`]),
//! and the Markdown tables of their outputs ([`tables`]; `catmap report`).

pub mod engines;
pub mod spec;
pub mod tables;

pub use spec::{SweepJob, SweepManifest, SweepSpec};
