//! The one configuration tree. Its defaults are the `fast` profile, catmap's; `MapperConfig::paper()`
//! is the paper's (METHOD.md). A TOML file lists only what it overrides, and unknown keys are errors.

use std::path::Path;

use serde::{Deserialize, Serialize};

pub mod layers;
mod phases;
mod profile;
mod rerun;
pub mod sensor_profile;

pub use crate::checkpoint::CheckpointConfig;
pub use crate::dataset::config::{DatasetConfig, LiveConfig, StreamConfig};
pub use crate::field::FieldConfig;
pub use crate::field::category::{CategoryFieldConfig, CategoryRayBudget};
pub use crate::meshing::MeshConfig;
pub use crate::objects::config::{KeyframeConfig, ObjectConfig};
pub use layers::SettingsLayers;
pub use phases::{AfterStream, FirstPhase};
pub use rerun::RerunConfig;

use crate::error::{CatmapError, Result};
use crate::geometry::face_normals_turn::BoxTurn;
use crate::sensor::depth_smoothing::{DepthImages, DepthSmoothing};

/// Everything the mapper can be told. `catmap config` prints the defaults as TOML.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(default, deny_unknown_fields)]
pub struct MapperConfig {
    /// Seed of every random choice (keyframe pruning, sampling, initial weights).
    pub seed: u64,
    /// How frames are read and handed to the mapper.
    pub stream: StreamConfig,
    /// How dataset images are interpreted.
    pub dataset: DatasetConfig,
    /// How objects are built from instance masks.
    pub objects: ObjectConfig,
    /// Per-object keyframe windows.
    pub keyframes: KeyframeConfig,
    /// Per-object fields and their training.
    pub fields: FieldConfig,
    /// Which fields train when (`catmap run --schedule`).
    pub schedule: crate::training::ScheduleConfig,
    /// Mesh extraction.
    pub meshes: MeshConfig,
    /// Category-level registration: representatives, subcategories, NOCS frames.
    pub categories: crate::categories::class_registration::CategoryConfig,
    /// Category-level fields (category mode).
    pub category_fields: CategoryFieldConfig,
    /// Live visualisation.
    pub rerun: RerunConfig,
    /// Checkpoints for `catmap run --resume`.
    pub checkpoint: CheckpointConfig,
}

impl MapperConfig {
    /// Steps every member's field must have taken before its class is registered: online,
    /// `categories.min_field_steps`; offline, all of the per-object training (as the reference
    /// code, which ranks uncertainty on the finished vMAP fields — early fields are confidently
    /// wrong in space no camera saw, which hides how well each member was observed).
    pub fn field_steps_before_registration(&self) -> u64 {
        let min = self.categories.min_field_steps;
        if self.fields.offline {
            min.max(self.fields.offline_iterations as u64)
        } else {
            min
        }
    }

    /// Parses a TOML file's text; unknown keys and wrong types are errors.
    pub fn from_toml(text: &str) -> Result<Self> {
        let config: Self = toml::from_str(text).map_err(|e| CatmapError::ConfigSyntax(e.to_string()))?;
        config.validate()?;
        Ok(config)
    }

    /// Reads a TOML config file (overrides only). Errors name the file, and the line of a TOML
    /// syntax or type error (line 0 when a value fails [`MapperConfig::validate`]).
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
        let parse_error = |line: usize, reason: String| CatmapError::Parse {
            path: path.to_path_buf(),
            line,
            reason,
        };
        let config: Self = toml::from_str(&text).map_err(|e| {
            let line = e.span().map_or(0, |span| line_of(&text, span.start));
            parse_error(line, e.message().trim().to_owned())
        })?;
        config.validate().map_err(|e| parse_error(0, e.to_string()))?;
        Ok(config)
    }

    /// Reads a config file's overrides as a table (for [`SettingsLayers::file`]), checked as
    /// [`Self::load`] checks them: errors name the file and the line.
    pub fn load_overrides(path: &Path) -> Result<toml::Table> {
        Self::load(path)?;
        let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
        toml::from_str(&text).map_err(|e| CatmapError::Parse {
            path: path.to_path_buf(),
            line: 0,
            reason: e.message().trim().to_owned(),
        })
    }

    /// The configuration as a TOML table, every field present.
    pub fn to_table(&self) -> toml::Table {
        toml::Table::try_from(self).expect("the config tree has only TOML-representable fields")
    }

    /// The configuration as TOML, every field present.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("the config tree has only TOML-representable fields")
    }

    /// These settings for depth images like `depth`: a depth camera's are smoothed (the
    /// bilateral filter of [`crate::sensor::depth_smoothing`]), its boxes fitted to the cloud
    /// voxels with at least 3 points (`objects.box_min_voxel_points`: its strays left out),
    /// moved onto their local surfaces (`objects.box_smoothing_m`, [`crate::objects::config::CAMERA_BOX_SMOOTHING_M`]),
    /// upright boxes of objects made mostly of upright faces turned to their normals
    /// (`objects.box_turn`), and the views allow for its noise (`dataset.depth_noise_per_m2`); exact ones get none of
    /// it and keep the masks' box rule. Measured in docs/ROBUSTNESS.md.
    pub fn with_depth_images(mut self, depth: DepthImages) -> Self {
        let (smoothing, depth_noise_per_m2) = match depth {
            DepthImages::Exact => (DepthSmoothing::None, 0.0),
            DepthImages::Camera => (DepthSmoothing::Bilateral, 0.0025),
        };
        self.dataset.depth_smoothing = smoothing;
        self.dataset.depth_noise_per_m2 = depth_noise_per_m2;
        if depth == DepthImages::Camera {
            self.objects.box_min_voxel_points = self.objects.box_min_voxel_points.max(3);
            self.objects.box_smoothing_m = crate::objects::config::CAMERA_BOX_SMOOTHING_M;
            self.objects.box_turn = BoxTurn::FaceNormals;
        } else {
            self.objects.box_smoothing_m = 0.0;
            self.objects.box_turn = BoxTurn::Rectangle;
        }
        self
    }

    /// Checks values that serde cannot.
    pub fn validate(&self) -> Result<()> {
        let bad = |msg: &str| Err(CatmapError::ConfigValue(msg.to_owned()));
        if !(1..=MAX_CHANNEL_CAPACITY).contains(&self.stream.channel_capacity) {
            return Err(CatmapError::ConfigValue(format!(
                "stream.channel_capacity must be between 1 and {MAX_CHANNEL_CAPACITY} frames (the channel reserves a slot per frame)"
            )));
        }
        if self.stream.frames_per_tick == 0 {
            return bad("stream.frames_per_tick must be at least 1");
        }
        if self.stream.stride == 0 {
            return bad("stream.stride must be at least 1");
        }
        if let Some(reason) = self.stream.live.invalid() {
            return bad(reason);
        }
        if self.dataset.depth_scale.is_nan() || self.dataset.depth_scale <= 0.0 {
            return bad("dataset.depth_scale must be positive");
        }
        if let Some(reason) = self.dataset.bilateral.invalid() {
            return bad(reason);
        }
        if self.keyframes.capacity < 3 {
            return bad("keyframes.capacity must be at least 3");
        }
        if self.keyframes.object_stride == 0 || self.keyframes.background_stride == 0 {
            return bad("keyframe strides must be at least 1");
        }
        if !(self.objects.cloud_voxel_m > 0.0
            && self.objects.bounds_voxel_m > 0.0
            && self.objects.background_voxel_m > 0.0)
        {
            return bad("voxel sizes must be positive");
        }
        let f = &self.fields;
        if !(f.learning_rate > 0.0 && f.learning_rate.is_finite() && f.weight_decay >= 0.0) {
            return bad("fields.learning_rate must be positive and fields.weight_decay non-negative");
        }
        if [f.object_scale, f.background_scale]
            .iter()
            .flatten()
            .any(|s| !(*s > 0.0 && s.is_finite()))
        {
            return bad("fields.object_scale and fields.background_scale must be positive");
        }
        for (name, rays) in [("object_rays", &f.object_rays), ("background_rays", &f.background_rays)] {
            if rays.keyframes_per_step == 0 || rays.pixels_per_keyframe == 0 || rays.samples_per_ray() == 0 {
                return Err(CatmapError::ConfigValue(format!(
                    "fields.{name}: keyframes, pixels and samples must be at least 1"
                )));
            }
            if !(rays.surface_band_m > 0.0 && rays.behind_occluder_m >= 0.0) {
                return Err(CatmapError::ConfigValue(format!(
                    "fields.{name}: surface_band_m must be positive"
                )));
            }
        }
        let plateau = &self.schedule.plateau;
        if !(plateau.learning_rate_decay > 0.0 && plateau.learning_rate_decay <= 1.0) {
            return bad("schedule.plateau.learning_rate_decay must be in (0, 1]");
        }
        let m = &self.meshes;
        if !(m.object.voxel_size_m > 0.0 && m.preview_voxel_m > 0.0 && m.background_voxel_m > 0.0) {
            return bad("meshes: voxel sizes must be positive");
        }
        if m.object.max_samples_per_side < 2 || !(m.object.box_fill > 0.0 && m.object.box_fill <= 1.0) {
            return bad("meshes.object: max_samples_per_side must be >= 2 and box_fill in (0, 1]");
        }
        if !(0.0..1.0).contains(&m.object.min_fragment_share) {
            return bad("meshes.object.min_fragment_share must be in [0, 1)");
        }
        if !(self.checkpoint.every_seconds >= 0.0 && self.checkpoint.every_seconds.is_finite()) {
            return bad("checkpoint.every_seconds must be a finite number of seconds, 0 or more (0: never)");
        }
        if self.rerun.image_downscale == 0 || self.rerun.image_every == 0 || self.rerun.depth_every == 0 {
            return bad("rerun.image_downscale, rerun.image_every and rerun.depth_every must be at least 1");
        }
        Ok(())
    }
}

/// Most frames the reader may run ahead of the mapper: the bounded channel reserves every slot
/// up front, and more than a few seconds of frames in flight only costs memory.
pub const MAX_CHANNEL_CAPACITY: usize = 1024;

/// 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    1 + text.as_bytes()[..end].iter().filter(|&&b| b == b'\n').count()
}

#[cfg(test)]
#[path = "reference_tests.rs"]
mod reference_tests;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_depth_cameras_images_are_smoothed_and_their_boxes_skip_lone_voxels() {
        let camera = MapperConfig::default().with_depth_images(DepthImages::Camera);
        assert_eq!(camera.dataset.depth_smoothing, DepthSmoothing::Bilateral);
        assert_eq!(
            camera.dataset.depth_noise_per_m2, 0.0025,
            "the views allow for its noise"
        );
        assert_eq!(camera.objects.box_min_voxel_points, 3);
        assert_eq!(camera.objects.box_smoothing_m, 0.08, "on their local surfaces");
        assert_eq!(camera.objects.box_turn, BoxTurn::FaceNormals);
        let exact = camera.with_depth_images(DepthImages::Exact);
        assert_eq!(exact.objects.box_smoothing_m, 0.0);
        assert_eq!(exact.objects.box_turn, BoxTurn::Rectangle);
        assert_eq!(exact.dataset, MapperConfig::default().dataset);
        assert_eq!(exact.objects.box_min_voxel_points, 3, "the masks' to reset");
        assert_eq!(
            MapperConfig::default().with_depth_images(DepthImages::Exact),
            MapperConfig::default()
        );
    }

    #[test]
    fn a_config_file_may_list_only_overrides() {
        let config = MapperConfig::from_toml("seed = 7\n[keyframes]\nobject_stride = 5\n").expect("valid");
        assert_eq!(config.seed, 7);
        assert_eq!(config.keyframes.object_stride, 5);
        assert_eq!(
            config.keyframes.capacity, 20,
            "untouched fields keep the paper's default"
        );
    }

    #[test]
    fn unknown_keys_are_rejected_with_their_name() {
        let err = MapperConfig::from_toml("[keyframes]\nstrid = 5\n").expect_err("typo must fail");
        assert!(err.to_string().contains("strid"), "error names the key: {err}");
    }

    #[test]
    fn printed_defaults_parse_back_to_the_defaults() {
        let text = MapperConfig::default().to_toml();
        assert_eq!(
            MapperConfig::from_toml(&text).expect("round trip"),
            MapperConfig::default()
        );
    }

    #[test]
    fn a_config_file_error_names_the_file_and_line() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, "seed = 1\n[keyframes]\nstrid = 5\n").expect("write");
        let err = MapperConfig::load(&path).expect_err("unknown key");
        let text = err.to_string();
        assert!(text.contains("bad.toml:3:") && text.contains("strid"), "{text}");
        std::fs::write(&path, "[stream]\nstride = 0\n").expect("write");
        let err = MapperConfig::load(&path).expect_err("stride 0");
        assert!(
            err.to_string().contains("bad.toml:0: invalid config: stream.stride"),
            "{err}"
        );
    }

    #[test]
    fn zero_channel_capacity_is_rejected() {
        let err = MapperConfig::from_toml("[stream]\nchannel_capacity = 0\n").expect_err("must fail");
        assert!(err.to_string().contains("channel_capacity"));
        // Found by the config fuzzer: the channel reserved 240 GB and the process aborted.
        let err = MapperConfig::from_toml("[stream]\nchannel_capacity = 4294967295\n").expect_err("must fail");
        assert!(err.to_string().contains("between 1 and 1024"), "{err}");
    }

    #[test]
    fn a_fragment_share_outside_zero_to_one_is_rejected() {
        for share in ["1.0", "-0.1", "nan"] {
            let toml = format!("[meshes.object]\nmin_fragment_share = {share}\n");
            let err = MapperConfig::from_toml(&toml).expect_err("must fail");
            assert!(err.to_string().contains("min_fragment_share"), "{share}: {err}");
        }
        assert!(MapperConfig::from_toml("[meshes.object]\nmin_fragment_share = 0.0\n").is_ok());
    }

    #[test]
    fn offline_classes_wait_for_the_whole_per_object_training() {
        let with_fields = |fields: FieldConfig| MapperConfig {
            fields,
            ..MapperConfig::default()
        };
        let min = MapperConfig::default().categories.min_field_steps;
        assert_eq!(
            with_fields(FieldConfig::default()).field_steps_before_registration(),
            min
        );
        let offline = FieldConfig {
            offline: true,
            offline_iterations: 1_500,
            ..FieldConfig::default()
        };
        assert_eq!(with_fields(offline.clone()).field_steps_before_registration(), 1_500);
        let short = FieldConfig {
            offline_iterations: 50,
            ..offline
        };
        assert_eq!(
            with_fields(short).field_steps_before_registration(),
            min,
            "never before the fields are trusted at all"
        );
    }
}
