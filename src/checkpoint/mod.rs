//! Checkpoints: a verified, atomically replaced snapshot of the mapper's state on disk.
//!
//! The pure part lives here: named tensors as safetensors ([`TensorStore`]), fields in and out
//! of tensors ([`store_occupancy_field`], [`store_category_field`]), and the checkpoint folder
//! with its manifest, generations and CRC-32 checks ([`write_checkpoint`], [`read_checkpoint`]).
//! What the state holds is decided by the streaming mapper (`catmap-systems`).

mod config;
mod fields;
mod files;
mod tensor_store;

pub use config::{CheckpointConfig, RunCount};
pub use fields::{
    CategoryFieldHeader, OccupancyFieldHeader, load_category_field, load_occupancy_field, store_category_field,
    store_occupancy_field,
};
pub use files::{
    CheckpointFile, CheckpointManifest, FORMAT, LoadedCheckpoint, MANIFEST, read_checkpoint, read_manifest,
    verify_checkpoint, write_checkpoint,
};
pub use tensor_store::TensorStore;
