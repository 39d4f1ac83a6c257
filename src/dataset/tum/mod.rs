//! Sequences in TUM RGB-D's layout, with a segmenter's masks beside them (`--format tum`):
//!
//! ```text
//! <dir>/rgb.txt                  `timestamp path` per line (`#` comments), e.g. `1.000000 rgb/1.000000.png`
//! <dir>/depth.txt                the same for the depth images
//! <dir>/groundtruth.txt          `timestamp tx ty tz qx qy qz qw` per line: world_from_camera
//! <dir>/rgb/…, <dir>/depth/…     the listed images: colour PNG or JPEG; depth uint16, value / depth_scale = metres
//! <dir>/instance/<stem>.png      instance id per pixel (8 or 16 bit), 0 = none; <stem> = the colour image's name
//! <dir>/class/<stem>.png         class id per pixel (8 or 16 bit), Replica's numbering
//! <dir>/intrinsics.json          width, height, fx, fy, cx, cy (optional depth_scale); or `--camera`
//! <dir>/info_semantic.json       optional: the classes' names, as Replica's
//! ```
//!
//! The frames are the lines of `rgb.txt`, each with the depth image and pose nearest in time
//! ([`association`]: within 0.02 s, not interpolated). A colour image without a depth image or a
//! pose that near, or without its two masks, is skipped: the skips are counted and logged once per
//! reason at [`TumSequence::open`]. The depth scale is [`TumOptions::depth_scale`], else
//! `intrinsics.json`'s `depth_scale`, else TUM's 5000 units per metre. TUM ships no intrinsics
//! file; its cameras are in its documentation. Pixels of instance 0 or of a background class are
//! background ([`crate::dataset::replica::replica_label`]). A frame's index is its line's
//! position among `rgb.txt`'s images, so skipped images leave gaps.

pub mod association;
mod camera;
pub mod lists;
mod skips;

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use crate::dataset::FrameSource;
use crate::dataset::camera_spec::intrinsics_problem;
use crate::dataset::class_names::ClassNames;
use crate::dataset::config::DatasetConfig;
use crate::dataset::images::{
    Image, check_depth_options, depth_to_metres_in_place, read_grey, read_grey_as, read_rgb, require_size, size_text,
};
use crate::dataset::replica::labelled_frame;
use crate::error::{CatmapError, Result};
use crate::ids::FrameIndex;
use crate::sensor::frame::{CameraIntrinsics, RgbdFrame};
use association::{MAX_TIME_DIFFERENCE_S, Unmatched, associate};
use camera::resolve_camera;
use lists::{TimedFile, TimedPose, read_file_list, read_groundtruth};
pub use skips::SkippedImages;
use skips::{Missing, warn_skips};

/// TUM RGB-D's depth images: 5000 units per metre (0.2 mm).
pub const TUM_DEPTH_SCALE: f32 = 5000.0;

/// How to read a TUM RGB-D sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct TumOptions {
    /// Intrinsics given on the command line; they win over `intrinsics.json`.
    pub camera: Option<CameraIntrinsics>,
    /// Raw depth units per metre; `None`: `intrinsics.json`'s `depth_scale`, else [`TUM_DEPTH_SCALE`].
    pub depth_scale: Option<f32>,
    /// Depth beyond this is invalid, metres.
    pub max_depth_m: f32,
    /// Largest time between a colour image and its depth image or pose, seconds.
    pub max_time_difference_s: f64,
}

impl Default for TumOptions {
    fn default() -> Self {
        Self {
            camera: None,
            depth_scale: None,
            max_depth_m: DatasetConfig::default().max_depth_m,
            max_time_difference_s: MAX_TIME_DIFFERENCE_S,
        }
    }
}

/// The files of one frame, and where its colour and depth images were listed.
#[derive(Debug, Clone)]
struct TumFrame {
    /// Position of its colour image among `rgb.txt`'s images.
    ordinal: u64,
    timestamp_s: f64,
    rgb: TimedFile,
    depth: TimedFile,
    world_from_camera: Isometry3<f32>,
}

/// A TUM RGB-D sequence folder opened for random access.
#[derive(Debug, Clone)]
pub struct TumSequence {
    dir: PathBuf,
    intrinsics: CameraIntrinsics,
    depth_scale: f32,
    max_depth_m: f32,
    frames: Vec<TumFrame>,
    skipped: SkippedImages,
    class_names: ClassNames,
}

/// The two mask paths of a colour image (relative): `instance/<stem>.png`, `class/<stem>.png`.
fn mask_paths(rgb: &str) -> [String; 2] {
    let stem = Path::new(rgb)
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    ["instance", "class"].map(|folder| format!("{folder}/{stem}.png"))
}

/// Why `dir` is no TUM sequence: `missing` is absent.
fn not_tum_layout(path: &Path, missing: &str) -> CatmapError {
    CatmapError::layout(
        path,
        format!(
            "{missing}: a sequence in TUM RGB-D's layout has rgb.txt, depth.txt and groundtruth.txt \
             (`timestamp path` and `timestamp tx ty tz qx qy qz qw` lines), the images they list, \
             masks instance/<stem>.png and class/<stem>.png per colour image, and intrinsics.json \
             or --camera; `catmap synth --layout tum --out DIR` writes an example"
        ),
    )
}

impl TumSequence {
    /// Opens the sequence in `dir`: resolves the camera, parses the three lists, associates them
    /// and checks that every frame's images exist. Fails on a missing folder, list or camera, on
    /// any malformed list line, and when no colour image makes a frame.
    pub fn open(dir: impl AsRef<Path>, options: &TumOptions) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        if !dir.is_dir() {
            return Err(not_tum_layout(&dir, "the dataset folder does not exist"));
        }
        check_depth_options(options.depth_scale.unwrap_or(TUM_DEPTH_SCALE), options.max_depth_m)?;
        if let Some(problem) = options.camera.as_ref().and_then(intrinsics_problem) {
            return Err(CatmapError::ConfigValue(format!("camera: {problem}")));
        }
        if !(options.max_time_difference_s >= 0.0 && options.max_time_difference_s.is_finite()) {
            let reason = format!(
                "the largest time difference must be finite and not negative, got {}",
                options.max_time_difference_s
            );
            return Err(CatmapError::ConfigValue(reason));
        }
        for list in ["rgb.txt", "depth.txt", "groundtruth.txt"] {
            if !dir.join(list).exists() {
                return Err(not_tum_layout(&dir.join(list), "no such file"));
            }
        }
        let (intrinsics, depth_scale) = resolve_camera(&dir, options)?;
        check_depth_options(depth_scale, options.max_depth_m)?;
        let rgb = read_file_list(&dir.join("rgb.txt"))?;
        let depth = read_file_list(&dir.join("depth.txt"))?;
        let poses = read_groundtruth(&dir.join("groundtruth.txt"))?;
        if rgb.is_empty() {
            return Err(CatmapError::layout(
                dir.join("rgb.txt"),
                "lists no images, so no frames",
            ));
        }
        let (frames, skips) = assemble_frames(&dir, &rgb, &depth, &poses, options.max_time_difference_s)?;
        let skipped = SkippedImages::of(&skips);
        if frames.is_empty() {
            let reason = format!(
                "no colour image makes a frame: of its {} images, {} have no depth image within {} s \
                 in depth.txt, {} no pose within {} s in groundtruth.txt, {} no masks in instance/ \
                 and class/",
                rgb.len(),
                skipped.no_depth,
                options.max_time_difference_s,
                skipped.no_pose,
                options.max_time_difference_s,
                skipped.no_mask
            );
            return Err(CatmapError::layout(dir.join("rgb.txt"), reason));
        }
        warn_skips(&skips, options.max_time_difference_s);
        tracing::debug!(dir = %dir.display(), frames = frames.len(), ?skipped, ?intrinsics, depth_scale, "opened TUM RGB-D sequence");
        Ok(Self {
            class_names: ClassNames::find_replica(&dir),
            dir,
            intrinsics,
            depth_scale,
            max_depth_m: options.max_depth_m,
            frames,
            skipped,
        })
    }

    /// The sequence folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Colour images skipped at open, by reason.
    pub fn skipped(&self) -> SkippedImages {
        self.skipped
    }

    /// Raw depth units per metre.
    pub fn depth_scale(&self) -> f32 {
        self.depth_scale
    }

    /// Pose of the frame at `position`, without decoding its images.
    pub fn world_from_camera(&self, position: usize) -> Option<Isometry3<f32>> {
        self.frames.get(position).map(|f| f.world_from_camera)
    }

    /// Timestamp of the colour image of the frame at `position`, seconds.
    pub fn timestamp_s(&self, position: usize) -> Option<f64> {
        self.frames.get(position).map(|f| f.timestamp_s)
    }
}

/// The frames of the colour images `rgb` (with their depth images and poses nearest in time, and
/// both masks), and the images skipped; fails when a listed image of a frame is missing.
fn assemble_frames<'a>(
    dir: &Path,
    rgb: &'a [TimedFile],
    depth: &[TimedFile],
    poses: &[TimedPose],
    max_difference_s: f64,
) -> Result<(Vec<TumFrame>, Vec<(Missing, &'a TimedFile)>)> {
    let times = |files: &[TimedFile]| files.iter().map(|f| f.timestamp_s).collect::<Vec<_>>();
    let pose_times: Vec<f64> = poses.iter().map(|p| p.timestamp_s).collect();
    let matches = associate(&times(rgb), &times(depth), &pose_times, max_difference_s);
    let mut frames = Vec::new();
    let mut skips: Vec<(Missing, &TimedFile)> = Vec::new();
    for ((ordinal, image), matched) in (0u64..).zip(rgb).zip(matches) {
        let matched = match matched {
            Ok(matched) => matched,
            Err(Unmatched::NoDepth) => {
                skips.push((Missing::Depth, image));
                continue;
            }
            Err(Unmatched::NoPose) => {
                skips.push((Missing::Pose, image));
                continue;
            }
        };
        let depth_image = &depth[matched.depth];
        require_listed_file(dir, "rgb.txt", image)?;
        require_listed_file(dir, "depth.txt", depth_image)?;
        if !mask_paths(&image.path).iter().all(|p| dir.join(p).exists()) {
            skips.push((Missing::Mask, image));
            continue;
        }
        frames.push(TumFrame {
            ordinal,
            timestamp_s: image.timestamp_s,
            rgb: image.clone(),
            depth: depth_image.clone(),
            world_from_camera: poses[matched.pose].world_from_camera,
        });
    }
    Ok((frames, skips))
}

/// Fails unless the image `file` that `list` names is a file in `dir`.
fn require_listed_file(dir: &Path, list: &str, file: &TimedFile) -> Result<()> {
    if dir.join(&file.path).is_file() {
        return Ok(());
    }
    Err(CatmapError::Parse {
        path: dir.join(list),
        line: file.line,
        reason: format!("{} is not a file in the sequence folder", file.path),
    })
}

/// `error` with where its image was listed appended, when it is an image error.
fn listed_at(error: CatmapError, place: &str) -> CatmapError {
    match error {
        CatmapError::Image { path, reason } => CatmapError::Image {
            path,
            reason: format!("{reason} ({place})"),
        },
        other => other,
    }
}

impl FrameSource for TumSequence {
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
        let rgb_path = self.dir.join(&frame.rgb.path);
        let depth_path = self.dir.join(&frame.depth.path);
        let [instance_path, class_path] = mask_paths(&frame.rgb.path).map(|p| self.dir.join(p));
        let rgb_place = format!("rgb.txt line {}", frame.rgb.line);
        let mask_place = format!("the mask of the image on rgb.txt line {}", frame.rgb.line);
        let depth_place = format!("depth.txt line {}", frame.depth.line);
        let ((rgb, depth), (classes, instances)) = rayon::join(
            || rayon::join(|| read_rgb(&rgb_path), || read_grey_as::<f32>(&depth_path)),
            || rayon::join(|| read_grey(&class_path), || read_grey_as::<u16>(&instance_path)),
        );
        let rgb = rgb.map_err(|e| listed_at(e, &rgb_place))?;
        let mut depth: Image<f32> = depth.map_err(|e| listed_at(e, &depth_place))?;
        let classes = classes.map_err(|e| listed_at(e, &mask_place))?;
        let instances = instances.map_err(|e| listed_at(e, &mask_place))?;

        let size = (self.intrinsics.width, self.intrinsics.height);
        if depth.size() != size {
            let reason = format!(
                "is {} pixels, but the camera intrinsics are for {} (images must match them exactly: \
                 pass --camera or fix intrinsics.json) ({depth_place})",
                size_text(depth.size()),
                size_text(size)
            );
            return Err(CatmapError::Image {
                path: depth_path,
                reason,
            });
        }
        let same_as_depth = "the depth image (and the camera)";
        require_size(&rgb, size, &rgb_path, same_as_depth).map_err(|e| listed_at(e, &rgb_place))?;
        require_size(&classes, size, &class_path, same_as_depth).map_err(|e| listed_at(e, &mask_place))?;
        require_size(&instances, size, &instance_path, same_as_depth).map_err(|e| listed_at(e, &mask_place))?;

        depth_to_metres_in_place(&mut depth.pixels, self.depth_scale, self.max_depth_m);
        Ok(labelled_frame(
            FrameIndex(frame.ordinal),
            frame.world_from_camera,
            self.intrinsics,
            (rgb, depth, classes, instances),
        ))
    }

    fn name(&self) -> String {
        self.dir.display().to_string()
    }
}
