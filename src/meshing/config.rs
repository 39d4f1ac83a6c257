//! Configuration of mesh extraction: final object meshes, online previews, the background.

use serde::{Deserialize, Serialize};

use super::ObjectMeshConfig;

/// When and how finely meshes are extracted.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MeshConfig {
    /// Final object meshes (METHOD.md §6: 5 mm, ≤ 256 samples per side, box fills 90 %).
    pub object: ObjectMeshConfig,
    /// Online preview meshes are extracted every this many frames (0 = only at the end).
    pub preview_every_frames: u64,
    /// Sample spacing of preview meshes, metres.
    pub preview_voxel_m: f32,
    /// Sample spacing of the background mesh, metres (over the background cloud's bounds).
    pub background_voxel_m: f32,
}

impl Default for MeshConfig {
    fn default() -> Self {
        Self {
            object: ObjectMeshConfig::default(),
            preview_every_frames: 60,
            preview_voxel_m: 0.02,
            background_voxel_m: 0.04,
        }
    }
}

impl MeshConfig {
    /// The object settings with the preview spacing.
    pub fn preview(&self) -> ObjectMeshConfig {
        // Dense: at 2 cm a coarse block would span 8 cm, wider than a chair's legs.
        ObjectMeshConfig {
            voxel_size_m: self.preview_voxel_m,
            coarse_block: 1,
            ..self.object.clone()
        }
    }

    /// The settings of the background mesh (its grid spans the background cloud's bounds; a
    /// piece of wall apart from the rest is no fragment).
    pub fn background(&self) -> ObjectMeshConfig {
        ObjectMeshConfig {
            voxel_size_m: self.background_voxel_m,
            box_fill: 1.0,
            coarse_block: 1,
            min_fragment_share: 0.0,
            ..self.object.clone()
        }
    }
}
