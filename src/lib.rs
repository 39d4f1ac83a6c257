//! catmap: object-level RGB-D mapping with category-level neural fields.
//!
//! This crate holds data types and pure algorithms; the streaming mapper that wires them into
//! `bevy_ecs` systems lives in `catmap-systems`. The modules follow the method (docs/METHOD.md)
//! from the sensor to the scores.

// Input: posed RGB-D frames with instance masks, from a dataset or the synthetic generator.
pub mod dataset;
pub mod sensor;
pub mod synth;

// §1 Objects: what each frame says about an object, its keyframes, cloud and box.
pub mod objects;

// §2 Per-object occupancy fields, trained as one batched model, and which get steps.
pub mod field;
pub mod training;

// §3–§5 Categories: uncertainty and representatives, registration and subcategories, NOCS.
pub mod categories;
pub mod registration;

// §6 Meshes and the paper's metrics.
pub mod meshing;
pub mod metrics;

// Shared by every layer.
pub mod checkpoint;
pub mod config;
pub mod error;
pub mod geometry;
pub mod ids;
pub mod rng;

// Process and file helpers.
pub mod atomic_file;
pub mod process_memory;

pub use config::MapperConfig;
pub use error::{CatmapError, Result};
pub use ids::{ClassId, FrameIndex, ObjectId};
pub use sensor::frame::{CameraIntrinsics, InstanceLabel, InstanceMask, RgbdFrame, SharedFrame};
