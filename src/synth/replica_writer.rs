//! Writes a synthetic scene in the Replica vMAP layout (METHOD.md §1), plus its ground truth:
//!
//! ```text
//! rgb/rgb_{i}.png                              8-bit RGB
//! depth/depth_{i}.png                          16-bit grey, millimetres, 0 = invalid
//! semantic_class/semantic_class_{i}.png        8-bit grey class id
//! semantic_instance/semantic_instance_{i}.png  16-bit grey instance id, 0 = none
//! traj_w_c.txt                                 per frame: 16 floats, row-major camera-to-world
//! intrinsics.json                              width, height, fx, fy, cx, cy, depth_scale
//! scene.json                                   seed, preset, objects (see SceneDescription)
//! gt_meshes/obj_{id}.ply                       binary PLY in world coordinates
//! ```
//!
//! Frames render in parallel; every file is written to `*.tmp` and renamed into place
//! ([`crate::atomic_file`]).

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

use image::codecs::png::{CompressionType, FilterType, PngEncoder};
use image::{ExtendedColorType, ImageEncoder};
use rayon::prelude::*;
use serde::Serialize;

use super::description::{SceneDescription, row_major};
use super::render::RenderedFrame;
use super::scene::SyntheticScene;
use crate::atomic_file::{write_atomic, write_atomic_with};
use crate::dataset::FrameSource;
use crate::error::{CatmapError, Result};

/// Depth PNG units per metre.
pub const DEPTH_SCALE: f32 = 1000.0;

/// Contents of `intrinsics.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
struct IntrinsicsFile {
    width: u32,
    height: u32,
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    depth_scale: f32,
}

/// Writes `scene` into `dir` (created if missing). `progress(done, total)` is called from worker
/// threads after each frame. Errors name the file that failed.
pub fn write_replica_layout(scene: &SyntheticScene, dir: &Path, progress: impl Fn(usize, usize) + Sync) -> Result<()> {
    write_all_frames(
        scene,
        dir,
        &["rgb", "depth", "semantic_class", "semantic_instance", "gt_meshes"],
        progress,
        |i, frame| write_frame(dir, i, frame),
    )?;
    let trajectory: String = scene
        .trajectory()
        .iter()
        .map(|pose| {
            let values: Vec<String> = row_major(pose).iter().flatten().map(f32::to_string).collect();
            values.join(" ") + "\n"
        })
        .collect();
    write_atomic(&dir.join("traj_w_c.txt"), trajectory.as_bytes())?;
    let k = scene.intrinsics();
    let intrinsics = IntrinsicsFile {
        width: k.width,
        height: k.height,
        fx: k.fx,
        fy: k.fy,
        cx: k.cx,
        cy: k.cy,
        depth_scale: DEPTH_SCALE,
    };
    write_json(&dir.join("intrinsics.json"), &intrinsics)?;
    write_ground_truth(scene, dir)
}

/// Creates the `folders` of a layout in `dir`, then renders every frame of `scene` (in parallel)
/// and hands it to `write_frame`; `progress(done, total)` is called after each frame.
pub(crate) fn write_all_frames(
    scene: &SyntheticScene,
    dir: &Path,
    folders: &[&str],
    progress: impl Fn(usize, usize) + Sync,
    write_frame: impl Fn(usize, &RenderedFrame) -> Result<()> + Sync,
) -> Result<()> {
    for sub in folders {
        let path = dir.join(sub);
        std::fs::create_dir_all(&path).map_err(|e| CatmapError::io(path, e))?;
    }
    let total = scene.len();
    let done = AtomicUsize::new(0);
    (0..total).into_par_iter().try_for_each(|i| {
        write_frame(i, &scene.render(i)?)?;
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
        Ok::<_, CatmapError>(())
    })
}

/// Writes `scene.json` (the objects) and `gt_meshes/obj_{id}.ply` into `dir`, as both layouts have
/// them.
pub(crate) fn write_ground_truth(scene: &SyntheticScene, dir: &Path) -> Result<()> {
    write_json(&dir.join("scene.json"), &SceneDescription::of(scene))?;
    for object in scene.objects() {
        object
            .surface_in_world
            .write_ply(&dir.join("gt_meshes").join(format!("obj_{}.ply", object.id)))?;
    }
    Ok(())
}

/// Writes the four images of frame `i` in the Replica layout.
fn write_frame(dir: &Path, i: usize, frame: &RenderedFrame) -> Result<()> {
    let paths = FrameImages {
        rgb: dir.join(format!("rgb/rgb_{i}.png")),
        depth: dir.join(format!("depth/depth_{i}.png")),
        class: dir.join(format!("semantic_class/semantic_class_{i}.png")),
        instance: dir.join(format!("semantic_instance/semantic_instance_{i}.png")),
    };
    write_frame_images(frame, &paths, DEPTH_SCALE)
}

/// Where a layout keeps one frame's four images.
pub(crate) struct FrameImages {
    pub rgb: std::path::PathBuf,
    pub depth: std::path::PathBuf,
    pub class: std::path::PathBuf,
    pub instance: std::path::PathBuf,
}

/// Writes `frame`'s colour (RGB8), depth (uint16, `depth_units_per_m`), class (8-bit) and
/// instance (16-bit) images to `paths`.
pub(crate) fn write_frame_images(frame: &RenderedFrame, paths: &FrameImages, depth_units_per_m: f32) -> Result<()> {
    let (w, h) = (frame.intrinsics.width, frame.intrinsics.height);
    let rgb: Vec<u8> = frame.rgb.iter().flatten().copied().collect();
    write_png(&paths.rgb, w, h, &rgb, ExtendedColorType::Rgb8)?;
    let depth: Vec<u8> = frame
        .depth_m
        .iter()
        .flat_map(|&d| depth_to_units(d, depth_units_per_m).to_ne_bytes())
        .collect();
    write_png(&paths.depth, w, h, &depth, ExtendedColorType::L16)?;
    let classes: Vec<u8> = frame.classes.iter().map(|c| u8::try_from(c.0).unwrap_or(0)).collect();
    write_png(&paths.class, w, h, &classes, ExtendedColorType::L8)?;
    let instances: Vec<u8> = frame.instance_ids.iter().flat_map(|id| id.to_ne_bytes()).collect();
    write_png(&paths.instance, w, h, &instances, ExtendedColorType::L16)
}

/// Depth in metres → `units_per_m` units (millimetres at 1000); invalid or unrepresentable depths
/// become 0.
pub(crate) fn depth_to_units(depth_m: f32, units_per_m: f32) -> u16 {
    let units = (depth_m * units_per_m).round();
    if units > 0.0 && units <= f32::from(u16::MAX) {
        units as u16
    } else {
        0
    }
}

/// Encodes `bytes` (native-endian samples) as PNG into `path`.
pub(super) fn write_png(path: &Path, width: u32, height: u32, bytes: &[u8], color: ExtendedColorType) -> Result<()> {
    write_atomic_with(path, |w| {
        PngEncoder::new_with_quality(w, CompressionType::Fast, FilterType::Sub)
            .write_image(bytes, width, height, color)
            .map_err(std::io::Error::other)
    })
}

/// Pretty-printed JSON into `path`.
pub(super) fn write_json(path: &Path, value: &impl Serialize) -> Result<()> {
    let mut text = serde_json::to_string_pretty(value).map_err(|e| CatmapError::layout(path, e.to_string()))?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_is_rounded_to_millimetres_and_clamped_to_invalid() {
        assert_eq!(depth_to_units(1.2344, DEPTH_SCALE), 1234);
        assert_eq!(depth_to_units(0.0, DEPTH_SCALE), 0);
        assert_eq!(depth_to_units(f32::NAN, DEPTH_SCALE), 0);
        assert_eq!(
            depth_to_units(70.0, DEPTH_SCALE),
            0,
            "beyond 65.535 m is not representable"
        );
    }
}
