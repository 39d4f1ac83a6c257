//! `catmap run`: stream a dataset through the mapper, log to Rerun, write the summary.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context as _;
use catmap::dataset::FrameSource;
use catmap::dataset::camera_spec::parse_camera_spec;
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::scannet::{ScanNetOptions, ScanNetSequence};
use catmap::stream::{FrameStream, stream_positions};
use catmap::synth::Preset;
use catmap_systems::Mapper;
use catmap_systems::summary::RunSummary;

use crate::cli_synth::write_scene;
use crate::progress::bar;

/// Arguments of `catmap run`.
#[derive(clap::Args, Debug)]
pub struct RunArgs {
    /// Dataset folder; without it the default synthetic scene is written to OUT/scene and mapped.
    #[arg(long)]
    pub dataset: Option<PathBuf>,
    /// Layout of the dataset folder.
    #[arg(long, value_enum, default_value_t = DatasetFormat::Replica)]
    pub format: DatasetFormat,
    /// Camera as W,H,FX,FY,CX,CY (Replica layout; default: intrinsics.json, else Replica's camera).
    #[arg(long)]
    pub camera: Option<String>,
    /// Config file (TOML; lists only what it changes, see `catmap config`).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Output folder.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
    /// Seed of every random choice (overrides the config's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Use every K-th frame.
    #[arg(long)]
    pub stride: Option<usize>,
    /// Map at most N frames.
    #[arg(long)]
    pub max_frames: Option<usize>,
    /// Save the Rerun recording here (default: OUT/recording.rrd unless --rerun-connect is given).
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
    /// Stream to a running Rerun viewer (default address: rerun+http://127.0.0.1:9876/proxy).
    #[arg(long, num_args = 0..=1, default_missing_value = "rerun+http://127.0.0.1:9876/proxy")]
    pub rerun_connect: Option<String>,
    /// Field model: per-object fields (vMAP*), or category-level fields.
    #[arg(long, value_enum, default_value_t = MapMode::Instance)]
    pub mode: MapMode,
    /// Offline protocol: read every frame first, then train (`fields.offline_iterations` steps).
    #[arg(long)]
    pub offline: bool,
    /// Training steps of the offline protocol (overrides `fields.offline_iterations`).
    #[arg(long)]
    pub iterations: Option<usize>,
    /// Category mode: steps of the category fields (overrides `category_fields.iterations`).
    #[arg(long)]
    pub category_iterations: Option<usize>,
    /// How a class's representative is chosen (ablation: random).
    #[arg(long, value_enum)]
    pub representative: Option<Representative>,
    /// Split classes into subcategories (ablation: off).
    #[arg(long, value_enum)]
    pub subcategories: Option<Switch>,
}

/// Representative choices.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Representative {
    /// The member with the most reliable uncertainty rays (the paper).
    Uncertainty,
    /// A member drawn at random (seeded).
    Random,
}

/// On or off.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Switch {
    /// Enabled.
    On,
    /// Disabled.
    Off,
}

/// Field models.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapMode {
    /// One occupancy field per object (the paper's vMAP* baseline).
    Instance,
    /// Category-level fields shared by objects of one shape (the paper).
    Category,
}

/// Dataset layouts.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum DatasetFormat {
    /// Replica in vMAP's layout (also what `catmap synth` writes).
    Replica,
    /// ScanNet (SensReader output + 2D labels).
    Scannet,
}

/// Runs `catmap run`.
pub fn run(args: &RunArgs) -> anyhow::Result<()> {
    let started = Instant::now();
    let mut config = crate::load_config(args.config.as_ref())?;
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    if let Some(stride) = args.stride {
        config.stream.stride = stride;
    }
    if let Some(max_frames) = args.max_frames {
        config.stream.max_frames = Some(max_frames);
    }
    if args.mode == MapMode::Category {
        config.categories.enabled = true;
        config.category_fields.enabled = true;
    }
    if let Some(iterations) = args.category_iterations {
        config.category_fields.iterations = iterations;
    }
    if let Some(choice) = args.representative {
        config.categories.representative = match choice {
            Representative::Uncertainty => catmap::uncertainty::RepresentativeChoice::Uncertainty,
            Representative::Random => catmap::uncertainty::RepresentativeChoice::Random,
        };
    }
    if let Some(switch) = args.subcategories {
        config.categories.subcategories.enabled = switch == Switch::On;
    }
    config.fields.offline |= args.offline;
    if let Some(iterations) = args.iterations {
        config.fields.offline_iterations = iterations;
    }
    if args.format == DatasetFormat::Scannet {
        config.fields = config
            .fields
            .with_default_scales(catmap::config::FieldConfig::SCANNET_SCALES);
    }
    config.validate().context("invalid settings")?;
    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;

    let (dataset_dir, source) = open_dataset(args, &config)?;
    let positions = stream_positions(source.len(), config.stream.stride, config.stream.max_frames);
    anyhow::ensure!(!positions.is_empty(), "{} has no frames to map", source.name());
    tracing::info!(dataset = %source.name(), frames = positions.len(), "mapping");

    let stream = FrameStream::spawn(Arc::clone(&source), positions.clone(), config.stream.channel_capacity);
    let fields = config.fields.clone();
    let category_mode = config.category_fields.enabled;
    let category_iterations = config.category_fields.iterations;
    let seed = config.seed;
    let mut mapper = Mapper::with_inbox(config, stream.receiver.clone())?;
    let recording = open_recording(args)?;
    mapper.set_recording(recording);

    let progress = bar(positions.len() as u64, "mapping");
    mapper.run_to_end(|frames| progress.set_position(frames));
    progress.finish_and_clear();
    stream.join();
    let after_stream = fields.steps_after_stream() as u64;
    if after_stream > 0 {
        let progress = bar(after_stream, if fields.offline { "training" } else { "refining" });
        mapper.train_after_stream(|done, _| progress.set_position(done));
        progress.finish_and_clear();
    }
    if category_mode {
        let total = category_iterations as u64;
        let progress = bar(total, "category fields");
        let count = mapper.train_categories(|done, _| progress.set_position(done));
        progress.finish_and_clear();
        tracing::info!(category_fields = count, "category fields trained");
    }
    let mut extra_seconds = std::collections::BTreeMap::new();
    if fields.enabled {
        let path = args.out.join("categories.json");
        catmap_systems::categories_report::write_category_records(&mapper.category_records(), &path)?;
        tracing::info!(path = %path.display(), "categories written");
    }
    if fields.enabled {
        let meshes = mapper.extract_final_meshes();
        let dir = args.out.join("meshes");
        let written = meshes.write_dir(&dir)?;
        tracing::info!(files = written, dir = %dir.display(), "meshes written");
        if dataset_dir.join("gt_meshes").is_dir() {
            let started = Instant::now();
            evaluate_run(&dir, &dataset_dir, seed, &args.out.join("metrics.json"))?;
            extra_seconds.insert("eval".to_owned(), started.elapsed().as_secs_f64());
        }
    }

    let mut stage_seconds: std::collections::BTreeMap<String, f64> = mapper
        .stage_seconds()
        .into_iter()
        .map(|(k, v)| (k.to_owned(), v))
        .collect();
    if let Some(stats) = mapper.stream_stats() {
        stage_seconds.insert("read (reader thread)".to_owned(), stats.decode_time.as_secs_f64());
    }
    stage_seconds.extend(extra_seconds);
    let training_steps = mapper.training_steps();
    let map = mapper.finish();
    let mut summary = RunSummary::new(source.name(), &map, stage_seconds, started.elapsed().as_secs_f64());
    summary.mode = format!(
        "{:?}{}",
        args.mode,
        if fields.offline { " (offline)" } else { " (online)" }
    )
    .to_lowercase();
    summary.training_steps = training_steps;
    let summary_path = args.out.join("summary.json");
    summary.write_json(&summary_path)?;
    crate::print_stdout(&summary.table());
    tracing::info!(summary = %summary_path.display(), "done");
    Ok(())
}

/// Scores the written meshes against the dataset's ground truth: `metrics.json` and a table.
fn evaluate_run(meshes: &Path, dataset: &Path, seed: u64, json: &Path) -> anyhow::Result<()> {
    let report = catmap::metrics::evaluate_dirs(meshes, dataset, catmap::metrics::Crop::Paper, seed)
        .with_context(|| format!("cannot evaluate {} against {}", meshes.display(), dataset.display()))?;
    let mut text = serde_json::to_string_pretty(&report).context("cannot serialise the metrics")?;
    text.push('\n');
    catmap::atomic_file::write_atomic(json, text.as_bytes())
        .with_context(|| format!("cannot write {}", json.display()))?;
    crate::print_stdout(&catmap::metrics::render_markdown(&report));
    tracing::info!(metrics = %json.display(), "evaluation written");
    Ok(())
}

fn open_dataset(args: &RunArgs, config: &catmap::MapperConfig) -> anyhow::Result<(PathBuf, Arc<dyn FrameSource>)> {
    let camera = args
        .camera
        .as_deref()
        .map(parse_camera_spec)
        .transpose()
        .context("--camera")?;
    let dir = match &args.dataset {
        Some(dir) => dir.clone(),
        None => {
            let dir = args.out.join("scene");
            write_scene(config.seed, Preset::Default, &dir)?;
            dir
        }
    };
    let source: Arc<dyn FrameSource> = match args.format {
        DatasetFormat::Replica => {
            let options = ReplicaOptions {
                camera,
                ..ReplicaOptions::from_config(&config.dataset)
            };
            Arc::new(ReplicaSequence::open(&dir, &options)?)
        }
        DatasetFormat::Scannet => {
            anyhow::ensure!(camera.is_none(), "--camera applies to the Replica layout only");
            let options = ScanNetOptions {
                depth_scale: config.dataset.depth_scale,
                max_depth_m: config.dataset.max_depth_m,
                ..ScanNetOptions::default()
            };
            Arc::new(ScanNetSequence::open(&dir, &options)?)
        }
    };
    Ok((dir, source))
}

fn open_recording(args: &RunArgs) -> anyhow::Result<rerun::RecordingStream> {
    let builder = rerun::RecordingStreamBuilder::new("catmap");
    if let Some(url) = &args.rerun_connect {
        let rec = builder
            .connect_grpc_opts(url.clone())
            .with_context(|| format!("cannot connect to Rerun at {url}"))?;
        if let Some(path) = &args.rerun_save {
            tracing::warn!(path = %path.display(), "--rerun-save is ignored with --rerun-connect");
        }
        return Ok(rec);
    }
    let path = args
        .rerun_save
        .clone()
        .unwrap_or_else(|| args.out.join("recording.rrd"));
    save_recording(builder, &path)
}

fn save_recording(builder: rerun::RecordingStreamBuilder, path: &Path) -> anyhow::Result<rerun::RecordingStream> {
    builder
        .save(path)
        .with_context(|| format!("cannot write the Rerun recording {}", path.display()))
}
