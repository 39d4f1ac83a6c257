//! [`RerunConfig`]: what the live Rerun log shows, and how often.

use serde::{Deserialize, Serialize};

/// Rerun logging.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RerunConfig {
    /// Images are logged at 1/`image_downscale` of their size (1 = full size).
    pub image_downscale: u32,
    /// Log the colour and instance images every this many frames (points and boxes are logged
    /// every frame).
    pub image_every: u32,
    /// Log the depth image every this many frames: raw 16-bit depth is the largest thing a
    /// recording holds per frame (≈ 46 KiB compressed at 320 × 240), so it is thinned.
    pub depth_every: u32,
    /// JPEG quality of logged colour images, 1–100.
    pub jpeg_quality: u8,
    /// At most this many points per object cloud are logged (evenly thinned).
    pub max_points_per_object: usize,
    /// An object's cloud is logged again once it has grown by this fraction (0.25 = 25 %).
    pub cloud_log_growth: f32,
    /// The final meshes are logged with their vertices merged on a grid of this many metres
    /// (vertex clustering: about a fifth of a 5 mm mesh's triangles at 0.01), which keeps a
    /// recording compact; the written .ply files keep every triangle (0 = log them whole).
    pub final_mesh_cell_m: f32,
    /// A saved .rrd ends with Rerun's chunk index (its footer) only for streams of at most this
    /// many frames: the index is held in memory until the file closes (≈ 15 MiB per 1 000 frames),
    /// so longer streams are saved without it to keep memory flat (0 = never write it).
    pub rrd_footer_max_frames: u64,
}

impl Default for RerunConfig {
    fn default() -> Self {
        Self {
            image_downscale: 2,
            image_every: 1,
            depth_every: 2,
            jpeg_quality: 80,
            max_points_per_object: 8_000,
            cloud_log_growth: 0.25,
            final_mesh_cell_m: 0.01,
            rrd_footer_max_frames: 2_000,
        }
    }
}
