//! The outputs of `catmap run`, in the order that keeps them safe: first the map's own
//! (`categories.json`, the meshes, `summary.json`, the recording under its final name), then the
//! optional evaluation (`metrics.json`). A failure of the evaluation, or of the recording's
//! completion, is a warning naming the file and the reason, recorded in `summary.json`
//! (`finishing_steps`); the run still exits 0, because the map was made.

use std::path::Path;
use std::time::Instant;

use anyhow::Context as _;
use catmap::metrics::object_matching::Pairing;
use catmap::metrics::{EvalSettings, EvaluationReport, GroundTruth, ObjectClasses, SceneFile};
use catmap::objects::instance_association::InstanceSource;
use catmap_systems::Mapper;
use catmap_systems::summary::{RunSummary, StepOutcome};

use crate::cli::run_plan::{Recording, RunPlan};

/// Writes every output of a finished mapper; errors only when the map's own outputs cannot be
/// written.
pub fn write_outputs(
    mut mapper: Mapper,
    plan: &RunPlan,
    dataset_name: String,
    started: Instant,
    live: Option<catmap_systems::summary::LiveSummary>,
) -> anyhow::Result<()> {
    let config = mapper.config().clone();
    let meshes_dir = if config.fields.enabled {
        let path = plan.out.join("categories.json");
        catmap_systems::categories_report::write_category_records(&mapper.category_records(), &path)?;
        tracing::info!(path = %path.display(), "categories written");
        let meshes = mapper.extract_final_meshes()?;
        let dir = plan.out.join("meshes");
        let written = meshes.write_dir(&dir)?;
        tracing::info!(files = written, dir = %dir.display(), "meshes written");
        Some(dir)
    } else {
        None
    };
    let mut stage_seconds = mapper.stage_seconds();
    if let Some(stats) = mapper.stream_stats() {
        stage_seconds.insert("read".to_owned(), stats.decode_time.as_secs_f64());
    }
    let training_steps = mapper.training_steps();
    let training = mapper.training_report();
    let map = mapper.finish();
    let seconds = || plan.seconds_before + started.elapsed().as_secs_f64();
    let mut summary = RunSummary::new(dataset_name, &map, stage_seconds, seconds());
    let protocol = if config.fields.offline {
        " (offline)"
    } else {
        " (online)"
    };
    summary.mode = format!("{:?}{protocol}", plan.mode).to_lowercase();
    summary.version = crate::VERSION.to_owned();
    summary.command_line = std::env::args().collect();
    summary.seed = config.seed;
    summary.config = Some(config.clone());
    summary.sensor = plan.sensor.clone();
    summary.training_steps = training_steps;
    summary.training = Some(training);
    summary.live = live;
    summary
        .finishing_steps
        .insert("recording".to_owned(), complete_recording(plan));
    let summary_path = plan.out.join("summary.json");
    summary.write_json(&summary_path)?;

    // Everything below is optional: the map and its summary are on disk.
    let eval_started = Instant::now();
    let eval = match &meshes_dir {
        None => StepOutcome::Skipped {
            reason: "fields.enabled = false: no meshes to evaluate".to_owned(),
        },
        Some(meshes) => {
            let settings = EvalSettings {
                seed: config.seed,
                pairing: pairing_of(&config),
                ..EvalSettings::default()
            };
            evaluate_run(meshes, plan, &settings, &summary.object_classes())
        }
    };
    if !matches!(eval, StepOutcome::Skipped { .. }) {
        summary
            .stage_seconds
            .insert("eval".to_owned(), eval_started.elapsed().as_secs_f64());
    }
    summary.finishing_steps.insert("eval".to_owned(), eval);
    summary.total_seconds = seconds();
    if let Err(e) = summary.write_json(&summary_path) {
        tracing::warn!(
            file = %summary_path.display(),
            error = %e,
            "cannot record the evaluation in the summary (the first summary stays)"
        );
    }
    crate::print_stdout(&summary.table());
    crate::print_stdout(&where_to_look(plan));
    tracing::info!(summary = %summary_path.display(), "done");
    Ok(())
}

/// What the run left in its output folder, with sizes, and how to look at it.
fn where_to_look(plan: &RunPlan) -> String {
    use std::fmt::Write as _;
    let mib = |bytes: u64| bytes as f64 / (1024.0 * 1024.0);
    let out = &plan.out;
    let mut text = format!("\noutputs in {}:\n", out.display());
    let meshes: Vec<(String, u64)> = std::fs::read_dir(out.join("meshes"))
        .map(|dir| {
            dir.flatten()
                .filter_map(|e| {
                    let name = e.file_name().to_string_lossy().into_owned();
                    let size = e.metadata().ok()?.len();
                    name.ends_with(".ply").then_some((name, size))
                })
                .collect()
        })
        .unwrap_or_default();
    if !meshes.is_empty() {
        let objects = meshes.iter().filter(|(name, _)| name.starts_with("obj_")).count();
        let total: u64 = meshes.iter().map(|(_, size)| size).sum();
        let _ = writeln!(
            text,
            "  meshes/          {objects} object meshes obj_{{id}}.ply{} ({:.0} MiB): open them in a mesh viewer \
             (MeshLab, Blender)",
            if meshes.len() > objects { " and the scene" } else { "" },
            mib(total),
        );
    }
    match &plan.recording {
        Recording::Save(path) => {
            let size = std::fs::metadata(path).map_or(0, |m| m.len());
            let _ = writeln!(
                text,
                "  recording        {} ({:.0} MiB): `rerun {}` replays the frames, masks, clouds, boxes, \
                 losses and meshes (--no-recording skips it)",
                path.display(),
                mib(size),
                path.display()
            );
        }
        Recording::Connect(url) => {
            let _ = writeln!(text, "  recording        streamed to {url}");
        }
        Recording::Off => {}
    }
    for (file, what) in [
        (
            "summary.json",
            "the run: seed, stages, training steps, objects and classes",
        ),
        (
            "metrics.json",
            "accuracy, completion and C.R. per object, per class and mean",
        ),
        (
            "categories.json",
            "each class's subcategories, representatives and registrations",
        ),
    ] {
        if out.join(file).is_file() {
            let _ = writeln!(text, "  {file:<16} {what}");
        }
    }
    text
}

/// Renames the finished recording file into place (a warning when that fails).
fn complete_recording(plan: &RunPlan) -> StepOutcome {
    match plan.complete_recording() {
        Ok(Some(output)) => StepOutcome::Done { output },
        Ok(None) => StepOutcome::Skipped {
            reason: "--no-recording".to_owned(),
        },
        Err(e) => {
            tracing::warn!("the recording is incomplete (the map is complete): {e:#}");
            StepOutcome::Failed {
                reason: format!("{e:#}"),
            }
        }
    }
}

/// Scores the written meshes against the dataset's `gt_meshes/` when there is one, with the
/// classes the map voted: `metrics.json` and the tables. Never fails the run.
fn evaluate_run(meshes: &Path, plan: &RunPlan, settings: &EvalSettings, classes: &ObjectClasses) -> StepOutcome {
    let gt_meshes = plan.dataset.join("gt_meshes");
    if !gt_meshes.is_dir() {
        return StepOutcome::Skipped {
            reason: format!("no ground truth: {} does not exist", gt_meshes.display()),
        };
    }
    let json = plan.out.join("metrics.json");
    match evaluate_and_write(meshes, &plan.dataset, settings, classes, &json) {
        Ok(report) => {
            crate::print_stdout(&catmap::metrics::render_markdown(&report));
            tracing::info!(metrics = %json.display(), "evaluation written");
            StepOutcome::Done {
                output: json.display().to_string(),
            }
        }
        Err(e) => {
            tracing::warn!("evaluation failed (the map is complete): {e:#}");
            StepOutcome::Failed {
                reason: format!("{e:#}"),
            }
        }
    }
}

/// How a run's meshes pair with the ground truth: by geometry when its ids came from per-frame
/// masks (they are not the dataset's), else by id.
pub fn pairing_of(config: &catmap::MapperConfig) -> Pairing {
    match config.objects.association.instances {
        InstanceSource::Consistent => Pairing::ById,
        InstanceSource::PerFrame => Pairing::Geometry,
    }
}

/// Evaluates `meshes` against `dataset` and writes the report to `json`. Paired by geometry,
/// the map's classes (keyed by its own ids) do not name the ground truth's objects.
fn evaluate_and_write(
    meshes: &Path,
    dataset: &Path,
    settings: &EvalSettings,
    classes: &ObjectClasses,
    json: &Path,
) -> anyhow::Result<EvaluationReport> {
    let none = ObjectClasses::new();
    let by_id = settings.pairing == Pairing::ById;
    let ground_truth = load_ground_truth(dataset, if by_id { classes } else { &none })?;
    let report = catmap::metrics::evaluate_ground_truth(meshes, &ground_truth, settings)
        .with_context(|| format!("cannot evaluate {} against {}", meshes.display(), dataset.display()))?;
    let mut text = serde_json::to_string_pretty(&report).context("cannot serialise the metrics")?;
    text.push('\n');
    catmap::atomic_file::write_atomic(json, text.as_bytes())
        .with_context(|| format!("cannot write {}", json.display()))?;
    Ok(report)
}

/// The ground truth of `dir`, saying once when its `scene.json` is not catmap's and is ignored.
pub fn load_ground_truth(dir: &Path, classes: &ObjectClasses) -> anyhow::Result<GroundTruth> {
    let ground_truth = GroundTruth::load(dir, classes)
        .with_context(|| format!("cannot read the ground truth in {}", dir.display()))?;
    if let SceneFile::Foreign { path, reason } = &ground_truth.scene_file {
        tracing::info!(
            file = %path.display(),
            %reason,
            "scene.json ignored: it is not catmap's scene description"
        );
    }
    Ok(ground_truth)
}
