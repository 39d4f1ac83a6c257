//! Replica sequences in vMAP's layout (METHOD.md §1):
//!
//! ```text
//! <dir>/rgb/rgb_{i}.png                              8-bit RGB (RGBA: alpha dropped)
//! <dir>/depth/depth_{i}.png                          uint16, value / depth_scale = metres, 0 invalid
//! <dir>/semantic_class/semantic_class_{i}.png        class id per pixel (8 or 16 bit)
//! <dir>/semantic_instance/semantic_instance_{i}.png  instance id per pixel, 0 = none
//! <dir>/traj_w_c.txt                                 line i+1: row-major 4×4 world_from_camera of frame i
//! <dir>/intrinsics.json                              optional: width, height, fx, fy, cx, cy
//! ```
//!
//! The frames are the `depth_{i}.png` files, sorted by `i` (no zero padding; `i` starts at 0). Poses
//! are parsed once, at [`ReplicaSequence::open`]; images are decoded per frame, the four in parallel.
//! Pixels of a background class ([`REPLICA_BACKGROUND`]) and pixels of instance 0 are background.

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use crate::dataset::FrameSource;
use crate::dataset::camera_spec::{
    intrinsics_problem, parse_numbers, read_intrinsics_json, world_from_camera_from_rows,
};
use crate::dataset::class_names::ClassNames;
use crate::dataset::classes::REPLICA_BACKGROUND;
use crate::dataset::config::DatasetConfig;
use crate::dataset::images::{
    Image, check_depth_options, depth_to_metres_in_place, numbered_files, read_grey, read_grey_as, read_rgb,
    require_size, size_text,
};
use crate::error::{CatmapError, Result};
use crate::ids::{ClassId, FrameIndex, ObjectId};
use crate::sensor::frame::{CameraIntrinsics, InstanceLabel, InstanceMask, RgbdFrame};

/// How to read a Replica sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplicaOptions {
    /// Intrinsics given on the command line; they win over `intrinsics.json` and the Replica default.
    pub camera: Option<CameraIntrinsics>,
    /// Raw depth units per metre (Replica: millimetres, 1000).
    pub depth_scale: f32,
    /// Depth beyond this is invalid, metres.
    pub max_depth_m: f32,
}

impl Default for ReplicaOptions {
    fn default() -> Self {
        Self::from_config(&DatasetConfig::default())
    }
}

impl ReplicaOptions {
    /// Options with the depth conversion of `config` and no camera override.
    pub fn from_config(config: &DatasetConfig) -> Self {
        Self {
            camera: None,
            depth_scale: config.depth_scale,
            max_depth_m: config.max_depth_m,
        }
    }
}

/// One frame of the sequence: its file index `i` and pose.
#[derive(Debug, Clone)]
struct ReplicaFrame {
    index: u64,
    world_from_camera: Isometry3<f32>,
}

/// A Replica sequence folder (vMAP layout) opened for random access.
#[derive(Debug, Clone)]
pub struct ReplicaSequence {
    dir: PathBuf,
    intrinsics: CameraIntrinsics,
    frames: Vec<ReplicaFrame>,
    depth_scale: f32,
    max_depth_m: f32,
    class_names: ClassNames,
}

/// Bit `c` is set for every Replica background class `c` (all are below 128).
const BACKGROUND_BITS: u128 = {
    let mut bits = 0u128;
    let mut k = 0;
    while k < REPLICA_BACKGROUND.len() {
        assert!(REPLICA_BACKGROUND[k] < 128, "background class ids fit the bit set");
        bits |= 1 << REPLICA_BACKGROUND[k];
        k += 1;
    }
    bits
};

fn is_background_class(class: u32) -> bool {
    class < 128 && (BACKGROUND_BITS >> class) & 1 == 1
}

/// The instance label of one pixel: background classes and instance 0 are background.
pub fn replica_label(class: u32, instance: u32) -> InstanceLabel {
    if instance == 0 || is_background_class(class) {
        InstanceLabel::Background
    } else {
        InstanceLabel::Object(ObjectId(instance))
    }
}

/// Intrinsics by precedence: the CLI camera, else `intrinsics.json`, else [`CameraIntrinsics::REPLICA`].
pub fn resolve_replica_intrinsics(dir: &Path, camera: Option<CameraIntrinsics>) -> Result<CameraIntrinsics> {
    if let Some(camera) = camera {
        return Ok(camera);
    }
    let json = dir.join("intrinsics.json");
    if json.exists() {
        // A folder or an unreadable file in its place is an error naming it, not a silent default.
        read_intrinsics_json(&json)
    } else {
        Ok(CameraIntrinsics::REPLICA)
    }
}

/// Poses of the frames with file indices `indices` from `traj_w_c.txt` (line `i + 1` holds frame `i`).
fn read_trajectory(path: &Path, indices: &[u64]) -> Result<Vec<Isometry3<f32>>> {
    let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
    let lines: Vec<&str> = text.lines().collect();
    let pose_count = lines
        .iter()
        .rposition(|l| !l.trim().is_empty())
        .map_or(0, |last| last + 1);
    let error = |line: usize, reason: String| CatmapError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    };
    indices
        .iter()
        .map(|&index| {
            let line_number = usize::try_from(index).map_or(usize::MAX, |i| i.saturating_add(1));
            let Some(line) = lines.get(line_number - 1).filter(|_| line_number <= pose_count) else {
                let reason = format!("missing pose of depth/depth_{index}.png: the file has only {pose_count} poses");
                return Err(error(line_number, reason));
            };
            let numbers = parse_numbers(line).map_err(|reason| error(line_number, reason))?;
            let rows: [f64; 16] = numbers
                .try_into()
                .map_err(|n: Vec<f64>| error(line_number, format!("expected 16 numbers, found {}", n.len())))?;
            world_from_camera_from_rows(&rows).map_err(|reason| error(line_number, reason))
        })
        .collect()
}

impl ReplicaSequence {
    /// Opens the sequence in `dir`: lists the depth frames, resolves the intrinsics and parses every
    /// pose. Fails on a missing folder or trajectory, and on any malformed pose line.
    pub fn open(dir: impl AsRef<Path>, options: &ReplicaOptions) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        if !dir.is_dir() {
            return Err(CatmapError::layout(
                dir,
                "the dataset folder does not exist (a sequence in Replica's layout: see `catmap run --help`)",
            ));
        }
        check_depth_options(options.depth_scale, options.max_depth_m)?;
        if let Some(problem) = options.camera.as_ref().and_then(intrinsics_problem) {
            return Err(CatmapError::ConfigValue(format!("camera: {problem}")));
        }
        let depth_dir = dir.join("depth");
        if !depth_dir.is_dir() {
            return Err(CatmapError::layout(&dir, not_replica_layout(&dir, "no depth/ folder")));
        }
        let indices: Vec<u64> = numbered_files(&depth_dir, "depth_", ".png")?
            .into_iter()
            .map(|(i, _)| i)
            .collect();
        if indices.is_empty() {
            return Err(CatmapError::layout(
                depth_dir,
                not_replica_layout(&dir, "no depth_<i>.png files, so no frames"),
            ));
        }
        let intrinsics = resolve_replica_intrinsics(&dir, options.camera)?;
        let poses = read_trajectory(&dir.join("traj_w_c.txt"), &indices)?;
        let frames = indices
            .into_iter()
            .zip(poses)
            .map(|(index, world_from_camera)| ReplicaFrame {
                index,
                world_from_camera,
            })
            .collect::<Vec<_>>();
        tracing::debug!(dir = %dir.display(), frames = frames.len(), ?intrinsics, "opened Replica sequence");
        Ok(Self {
            class_names: ClassNames::find_replica(&dir),
            dir,
            intrinsics,
            frames,
            depth_scale: options.depth_scale,
            max_depth_m: options.max_depth_m,
        })
    }

    /// The sequence folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Pose of the frame at `position`, without decoding its images.
    pub fn world_from_camera(&self, position: usize) -> Option<Isometry3<f32>> {
        self.frames.get(position).map(|f| f.world_from_camera)
    }

    fn frame_path(&self, folder: &str, index: u64) -> PathBuf {
        self.dir.join(folder).join(format!("{folder}_{index}.png"))
    }
}

/// Decodes the four images of a frame in parallel; errors are reported in the order rgb, depth,
/// class, instance.
/// A frame of checked images (depth in metres), each pixel labelled by [`replica_label`].
pub(crate) fn labelled_frame(
    index: FrameIndex,
    world_from_camera: Isometry3<f32>,
    intrinsics: CameraIntrinsics,
    (rgb, depth, classes, instances): (Image<[u8; 3]>, Image<f32>, Image<u32>, Image<u16>),
) -> RgbdFrame {
    let labels = classes
        .pixels
        .iter()
        .zip(&instances.pixels)
        .map(|(&c, &i)| replica_label(c, u32::from(i)));
    RgbdFrame {
        index,
        world_from_camera,
        intrinsics,
        rgb: rgb.pixels,
        depth_m: depth.pixels,
        instances: InstanceMask::from_labels(labels),
        classes: classes.pixels.into_iter().map(ClassId).collect(),
    }
}

fn decode_frame_images(
    rgb: &Path,
    depth: &Path,
    class: &Path,
    instance: &Path,
) -> Result<(Image<[u8; 3]>, Image<f32>, Image<u32>, Image<u16>)> {
    let ((rgb, depth), (class, instance)) = rayon::join(
        || rayon::join(|| read_rgb(rgb), || read_grey_as::<f32>(depth)),
        || rayon::join(|| read_grey(class), || read_grey_as::<u16>(instance)),
    );
    Ok((rgb?, depth?, class?, instance?))
}

impl FrameSource for ReplicaSequence {
    fn len(&self) -> usize {
        self.frames.len()
    }

    fn class_names(&self) -> ClassNames {
        self.class_names.clone()
    }

    fn intrinsics(&self) -> CameraIntrinsics {
        self.intrinsics
    }

    fn read_frame(&self, position: usize) -> Result<RgbdFrame> {
        let Some(frame) = self.frames.get(position) else {
            return Err(crate::dataset::position_out_of_range(&self.dir, position, self.len()));
        };
        let rgb_path = self.frame_path("rgb", frame.index);
        let depth_path = self.frame_path("depth", frame.index);
        let class_path = self.frame_path("semantic_class", frame.index);
        let instance_path = self.frame_path("semantic_instance", frame.index);
        let (rgb, mut depth, classes, instances) =
            decode_frame_images(&rgb_path, &depth_path, &class_path, &instance_path)?;

        let size = (self.intrinsics.width, self.intrinsics.height);
        if depth.size() != size {
            let reason = format!(
                "is {} pixels, but the camera intrinsics are for {} (images must match them exactly: \
                 pass --camera or add intrinsics.json)",
                size_text(depth.size()),
                size_text(size)
            );
            return Err(CatmapError::Image {
                path: depth_path,
                reason,
            });
        }
        let same_as_depth = "the depth image (and the camera)";
        require_size(&rgb, size, &rgb_path, same_as_depth)?;
        require_size(&classes, size, &class_path, same_as_depth)?;
        require_size(&instances, size, &instance_path, same_as_depth)?;

        depth_to_metres_in_place(&mut depth.pixels, self.depth_scale, self.max_depth_m);
        Ok(labelled_frame(
            FrameIndex(frame.index),
            frame.world_from_camera,
            self.intrinsics,
            (rgb, depth, classes, instances),
        ))
    }

    fn name(&self) -> String {
        self.dir.display().to_string()
    }
}

/// What a folder lacks (`missing`), what the Replica layout is, and what to try.
fn not_replica_layout(dir: &Path, missing: &str) -> String {
    let looks_like_scannet = ["color", "pose", "instance-filt"].iter().all(|f| dir.join(f).is_dir());
    let hint = if looks_like_scannet {
        "this looks like a ScanNet export: try `--format scannet`"
    } else {
        "a ScanNet export (color/, depth/, pose/, instance-filt/, label-filt/) opens with \
         `--format scannet`; `catmap synth --out DIR` writes an example of this layout"
    };
    format!(
        "not a sequence in Replica's (vMAP's) layout: {missing}. Expected depth/depth_<i>.png, \
         rgb/rgb_<i>.png, semantic_class/semantic_class_<i>.png, \
         semantic_instance/semantic_instance_<i>.png and traj_w_c.txt (intrinsics.json optional); {hint}"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn background_classes_override_instance_ids() {
        assert_eq!(replica_label(40, 7), InstanceLabel::Background, "floor is background");
        assert_eq!(
            replica_label(20, 0),
            InstanceLabel::Background,
            "instance 0 is no object"
        );
        assert_eq!(replica_label(20, 7), InstanceLabel::Object(ObjectId(7)));
        assert_eq!(
            replica_label(1000, 7),
            InstanceLabel::Object(ObjectId(7)),
            "large class ids are objects"
        );
        for class in REPLICA_BACKGROUND {
            assert!(is_background_class(class), "class {class} is background");
        }
    }
}
