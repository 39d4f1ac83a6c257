//! `catmap run`: stream a dataset through the mapper, log to Rerun, write the summary.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context as _;

use crate::cli::run_plan::{DatasetFormat, MapMode, Recording, RunPlan};
use crate::cli::sensor_choice::sensor_choice;
use crate::cli::synth::{PresetArg, write_scene};
use catmap::config::SettingsLayers;
use catmap::config::layers::set;

/// Arguments of `catmap run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Dataset folder; without it the default synthetic scene is written to OUT/scene and mapped.
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Without --dataset: the synthetic scene written to OUT/scene and mapped (`small`: a quick
    /// look in about a minute).
    #[arg(long, value_enum, default_value_t = PresetArg::Default, conflicts_with = "dataset")]
    pub preset: PresetArg,
    /// Layout of the dataset folder.
    #[arg(long, value_enum, default_value_t = DatasetFormat::Replica)]
    pub format: DatasetFormat,
    /// Camera as W,H,FX,FY,CX,CY (Replica and TUM layouts; default: intrinsics.json, else Replica's camera).
    #[arg(long)]
    pub camera: Option<String>,
    /// Config file (TOML; lists only what it changes, see `catmap config`).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Seed of every random choice [default: the config's `seed`, 0]
    #[arg(long)]
    pub seed: Option<u64>,
    /// Use every K-th frame [default: the config's `stream.stride`, 1]
    #[arg(long)]
    pub stride: Option<usize>,
    /// Map at most N frames [default: every frame]
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Save the Rerun recording here (default: OUT/recording.rrd unless --rerun-connect is given).
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
    /// Write no Rerun recording (it is ~18 MB for the small preset, ~100 MB for the default scene).
    #[arg(long, conflicts_with_all = ["rerun_save", "rerun_connect"])]
    pub no_recording: bool,
    /// Stream to a running Rerun viewer (default address: rerun+http://127.0.0.1:9876/proxy).
    #[arg(long, num_args = 0..=1, default_missing_value = "rerun+http://127.0.0.1:9876/proxy")]
    pub rerun_connect: Option<String>,
    /// Field model: category-level fields (the paper), or per-object fields only (vMAP*).
    #[arg(long, value_enum, default_value_t = MapMode::Category)]
    pub mode: MapMode,
    /// Offline protocol: read every frame first, then train (`fields.offline_iterations` steps).
    #[arg(long)]
    pub offline: bool,
    /// Training steps of the offline protocol [default: the config's `fields.offline_iterations`,
    /// 15000]
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Category mode: steps of the category fields under the paper schedule [default: the config's
    /// `category_fields.iterations`, 10000]
    #[arg(long)]
    pub category_iterations: Option<usize>,
    /// How a class's representative is chosen (ablation: random) [default: the config's
    /// `categories.representative`, uncertainty]
    #[arg(long, value_enum)]
    pub representative: Option<Representative>,
    /// Training schedule: fast (the default: train only what changes the map — fields seen in the
    /// new frame or still improving — and stop what has converged) or paper (the paper's fixed
    /// protocol, every field on every step: ~3.7× the time, better completion of objects seen
    /// from one side only). Offline runs always follow paper [default: the config's
    /// `schedule.policy`, fast]
    #[arg(long, value_enum)]
    pub schedule: Option<ScheduleArg>,
    /// Split classes into subcategories (ablation: off) [default: the config's
    /// `categories.subcategories.enabled`, on]
    #[arg(long, value_enum)]
    pub subcategories: Option<Switch>,
    /// Live mapping: replay the dataset at the sensor's rate (--fps) instead of waiting for the
    /// mapper; the mapper takes the newest frame (older ones are dropped and counted), trains in
    /// the time there is, and after the last frame trains `stream.live.finish_seconds` more
    /// before the final meshes. Live runs keep no checkpoint.
    #[arg(long)]
    pub live: bool,
    /// Frames per second of the live replay [default: the config's `stream.live.fps`, else 30]
    #[arg(long, requires = "live")]
    pub fps: Option<f64>,
    /// Instance ids of the dataset: one per object over the sequence, or every frame its own
    /// (a 2D segmenter's); per-frame masks are associated into objects by class and 3D overlap
    /// [default: what a probe finds — per-frame when an id is not where it was in the next frame
    /// or the masks are a segmenter's; else the config's `objects.association.instances`]
    #[arg(long, value_enum)]
    pub instances: Option<InstancesArg>,
    /// The masks' borders: exact (rendered, annotated) or a 2D segmenter's (a pixel or two off,
    /// filling narrow gaps): `segmenter` trims mask pixels far behind their object and ignores a
    /// band around every border [default: what a probe of 12 frames finds — a segmenter's when
    /// the masks' borders stray from the depth's silhouettes; else the config's]
    #[arg(long, value_enum)]
    pub masks: Option<MasksArg>,
    /// The depth images: exact (rendered, Replica's) or a depth camera's (noise growing with
    /// distance, stray points): `camera` smooths each depth image with an edge-preserving
    /// bilateral filter before use, fits boxes to cloud voxels holding at least 3 points and
    /// allows for the noise in what a view says of a point [default: what a probe of 12 frames
    /// finds — a camera's when the depth's noise σ at 2 m is above 1 mm; else the config's]
    #[arg(long, value_enum)]
    pub depth: Option<DepthArg>,
    /// Continue the interrupted run whose output folder is DIR (from `DIR/checkpoint`), with the
    /// settings it started with; other options are ignored.
    #[arg(long, value_name = "DIR")]
    pub resume: Option<PathBuf>,
}

/// `--instances` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum InstancesArg {
    /// One id per object over the whole sequence (Replica, ScanNet).
    Consistent,
    /// Every frame numbers its masks anew.
    PerFrame,
}

impl From<InstancesArg> for catmap::objects::instance_association::InstanceSource {
    fn from(instances: InstancesArg) -> Self {
        match instances {
            InstancesArg::Consistent => Self::Consistent,
            InstancesArg::PerFrame => Self::PerFrame,
        }
    }
}

/// `--masks` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum MasksArg {
    /// Exact masks (Replica, ScanNet, the synthetic scenes without noise).
    Exact,
    /// A 2D segmenter's masks.
    Segmenter,
}

/// `--depth` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthArg {
    /// Exact depth, used as read.
    Exact,
    /// A depth camera's depth, smoothed (bilateral filter), its noise allowed for.
    Camera,
}

/// Representative choices.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Representative {
    /// The member with the most reliable uncertainty rays (the paper).
    Uncertainty,
    /// A member drawn at random (seeded).
    Random,
}

/// Training schedules.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ScheduleArg {
    /// Train what changes the map; stop converged and replaced fields.
    Fast,
    /// The paper's fixed protocol: every field on every step.
    Paper,
}

/// On or off.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

/// Runs `catmap run` (or continues one with `--resume`).
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    if let Some(out) = &args.resume {
        return crate::cli::run_phases::resume(out);
    }
    let started = Instant::now();
    let mut layers = layers_from_args(args)?;
    let config = resolved(&layers, args.format)?;
    let dataset = match &args.dataset {
        Some(dir) => dir.clone(),
        None => args.out.join("scene"),
    };
    let recording = match &args.rerun_connect {
        _ if args.no_recording => Recording::Off,
        Some(url) => {
            if let Some(path) = &args.rerun_save {
                tracing::warn!(path = %path.display(), "--rerun-save is ignored with --rerun-connect");
            }
            Recording::Connect(url.clone())
        }
        None => Recording::Save(
            args.rerun_save
                .clone()
                .unwrap_or_else(|| args.out.join("recording.rrd")),
        ),
    };
    // Absolute paths, so that `--resume` works from any folder.
    let absolute = |p: &std::path::Path| std::path::absolute(p).with_context(|| format!("bad path {}", p.display()));
    let recording = match recording {
        Recording::Save(path) => Recording::Save(absolute(&path)?),
        connect => connect,
    };
    let mut plan = RunPlan {
        dataset: absolute(&dataset)?,
        format: args.format,
        camera: args.camera.clone(),
        out: absolute(&args.out)?,
        mode: args.mode,
        recording,
        seconds_before: 0.0,
        sensor: None,
    };
    // A dataset is opened before anything is written, so that a run that cannot start leaves
    // nothing behind.
    if args.dataset.is_none() {
        write_scene(
            config.seed,
            args.preset.into(),
            catmap::synth::SensorSettings::default(),
            &plan.dataset,
        )?;
    }
    let raw = plan.open_raw_source(&config)?;
    // `--instances` (or a config file's per-frame) is a choice the probe leaves alone.
    let instances = config.objects.association.instances;
    let given =
        args.instances.is_some() || instances == catmap::objects::instance_association::InstanceSource::PerFrame;
    let choice = sensor_choice(args.depth, args.masks, given.then_some(instances), raw.as_ref());
    layers.sensor = Some(choice.clone());
    let config = resolved(&layers, args.format)?;
    plan.sensor = Some(choice);
    let dataset_config = &config.dataset;
    let source = catmap::dataset::smoothed_depth::with_depth_smoothing(
        raw,
        dataset_config.depth_smoothing,
        &dataset_config.bilateral,
    );
    std::fs::create_dir_all(&plan.out).with_context(|| format!("cannot create {}", plan.out.display()))?;
    crate::cli::run_phases::drive(
        crate::cli::run_phases::Start::Fresh(Box::new(config)),
        plan,
        Arc::clone(&source),
        started,
    )
}

/// The run's layers of settings above its profile: the config file's overrides and the flags'
/// (the sensor's are added once the dataset is probed, [`run`]).
pub fn layers_from_args(args: &RunArgs) -> anyhow::Result<SettingsLayers> {
    let file = match &args.config {
        None => toml::Table::new(),
        // The error names the file (and the line of a TOML error).
        Some(path) => catmap::MapperConfig::load_overrides(path).context("cannot load the config")?,
    };
    let mut flags = toml::Table::new();
    let f = &mut flags;
    if let Some(seed) = args.seed {
        set(f, "seed", value(&seed)?);
    }
    if let Some(stride) = args.stride {
        set(f, "stream.stride", value(&stride)?);
    }
    if let Some(max_frames) = args.max_frames {
        set(f, "stream.max_frames", value(&max_frames)?);
    }
    if args.live {
        set(f, "stream.live.enabled", true);
    }
    if let Some(fps) = args.fps {
        set(f, "stream.live.fps", fps);
    }
    if let Some(instances) = args.instances {
        let source = catmap::objects::instance_association::InstanceSource::from(instances);
        set(f, "objects.association.instances", value(&source)?);
    }
    match args.mode {
        MapMode::Category => {
            set(f, "categories.enabled", true);
            set(f, "category_fields.enabled", true);
        }
        // Registration alone (categories.json) stays as the config file says.
        MapMode::Instance => set(f, "category_fields.enabled", false),
    }
    if let Some(iterations) = args.category_iterations {
        set(f, "category_fields.iterations", value(&iterations)?);
    }
    if let Some(choice) = args.representative {
        let choice = match choice {
            Representative::Uncertainty => catmap::categories::uncertainty::RepresentativeChoice::Uncertainty,
            Representative::Random => catmap::categories::uncertainty::RepresentativeChoice::Random,
        };
        set(f, "categories.representative", value(&choice)?);
    }
    if let Some(schedule) = args.schedule {
        let policy = match schedule {
            ScheduleArg::Fast => catmap::training::SchedulePolicy::Fast,
            ScheduleArg::Paper => catmap::training::SchedulePolicy::Paper,
        };
        set(f, "schedule.policy", value(&policy)?);
    }
    if let Some(switch) = args.subcategories {
        set(f, "categories.subcategories.enabled", switch == Switch::On);
    }
    if args.offline {
        set(f, "fields.offline", true);
    }
    if let Some(iterations) = args.iterations {
        set(f, "fields.offline_iterations", value(&iterations)?);
    }
    Ok(SettingsLayers {
        sensor: None,
        file,
        flags,
    })
}

/// A flag's value as TOML (a seed above 2⁶³ − 1 is none).
fn value<T: serde::Serialize + std::fmt::Debug>(v: &T) -> anyhow::Result<toml::Value> {
    toml::Value::try_from(v).with_context(|| format!("{v:?} is not a value a setting can take"))
}

/// The settings `layers` resolve to, with the encoding scales of a ScanNet dataset.
pub fn resolved(layers: &SettingsLayers, format: DatasetFormat) -> anyhow::Result<catmap::MapperConfig> {
    let mut config = layers.resolve().context("invalid settings")?;
    if format == DatasetFormat::Scannet {
        config.fields = config
            .fields
            .with_default_scales(catmap::config::FieldConfig::SCANNET_SCALES);
    }
    Ok(config)
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    /// The settings of `args` without a sensor probe (exact depth and masks unless a config
    /// file or a flag says otherwise).
    fn config_from_args(args: &RunArgs) -> anyhow::Result<catmap::MapperConfig> {
        resolved(&layers_from_args(args)?, args.format)
    }

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: RunArgs,
    }

    fn config_of(argv: &[&str]) -> catmap::MapperConfig {
        let cli = Cli::try_parse_from(std::iter::once("catmap").chain(argv.iter().copied())).expect("arguments parse");
        config_from_args(&cli.args).expect("valid config")
    }

    #[test]
    fn category_mode_is_the_default() {
        let config = config_of(&[]);
        assert!(config.categories.enabled && config.category_fields.enabled);
        let cli = Cli::try_parse_from(["catmap"]).expect("arguments parse");
        assert_eq!(cli.args.mode, MapMode::Category);
    }

    #[test]
    fn catmap_config_prints_the_defaults_the_command_line_uses_and_reads_back_as_them() {
        let defaults = catmap::MapperConfig::default();
        assert_eq!(
            config_of(&[]),
            defaults,
            "the library's defaults are the command line's"
        );
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("printed.toml");
        std::fs::write(&path, defaults.to_toml()).expect("write the printed config");
        let path = path.to_str().expect("a UTF-8 temp path");
        assert_eq!(
            config_of(&["--config", path]),
            defaults,
            "`catmap config > F; catmap run --config F`"
        );
    }

    #[test]
    fn the_fast_schedule_is_the_default_and_paper_is_one_flag_away() {
        use catmap::training::SchedulePolicy;
        assert_eq!(config_of(&[]).schedule.policy, SchedulePolicy::Fast);
        let instance = config_of(&["--mode", "instance"]);
        assert_eq!(instance.schedule.policy, SchedulePolicy::Fast, "instance mode included");
        assert_eq!(
            config_of(&["--schedule", "paper"]).schedule.policy,
            SchedulePolicy::Paper
        );
        let offline = config_of(&["--offline"]);
        assert_eq!(
            offline.training_policy(),
            SchedulePolicy::Paper,
            "offline is the paper's protocol"
        );
    }

    #[test]
    fn live_is_off_by_default_and_takes_its_rate_from_fps() {
        assert!(!config_of(&[]).stream.live.enabled);
        let live = config_of(&["--live", "--fps", "5"]).stream.live;
        assert!(live.enabled);
        assert_eq!(live.fps(), 5.0);
        assert_eq!(
            config_of(&["--live"]).stream.live.fps(),
            30.0,
            "no timestamps: 30 frames/s"
        );
        assert!(
            Cli::try_parse_from(["catmap", "--fps", "5"]).is_err(),
            "--fps needs --live"
        );
        let cli = Cli::try_parse_from(["catmap", "--live", "--fps", "0"]).expect("arguments parse");
        let err = config_from_args(&cli.args).expect_err("a rate of 0");
        assert!(format!("{err:#}").contains("stream.live.fps"), "{err:#}");
    }

    #[test]
    fn instance_mode_trains_no_category_fields() {
        let config = config_of(&["--mode", "instance"]);
        assert!(!config.category_fields.enabled);
        let config = config_of(&["--mode", "instance", "--subcategories", "off", "--offline"]);
        assert!(!config.category_fields.enabled && !config.categories.subcategories.enabled && config.fields.offline);
    }
}
