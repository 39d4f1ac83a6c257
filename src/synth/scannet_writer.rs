//! Writes a synthetic scene in ScanNet's layout (the one [`crate::dataset::scannet`] reads, as
//! SensReader and the 2D labels lay it out), plus its ground truth:
//!
//! ```text
//! color/{n}.jpg                       colour, JPEG
//! depth/{n}.png                       16-bit grey, millimetres, 0 = invalid
//! pose/{n}.txt                        4 lines × 4 numbers: world_from_camera
//! intrinsic/intrinsic_depth.txt       4×4: fx, fy, cx, cy as ScanNet writes them
//! instance-filt/{n}.png               8-bit grey instance id (the object's id), 0 = none
//! label-filt/{n}.png                  8-bit grey raw label id (the object's Replica class), 0 = none
//! scannetv2-labels.combined.tsv       the label map: `id`, `raw_category`, `category` per class
//! scene.json, gt_meshes/              as the Replica writer's
//! ```
//!
//! Floor, walls and empty pixels are written as instance 0 with label 0 (unannotated), which the
//! reader takes as background. The reader shifts instance ids by one (ScanNet's instance 0 is a
//! real instance), so object `k` of `scene.json` is object `k + 1` of a run; the evaluation pairs
//! objects by geometry. The reader crops a border of `border_px` pixels, as it does ScanNet's.

use std::path::Path;

use image::ExtendedColorType;
use image::codecs::jpeg::JpegEncoder;

use super::description::row_major;
use super::render::RenderedFrame;
use super::replica_writer::{DEPTH_SCALE, depth_to_units, write_all_frames, write_ground_truth, write_png};
use super::scene::SyntheticScene;
use crate::atomic_file::{write_atomic, write_atomic_with};
use crate::dataset::FrameSource;
use crate::dataset::class_names::{SCANNET_LABEL_MAP, replica_class_name};
use crate::dataset::classes::is_replica_background;
use crate::error::Result;

/// JPEG quality of the colour images (SensReader's exports are JPEG).
const JPEG_QUALITY: u8 = 95;

/// Writes `scene` into `dir` (created if missing) in ScanNet's layout. `progress(done, total)` is
/// called from worker threads after each frame. Errors name the file that failed.
pub fn write_scannet_layout(scene: &SyntheticScene, dir: &Path, progress: impl Fn(usize, usize) + Sync) -> Result<()> {
    write_all_frames(
        scene,
        dir,
        &[
            "color",
            "depth",
            "pose",
            "intrinsic",
            "instance-filt",
            "label-filt",
            "gt_meshes",
        ],
        progress,
        |i, frame| write_frame(dir, i, frame),
    )?;
    let k = scene.intrinsics();
    let intrinsic = format!("{} 0 {} 0\n0 {} {} 0\n0 0 1 0\n0 0 0 1\n", k.fx, k.cx, k.fy, k.cy);
    write_atomic(&dir.join("intrinsic/intrinsic_depth.txt"), intrinsic.as_bytes())?;
    write_atomic(&dir.join(SCANNET_LABEL_MAP), label_map(scene).as_bytes())?;
    write_ground_truth(scene, dir)
}

/// The label map: one row per object class of the scene, its Replica id as the raw label id.
fn label_map(scene: &SyntheticScene) -> String {
    let mut classes: Vec<_> = scene.objects().iter().map(super::scene::SceneObject::class).collect();
    classes.sort_unstable();
    classes.dedup();
    let rows: String = classes
        .into_iter()
        .map(|class| {
            let name = replica_class_name(class).unwrap_or("object");
            format!("{}\t{name}\t{name}\n", class.0)
        })
        .collect();
    format!("id\traw_category\tcategory\n{rows}")
}

/// Writes frame `i`'s colour, depth, pose and label images.
fn write_frame(dir: &Path, i: usize, frame: &RenderedFrame) -> Result<()> {
    let (w, h) = (frame.intrinsics.width, frame.intrinsics.height);
    let rgb: Vec<u8> = frame.rgb.iter().flatten().copied().collect();
    write_atomic_with(&dir.join(format!("color/{i}.jpg")), |out| {
        JpegEncoder::new_with_quality(out, JPEG_QUALITY)
            .encode(&rgb, w, h, ExtendedColorType::Rgb8)
            .map_err(std::io::Error::other)
    })?;
    let depth: Vec<u8> = (frame.depth_m.iter())
        .flat_map(|&d| depth_to_units(d, DEPTH_SCALE).to_ne_bytes())
        .collect();
    write_png(
        &dir.join(format!("depth/{i}.png")),
        w,
        h,
        &depth,
        ExtendedColorType::L16,
    )?;
    let pose: String = (row_major(&frame.world_from_camera).iter())
        .map(|row| row.map(|x| x.to_string()).join(" ") + "\n")
        .collect();
    write_atomic(&dir.join(format!("pose/{i}.txt")), pose.as_bytes())?;
    let object_at = |p: usize| {
        let (id, class) = (frame.instance_ids[p], frame.classes[p]);
        (id != 0 && !is_replica_background(class)).then_some((id, class))
    };
    let instances: Vec<u8> = (0..frame.instance_ids.len())
        .map(|p| object_at(p).map_or(0, |(id, _)| u8::try_from(id).unwrap_or(0)))
        .collect();
    write_png(
        &dir.join(format!("instance-filt/{i}.png")),
        w,
        h,
        &instances,
        ExtendedColorType::L8,
    )?;
    let labels: Vec<u8> = (0..frame.classes.len())
        .map(|p| object_at(p).map_or(0, |(_, class)| u8::try_from(class.0).unwrap_or(0)))
        .collect();
    write_png(
        &dir.join(format!("label-filt/{i}.png")),
        w,
        h,
        &labels,
        ExtendedColorType::L8,
    )
}
