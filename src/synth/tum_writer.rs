//! Writes a synthetic scene in TUM RGB-D's layout with a segmenter's masks beside it (the layout
//! [`crate::dataset::tum`] reads), plus its ground truth:
//!
//! ```text
//! rgb.txt, depth.txt           `# ` header lines, then `timestamp path` per frame
//! groundtruth.txt              `timestamp tx ty tz qx qy qz qw` per frame: world_from_camera
//! rgb/{t}.png                  8-bit RGB, t = the colour image's timestamp with 6 decimals
//! depth/{d}.png                16-bit grey, 5000 units per metre (TUM's), 0 = invalid
//! instance/{t}.png             16-bit grey instance id, 0 = none
//! class/{t}.png                8-bit grey class id (Replica's)
//! intrinsics.json              width, height, fx, fy, cx, cy, depth_scale (5000)
//! scene.json, gt_meshes/       as the Replica writer's
//! ```
//!
//! Frame `i`'s colour image is taken at [`START_S`] + i / 30 s, its depth image
//! [`DEPTH_DELAY_S`] later and its pose stamped [`POSE_LEAD_S`] earlier: like TUM's streams, the
//! three are not simultaneous, and a reader has to associate them by nearest timestamp.

use std::path::Path;

use super::render::RenderedFrame;
use super::replica_writer::{FrameImages, write_all_frames, write_frame_images, write_ground_truth, write_json};
use super::scene::SyntheticScene;
use crate::atomic_file::write_atomic;
use crate::dataset::FrameSource;
use crate::dataset::tum::TUM_DEPTH_SCALE;
use crate::error::Result;

/// Timestamp of the first colour image, seconds (a Unix time, as TUM's are).
pub const START_S: f64 = 1_700_000_000.0;
/// Frames per second.
pub const FRAME_RATE_HZ: f64 = 30.0;
/// How much later than its colour image a frame's depth image is stamped, seconds.
pub const DEPTH_DELAY_S: f64 = 0.004;
/// How much earlier than its colour image a frame's pose is stamped, seconds.
pub const POSE_LEAD_S: f64 = 0.002;

/// Timestamp of frame `i`'s colour image, as written (6 decimals).
pub fn rgb_timestamp(i: usize) -> String {
    format!("{:.6}", START_S + i as f64 / FRAME_RATE_HZ)
}

fn depth_timestamp(i: usize) -> String {
    format!("{:.6}", START_S + i as f64 / FRAME_RATE_HZ + DEPTH_DELAY_S)
}

fn pose_timestamp(i: usize) -> String {
    format!("{:.6}", START_S + i as f64 / FRAME_RATE_HZ - POSE_LEAD_S)
}

/// Writes `scene` into `dir` (created if missing) in TUM's layout. `progress(done, total)` is
/// called from worker threads after each frame. Errors name the file that failed.
pub fn write_tum_layout(scene: &SyntheticScene, dir: &Path, progress: impl Fn(usize, usize) + Sync) -> Result<()> {
    write_all_frames(
        scene,
        dir,
        &["rgb", "depth", "instance", "class", "gt_meshes"],
        progress,
        |i, frame| write_frame(dir, i, frame),
    )?;
    let total = scene.len();
    // The header lines of TUM's own files.
    let list = |title: &str, folder: &str, stamp: fn(usize) -> String| {
        let header = format!("# {title}\n# file: 'catmap synth'\n# timestamp filename\n");
        let lines: String = (0..total)
            .map(|i| format!("{} {folder}/{}.png\n", stamp(i), stamp(i)))
            .collect();
        header + &lines
    };
    write_atomic(
        &dir.join("rgb.txt"),
        list("color images", "rgb", rgb_timestamp).as_bytes(),
    )?;
    write_atomic(
        &dir.join("depth.txt"),
        list("depth maps", "depth", depth_timestamp).as_bytes(),
    )?;
    let poses: String = scene
        .trajectory()
        .iter()
        .enumerate()
        .map(|(i, pose)| {
            let (t, q) = (pose.translation.vector, pose.rotation);
            let (x, y, z, w) = (q.i, q.j, q.k, q.w);
            format!("{} {} {} {} {x} {y} {z} {w}\n", pose_timestamp(i), t.x, t.y, t.z)
        })
        .collect();
    let header = "# ground truth trajectory\n# file: 'catmap synth'\n# timestamp tx ty tz qx qy qz qw\n";
    write_atomic(&dir.join("groundtruth.txt"), (header.to_owned() + &poses).as_bytes())?;
    let k = scene.intrinsics();
    let intrinsics = serde_json::json!({
        "width": k.width, "height": k.height, "fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy,
        "depth_scale": TUM_DEPTH_SCALE,
    });
    write_json(&dir.join("intrinsics.json"), &intrinsics)?;
    write_ground_truth(scene, dir)
}

/// Writes the four images of frame `i` in the TUM layout.
fn write_frame(dir: &Path, i: usize, frame: &RenderedFrame) -> Result<()> {
    let (stamp, depth_stamp) = (rgb_timestamp(i), depth_timestamp(i));
    let paths = FrameImages {
        rgb: dir.join(format!("rgb/{stamp}.png")),
        depth: dir.join(format!("depth/{depth_stamp}.png")),
        class: dir.join(format!("class/{stamp}.png")),
        instance: dir.join(format!("instance/{stamp}.png")),
    };
    write_frame_images(frame, &paths, TUM_DEPTH_SCALE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::replica_writer::depth_to_units;

    #[test]
    fn depth_is_written_in_fifths_of_a_millimetre_and_clamped_to_invalid() {
        assert_eq!(depth_to_units(1.2344, TUM_DEPTH_SCALE), 6172);
        assert_eq!(depth_to_units(0.0, TUM_DEPTH_SCALE), 0);
        assert_eq!(depth_to_units(f32::NAN, TUM_DEPTH_SCALE), 0);
        assert_eq!(
            depth_to_units(13.2, TUM_DEPTH_SCALE),
            0,
            "beyond 13.107 m is not representable"
        );
    }

    #[test]
    fn timestamps_are_30_hz_with_depth_after_and_pose_before_the_colour_image() {
        assert_eq!(rgb_timestamp(0), "1700000000.000000");
        assert_eq!(rgb_timestamp(3), "1700000000.100000");
        assert_eq!(depth_timestamp(3), "1700000000.104000");
        assert_eq!(pose_timestamp(3), "1700000000.098000");
    }
}
