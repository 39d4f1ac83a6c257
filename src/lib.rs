//! catmap: object-level RGB-D mapping with category-level neural fields.
//!
//! This crate holds data types and pure algorithms (geometry, readers, synthetic scenes); the
//! streaming mapper that wires them into `bevy_ecs` systems lives in `catmap-systems`.

pub mod classes;
pub mod config;
pub mod dataset;
pub mod error;
pub mod frame;
pub mod ids;

pub use config::MapperConfig;
pub use error::{CatmapError, Result};
pub use frame::{CameraIntrinsics, InstanceLabel, InstanceMask, RgbdFrame, SharedFrame};
pub use ids::{ClassId, FrameIndex, ObjectId};
pub mod atomic_file;
pub mod category;
pub mod category_field_plan;
pub mod checkpoint;
pub mod class_registration;
pub mod field;
pub mod frame_observation;
pub mod image_ops;
pub mod keyframes;
pub mod mesh;
pub mod meshing;
pub mod metrics;
pub mod nearest;
pub mod nocs;
pub mod object_bounds;
pub mod object_view;
pub mod observed_cloud;
pub mod oriented_box;
pub mod pixel_box;
pub mod process_memory;
pub mod registration;
pub mod rng;
pub mod stream;
pub mod synth;
pub mod training;
pub mod uncertainty;
