//! [`RunPlan`]: what `catmap run` was asked to do, kept in each checkpoint so that
//! `catmap run --resume OUT` can continue without the original command line.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Context as _;
use catmap::config::RerunConfig;
use catmap::config::sensor_profile::SensorChoice;
use catmap::dataset::FrameSource;
use catmap::dataset::camera_spec::parse_camera_spec;
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::scannet::{ScanNetOptions, ScanNetSequence};
use catmap::dataset::smoothed_depth::with_depth_smoothing;
use catmap::dataset::tum::{TumOptions, TumSequence};
use serde::{Deserialize, Serialize};

use catmap_systems::rrd_file::{RrdFooter, save_rrd};

/// Field models.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum MapMode {
    /// Category-level fields shared by objects of one shape (the paper; the default).
    Category,
    /// One occupancy field per object (the paper's vMAP* baseline).
    Instance,
}

/// Dataset layouts.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum DatasetFormat {
    /// Replica in vMAP's layout (also what `catmap synth` writes).
    Replica,
    /// ScanNet (SensReader output + 2D labels).
    Scannet,
    /// TUM RGB-D (rgb.txt, depth.txt, groundtruth.txt) with masks in instance/ and class/; the
    /// default `replica` opens such a folder as this too.
    Tum,
}

impl DatasetFormat {
    /// The layout `dir` is opened with: `self`, except that under the default (`replica`) a
    /// folder in TUM RGB-D's layout — `rgb.txt` and `depth.txt`, no `traj_w_c.txt` — is TUM's.
    pub fn resolve(self, dir: &Path) -> Self {
        let is_file = |name: &str| dir.join(name).is_file();
        if self == Self::Replica && is_file("rgb.txt") && is_file("depth.txt") && !is_file("traj_w_c.txt") {
            tracing::debug!(dir = %dir.display(), "rgb.txt and depth.txt: opened in TUM RGB-D's layout");
            Self::Tum
        } else {
            self
        }
    }
}

/// Where the Rerun recording goes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Recording {
    /// Saved to this file (written as `FILE.tmp`, renamed when the run completes).
    Save(PathBuf),
    /// Streamed to a viewer at this address.
    Connect(String),
    /// None (`--no-recording`).
    Off,
}

/// The run's inputs and outputs besides the mapper configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunPlan {
    /// Dataset folder (the synthetic scene written to OUT/scene when none was given).
    pub dataset: PathBuf,
    /// Its layout.
    pub format: DatasetFormat,
    /// `--camera`, if given.
    pub camera: Option<String>,
    /// Output folder.
    pub out: PathBuf,
    /// Field model.
    pub mode: MapMode,
    /// The Rerun recording.
    pub recording: Recording,
    /// Wall-clock seconds spent by earlier (interrupted) processes of this run.
    pub seconds_before: f64,
    /// The depth and mask settings the run took, and what the probe of the dataset found.
    #[serde(default)]
    pub sensor: Option<SensorChoice>,
}

impl RunPlan {
    /// The checkpoint folder.
    pub fn checkpoint_dir(&self) -> PathBuf {
        self.out.join("checkpoint")
    }

    /// Opens the dataset as a frame source, its depth smoothed as `config` says.
    pub fn open_source(&self, config: &catmap::MapperConfig) -> anyhow::Result<Arc<dyn FrameSource>> {
        let dataset = &config.dataset;
        Ok(with_depth_smoothing(
            self.open_raw_source(config)?,
            dataset.depth_smoothing,
            &dataset.bilateral,
        ))
    }

    /// Opens the dataset as a frame source, its images as read.
    pub fn open_raw_source(&self, config: &catmap::MapperConfig) -> anyhow::Result<Arc<dyn FrameSource>> {
        let camera = self
            .camera
            .as_deref()
            .map(parse_camera_spec)
            .transpose()
            .context("--camera")?;
        let dir = &self.dataset;
        let source: Arc<dyn FrameSource> = match self.format.resolve(dir) {
            DatasetFormat::Replica => {
                let options = ReplicaOptions {
                    camera,
                    ..ReplicaOptions::from_config(&config.dataset)
                };
                Arc::new(ReplicaSequence::open(dir, &options)?)
            }
            DatasetFormat::Scannet => {
                anyhow::ensure!(camera.is_none(), "--camera applies to the Replica and TUM layouts only");
                let options = ScanNetOptions {
                    depth_scale: config.dataset.depth_scale,
                    max_depth_m: config.dataset.max_depth_m,
                    ..ScanNetOptions::default()
                };
                Arc::new(ScanNetSequence::open(dir, &options)?)
            }
            DatasetFormat::Tum => {
                // TUM's depth scale is its own (intrinsics.json's `depth_scale`, else 5000) unless
                // the config changes `dataset.depth_scale` from its (Replica's) default.
                let default_scale = catmap::dataset::config::DatasetConfig::default().depth_scale;
                let changed = config.dataset.depth_scale != default_scale;
                let options = TumOptions {
                    camera,
                    depth_scale: changed.then_some(config.dataset.depth_scale),
                    max_depth_m: config.dataset.max_depth_m,
                    ..TumOptions::default()
                };
                Arc::new(TumSequence::open(dir, &options)?)
            }
        };
        Ok(source)
    }

    /// Opens the recording: a connection, or the temporary sibling of the file (see
    /// [`RunPlan::complete_recording`]). A file for a stream of more than
    /// `rerun.rrd_footer_max_frames` frames is saved without Rerun's in-memory chunk index
    /// ([`crate::rrd_file`]).
    pub fn open_recording(
        &self,
        frames: usize,
        config: &RerunConfig,
    ) -> anyhow::Result<Option<rerun::RecordingStream>> {
        let builder = rerun::RecordingStreamBuilder::new("catmap");
        match &self.recording {
            Recording::Off => Ok(None),
            Recording::Connect(url) => builder
                .connect_grpc_opts(url.clone())
                .map(Some)
                .with_context(|| format!("cannot connect to Rerun at {url}")),
            Recording::Save(path) => {
                if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
                    std::fs::create_dir_all(parent).with_context(|| format!("cannot create {}", parent.display()))?;
                }
                let temp = catmap::atomic_file::temp_path_for(path);
                let footer = RrdFooter::for_stream(Some(frames as u64), config);
                if footer == RrdFooter::Omitted {
                    tracing::info!(
                        frames,
                        "long stream: the recording is saved without its chunk index (add it with `rerun rrd optimize`)"
                    );
                }
                save_rrd(builder, &temp, footer)
                    .map(Some)
                    .with_context(|| format!("cannot write the Rerun recording {}", temp.display()))
            }
        }
    }

    /// Renames the finished recording file into place (after the recording was flushed);
    /// returns where the recording went (`None`: there is none).
    pub fn complete_recording(&self) -> anyhow::Result<Option<String>> {
        match &self.recording {
            Recording::Save(path) => {
                let temp = catmap::atomic_file::temp_path_for(path);
                std::fs::rename(&temp, path)
                    .with_context(|| format!("cannot move {} to {}", temp.display(), path.display()))?;
                Ok(Some(path.display().to_string()))
            }
            Recording::Connect(url) => Ok(Some(url.clone())),
            Recording::Off => Ok(None),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_format_opens_a_folder_with_tums_lists_as_tum() {
        let dir = tempfile::tempdir().expect("temp dir");
        let dir = dir.path();
        assert_eq!(
            DatasetFormat::Replica.resolve(dir),
            DatasetFormat::Replica,
            "an empty folder"
        );
        for list in ["rgb.txt", "depth.txt"] {
            std::fs::write(dir.join(list), "# a list\n").expect("list written");
        }
        assert_eq!(DatasetFormat::Replica.resolve(dir), DatasetFormat::Tum);
        assert_eq!(
            DatasetFormat::Scannet.resolve(dir),
            DatasetFormat::Scannet,
            "an explicit other format stays"
        );
        std::fs::write(dir.join("traj_w_c.txt"), "").expect("a Replica trajectory");
        assert_eq!(
            DatasetFormat::Replica.resolve(dir),
            DatasetFormat::Replica,
            "Replica's trajectory wins"
        );
    }
}
