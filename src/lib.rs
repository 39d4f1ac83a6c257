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

// Sweeps of runs (`catmap sweep`, `catmap report`).
pub mod sweep;

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

#[cfg(test)]
mod tests {
    /// docs/ARCHITECTURE.md names every top-level module of `src/` (as `src/name/` or `name`).
    #[test]
    fn the_architecture_page_names_every_top_level_module() {
        let page = include_str!("../docs/ARCHITECTURE.md");
        let modules: Vec<&str> = include_str!("lib.rs")
            .lines()
            .filter_map(|line| line.strip_prefix("pub mod ")?.strip_suffix(';'))
            .collect();
        assert!(modules.len() > 10, "lib.rs lists its modules: {modules:?}");
        let missing: Vec<&&str> = modules
            .iter()
            .filter(|m| {
                !page.contains(&format!("src/{m}/"))
                    && !page.contains(&format!(" {m} "))
                    && !page.contains(&format!(" {m}\n"))
            })
            .collect();
        assert!(missing.is_empty(), "docs/ARCHITECTURE.md does not name {missing:?}");
    }
}
