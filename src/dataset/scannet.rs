//! ScanNet sequences as SensReader and the official 2D labels lay them out (METHOD.md §1):
//!
//! ```text
//! <dir>/color/{n}.jpg                   colour, any size (1296×968), resized bilinearly to the depth size
//! <dir>/depth/{n}.png                   uint16 millimetres (640×480)
//! <dir>/pose/{n}.txt                    4 lines × 4 numbers, world_from_camera; -inf marks lost tracking
//! <dir>/intrinsic/intrinsic_depth.txt   4×4: fx = m00, fy = m11, cx = m02, cy = m12
//! <dir>/instance-filt/{n}.png           instance id per pixel (0 = unlabelled), resized (nearest) to depth
//! <dir>/label-filt/{n}.png              raw label id per pixel (0 = unannotated), resized (nearest) to depth
//! ```
//!
//! Frames are the depth files sorted by the integer `n` (`2` before `10`); frames whose pose has an
//! infinite or NaN entry are skipped at open with a warning. A border of `border_px` pixels is cropped
//! from every image (ScanNet colour is invalid at the edges), shifting the principal point.
//!
//! Instance labels follow vMAP's `dataset.py` (`ScanNet.__getitem__`): instance ids are shifted by +1
//! so that 0 can mean background, and every instance whose label is a background label
//! ([`SCANNET_BACKGROUND`], which includes 0 = unannotated) becomes background. ScanNet's instance 0
//! always carries label 0, so in vMAP it becomes background, not unknown: vMAP's unknown state (−1,
//! "unsure area") is produced only later, by `utils.box_filter`, a cross-frame 3D consistency check
//! on tracked instances, not by the loader. The one case the loader leaves open — a pixel of
//! instance 0 whose label is a foreground class — is [`InstanceLabel::Unknown`] here (vMAP would
//! lump all such pixels into one spurious object 1).

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use crate::dataset::FrameSource;
use crate::dataset::camera_spec::{
    intrinsics_problem, parse_numbers, read_intrinsic_matrix, world_from_camera_from_rows,
};
use crate::dataset::class_names::ClassNames;
use crate::dataset::classes::SCANNET_BACKGROUND;
use crate::dataset::images::{
    Image, check_depth_options, depth_to_metres_in_place, numbered_files, read_grey_as, read_rgb, read_size,
    require_size, size_text,
};
use crate::dataset::resize::{resize_bilinear_rgb, resize_nearest};
use crate::error::{CatmapError, Result};
use crate::ids::{ClassId, FrameIndex, ObjectId};
use crate::sensor::frame::{CameraIntrinsics, InstanceLabel, InstanceMask, RgbdFrame};

/// How to read a ScanNet sequence.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanNetOptions {
    /// Raw depth units per metre (ScanNet: millimetres, 1000).
    pub depth_scale: f32,
    /// Depth beyond this is invalid, metres (vMAP's ScanNet configs use 6).
    pub max_depth_m: f32,
    /// Pixels cropped from every side of every image (vMAP: 10).
    pub border_px: u32,
}

impl Default for ScanNetOptions {
    fn default() -> Self {
        Self {
            depth_scale: 1000.0,
            max_depth_m: 6.0,
            border_px: 10,
        }
    }
}

/// One usable frame: its file number `n` and pose.
#[derive(Debug, Clone)]
struct ScanNetFrame {
    number: u64,
    world_from_camera: Isometry3<f32>,
}

/// A ScanNet sequence folder opened for random access.
#[derive(Debug, Clone)]
pub struct ScanNetSequence {
    dir: PathBuf,
    /// Size of the depth images before cropping.
    depth_size: (u32, u32),
    /// The depth image that size was read from (named when another one differs).
    first_depth: PathBuf,
    /// Intrinsics of the cropped images.
    intrinsics: CameraIntrinsics,
    frames: Vec<ScanNetFrame>,
    options: ScanNetOptions,
    class_names: ClassNames,
}

fn is_background_label(label: u32) -> bool {
    SCANNET_BACKGROUND.contains(&i64::from(label))
}

/// The instance label of one pixel from ScanNet's raw instance id and raw label id.
pub fn scannet_label(instance: u32, label: u32) -> InstanceLabel {
    if is_background_label(label) {
        InstanceLabel::Background
    } else if instance == 0 {
        InstanceLabel::Unknown
    } else {
        // vMAP: `inst_data += 1  # shift from 0->1 , 0 is for background`.
        InstanceLabel::Object(ObjectId(instance.saturating_add(1)))
    }
}

/// What a pose file holds.
enum PoseFile {
    Valid(Isometry3<f32>),
    /// An infinite or NaN entry: ScanNet's mark of lost tracking.
    NonFinite,
}

/// Parses `pose/{n}.txt`: four lines of four numbers.
fn read_pose(path: &Path) -> Result<PoseFile> {
    let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
    let error = |line: usize, reason: String| CatmapError::Parse {
        path: path.to_path_buf(),
        line,
        reason,
    };
    let mut rows = Vec::with_capacity(16);
    let mut row_count = 0;
    for (i, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let numbers = parse_numbers(line).map_err(|reason| error(i + 1, reason))?;
        if numbers.len() != 4 {
            return Err(error(i + 1, format!("expected 4 numbers, found {}", numbers.len())));
        }
        row_count += 1;
        rows.extend(numbers);
    }
    let rows: [f64; 16] = rows
        .try_into()
        .map_err(|_| error(0, format!("expected 4 rows, found {row_count}")))?;
    if rows.iter().any(|v| !v.is_finite()) {
        return Ok(PoseFile::NonFinite);
    }
    world_from_camera_from_rows(&rows)
        .map(PoseFile::Valid)
        .map_err(|reason| error(0, reason))
}

/// Fails unless `dir` is a folder.
fn require_dir(dir: &Path, what: &str) -> Result<()> {
    if dir.is_dir() {
        Ok(())
    } else {
        Err(CatmapError::layout(
            dir,
            format!(
                "{what} folder does not exist. A ScanNet sequence (SensReader output with its 2D \
                 labels) has color/, depth/, pose/, instance-filt/, label-filt/ and \
                 intrinsic/intrinsic_depth.txt; a folder in Replica's layout (depth/, rgb/, \
                 semantic_class/, semantic_instance/, traj_w_c.txt) opens with `--format replica`"
            ),
        ))
    }
}

impl ScanNetSequence {
    /// Opens the sequence in `dir`: lists the depth frames, parses every pose (skipping lost ones
    /// with a warning) and derives the cropped intrinsics from `intrinsic_depth.txt` and the size
    /// of the first depth image.
    pub fn open(dir: impl AsRef<Path>, options: &ScanNetOptions) -> Result<Self> {
        let dir = dir.as_ref().to_path_buf();
        require_dir(&dir, "ScanNet sequence")?;
        check_depth_options(options.depth_scale, options.max_depth_m)?;
        for folder in ["color", "depth", "pose", "instance-filt", "label-filt"] {
            require_dir(&dir.join(folder), folder)?;
        }
        let depth_files = numbered_files(&dir.join("depth"), "", ".png")?;
        let mut frames = Vec::with_capacity(depth_files.len());
        for (number, _) in &depth_files {
            let pose_path = dir.join("pose").join(format!("{number}.txt"));
            if !pose_path.exists() {
                let reason = format!("no such file: depth/{number}.png has no pose");
                return Err(CatmapError::layout(pose_path, reason));
            }
            match read_pose(&pose_path)? {
                PoseFile::Valid(world_from_camera) => frames.push(ScanNetFrame {
                    number: *number,
                    world_from_camera,
                }),
                PoseFile::NonFinite => {
                    tracing::warn!(file = %pose_path.display(), "skipping frame: pose has an infinite or NaN entry");
                }
            }
        }
        let Some(first) = frames.first() else {
            let reason = format!(
                "no frame has both a depth image and a finite pose ({} depth files)",
                depth_files.len()
            );
            return Err(CatmapError::layout(dir.join("depth"), reason));
        };
        let first_depth = dir.join("depth").join(format!("{}.png", first.number));
        let depth_size = read_size(&first_depth)?;
        let border = options.border_px;
        let crop = |side: u32| border.checked_mul(2).and_then(|b| side.checked_sub(b));
        let cropped = (crop(depth_size.0), crop(depth_size.1));
        let (Some(width @ 1..), Some(height @ 1..)) = cropped else {
            let reason = format!(
                "a {border}-pixel border leaves nothing of a {} image",
                size_text(depth_size)
            );
            return Err(CatmapError::Image {
                path: first_depth,
                reason,
            });
        };
        // The matrix is the full depth image's; the cropped camera is checked again.
        let matrix_path = dir.join("intrinsic").join("intrinsic_depth.txt");
        let full = read_intrinsic_matrix(&matrix_path, depth_size.0, depth_size.1)?;
        let intrinsics = CameraIntrinsics {
            width,
            height,
            cx: full.cx - border as f32,
            cy: full.cy - border as f32,
            ..full
        };
        if let Some(problem) = intrinsics_problem(&intrinsics) {
            return Err(CatmapError::Parse {
                path: matrix_path,
                line: 0,
                reason: format!(
                    "after cropping the {border}-pixel border of the first depth image ({}, {}): {problem}",
                    first_depth.display(),
                    size_text(depth_size)
                ),
            });
        }
        tracing::debug!(dir = %dir.display(), frames = frames.len(), ?intrinsics, "opened ScanNet sequence");
        Ok(Self {
            class_names: ClassNames::find_scannet(&dir),
            dir,
            depth_size,
            first_depth,
            intrinsics,
            frames,
            options: options.clone(),
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

    /// File number `n` of the frame at `position`.
    pub fn file_number(&self, position: usize) -> Option<u64> {
        self.frames.get(position).map(|f| f.number)
    }

    /// `image` without the border, checked to have the cropped camera's size.
    fn crop<T: Copy>(&self, image: &Image<T>, path: &Path) -> Result<Vec<T>> {
        let cropped = image
            .crop_border(self.options.border_px)
            .filter(|c| c.size() == (self.intrinsics.width, self.intrinsics.height));
        cropped.map(|c| c.pixels).ok_or_else(|| CatmapError::Image {
            path: path.to_path_buf(),
            reason: format!(
                "cannot crop a {}-pixel border from {}",
                self.options.border_px,
                size_text(image.size())
            ),
        })
    }

    /// Depth: must have the size of the sequence's first depth image; cropped.
    fn load_depth(&self, path: &Path) -> Result<Vec<f32>> {
        let depth = read_grey_as::<f32>(path)?;
        let first = format!("the sequence's first depth image ({})", self.first_depth.display());
        require_size(&depth, self.depth_size, path, &first)?;
        self.crop(&depth, path)
    }

    /// Colour: resized to the depth size with vMAP's `INTER_LINEAR`, then cropped.
    fn load_color(&self, path: &Path) -> Result<Vec<[u8; 3]>> {
        let (width, height) = self.depth_size;
        self.crop(&resize_bilinear_rgb(read_rgb(path)?, width, height), path)
    }

    /// Instance or label ids: resized to the depth size with vMAP's `INTER_NEAREST`, then cropped.
    fn load_ids<T: From<u16> + Copy + Default>(&self, path: &Path) -> Result<Vec<T>> {
        let (width, height) = self.depth_size;
        self.crop(&resize_nearest(read_grey_as::<T>(path)?, width, height), path)
    }
}

impl FrameSource for ScanNetSequence {
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
        let n = frame.number;
        let color_path = self.dir.join("color").join(format!("{n}.jpg"));
        let depth_path = self.dir.join("depth").join(format!("{n}.png"));
        let instance_path = self.dir.join("instance-filt").join(format!("{n}.png"));
        let label_path = self.dir.join("label-filt").join(format!("{n}.png"));
        // Each image is decoded, resized and cropped in its own task; errors are reported in the
        // order colour, depth, instance, label.
        let (color, (depth, (instances, labels))) = rayon::join(
            || self.load_color(&color_path),
            || {
                rayon::join(
                    || self.load_depth(&depth_path),
                    || {
                        rayon::join(
                            || self.load_ids::<u16>(&instance_path),
                            || self.load_ids::<u32>(&label_path),
                        )
                    },
                )
            },
        );
        let (color, mut depth, instances, labels) = (color?, depth?, instances?, labels?);
        depth_to_metres_in_place(&mut depth, self.options.depth_scale, self.options.max_depth_m);
        let mask = InstanceMask::from_labels(
            instances
                .iter()
                .zip(&labels)
                .map(|(&i, &l)| scannet_label(u32::from(i), l)),
        );
        Ok(RgbdFrame {
            index: FrameIndex(n),
            world_from_camera: frame.world_from_camera,
            intrinsics: self.intrinsics,
            rgb: color,
            depth_m: depth,
            instances: mask,
            classes: labels.into_iter().map(ClassId).collect(),
        })
    }

    fn name(&self) -> String {
        self.dir.display().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instance_ids_shift_by_one_and_background_labels_win() {
        assert_eq!(
            scannet_label(3, 5),
            InstanceLabel::Object(ObjectId(4)),
            "vMAP shifts ids by +1"
        );
        assert_eq!(
            scannet_label(3, 1),
            InstanceLabel::Background,
            "label 1 (wall) is background"
        );
        assert_eq!(
            scannet_label(0, 0),
            InstanceLabel::Background,
            "unannotated pixels are background"
        );
        assert_eq!(
            scannet_label(0, 5),
            InstanceLabel::Unknown,
            "a labelled pixel of no instance is unknown"
        );
    }
}
