//! What `catmap run` leaves on disk.
//! - Issue 6 (resilience): on degenerate datasets it finishes with a warning and whole outputs —
//!   a scene without objects, and a stream whose depth file is truncated mid-frame.
//! - Issue 16: a run never loses its outputs to an optional step — on a Replica-layout dataset
//!   whose `scene.json` is not catmap's (another schema, none, not JSON) every output is written
//!   under its final name and `metrics.json` names each object's class from the map; when the
//!   evaluation itself fails, the run exits 0 with its other outputs whole and the failure in the
//!   log and in `summary.json`.
//! - Kills (`kill_resume`): a run SIGKILLed at random moments and resumed each time ends like one
//!   that was never interrupted, and every file on disk is whole after each kill.
//! - Issue 32 (`live`): a live run that drops frames ends with whole outputs and lists its drops.
//! - Issue 18: what a newcomer meets — the README's quick look prints what it promises and leaves
//!   the files it lists; a dataset in the wrong layout, or none, is refused with the expected
//!   files and the other format named, and leaves no output folder; `eval` on a folder without
//!   predictions fails and says what to try; `catmap [run options]` and `--version`.
//! - Issue 34 (`own_data`): the README's "Your own data" walk-through, run as written: a
//!   synthetic sequence in TUM RGB-D's layout with per-frame masks, mapped.
//! - Issue 69 (`sweeps`): the quick sweep and its report reproduce docs/RESULTS.md's quick tables
//!   byte for byte; the jobs emitted for GNU parallel, Slurm and Kubernetes parse, and parallel's
//!   script runs a two-run sweep where GNU parallel is installed.

use std::path::Path;
use std::process::{Command, Output};

const CONFIG: &str = r#"
seed = 2

[stream]
max_frames = 5

[fields]
steps_per_frame = 2
final_steps = 20

[categories]
min_field_steps = 4

[categories.uncertainty]
angles = 30

[category_fields]
iterations = 20

# The default (fast) schedule, capped: a short phase after the stream.
[schedule]
max_steps_after_stream = 40

[meshes]
background_voxel_m = 0.15

[meshes.object]
voxel_size_m = 0.04
max_samples_per_side = 48
"#;

fn catmap() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_catmap"));
    command.env("RUST_LOG", "warn").env("NO_COLOR", "1");
    command
}

/// A small synthetic scene in `work/scene` and the quick config in `work/config.toml`.
fn small_scene(work: &Path) {
    std::fs::write(work.join("config.toml"), CONFIG).expect("config written");
    let status = catmap()
        .args(["synth", "--preset", "small", "--seed", "4", "--out"])
        .arg(work.join("scene"))
        .output()
        .expect("catmap runs")
        .status;
    assert!(status.success(), "synth");
}

/// `catmap run` in category mode on `work/scene` into `work/out`.
fn run(work: &Path) -> Output {
    catmap()
        .arg("run")
        .arg("--dataset")
        .arg(work.join("scene"))
        .arg("--config")
        .arg(work.join("config.toml"))
        .args(["--mode", "category", "--out"])
        .arg(work.join("out"))
        .output()
        .expect("catmap runs")
}

fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{} readable: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{} is whole JSON: {e}", path.display()))
}

fn object_meshes(out: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(out.join("meshes"))
        .expect("meshes folder")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with("obj_"))
        .collect();
    names.sort();
    names
}

#[test]
fn catmap_run_on_a_scene_without_objects_warns_and_writes_every_output() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    for entry in std::fs::read_dir(work.join("scene/semantic_instance")).expect("instance masks") {
        let path = entry.expect("entry").path();
        let (w, h) = image::image_dimensions(&path).expect("png");
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::new(w, h)
            .save(&path)
            .expect("mask rewritten");
    }
    let output = run(work);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the run completes: {stderr}");
    assert!(stderr.contains("the map has no objects"), "warned: {stderr}");
    let out = work.join("out");
    assert_eq!(json(&out.join("categories.json")), serde_json::json!([]), "no classes");
    assert!(
        object_meshes(&out).is_empty(),
        "no object meshes: {:?}",
        object_meshes(&out)
    );
    assert!(json(&out.join("summary.json")).is_object(), "summary written");
    assert!(json(&out.join("metrics.json")).is_object(), "metrics written");
}

#[test]
fn catmap_run_on_a_stream_truncated_mid_frame_reports_it_and_keeps_the_map() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    let depth = work.join("scene/depth/depth_3.png");
    let bytes = std::fs::read(&depth).expect("depth png");
    std::fs::write(&depth, &bytes[..bytes.len() / 2]).expect("depth truncated");
    let output = run(work);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the run completes: {stderr}");
    assert!(stderr.contains("depth_3.png"), "the truncated file is named: {stderr}");
    let out = work.join("out");
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["frames_skipped"], 1, "one frame skipped");
    assert!(!object_meshes(&out).is_empty(), "the other frames are meshed");
    assert!(json(&out.join("categories.json")).is_array(), "categories written");
    assert!(json(&out.join("metrics.json")).is_object(), "metrics written");
}

/// Every file under `dir`, relative, sorted.
fn files_under(dir: &Path) -> Vec<String> {
    let mut files = Vec::new();
    let mut pending = vec![dir.to_owned()];
    while let Some(folder) = pending.pop() {
        for entry in std::fs::read_dir(&folder).expect("readable folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                pending.push(path);
            } else {
                let relative = path.strip_prefix(dir).expect("under dir");
                files.push(relative.to_string_lossy().into_owned());
            }
        }
    }
    files.sort();
    files
}

/// The run's own outputs are whole and under their final names: no `*.tmp` anywhere, the
/// recording, categories, summary and at least one object mesh.
fn assert_outputs_whole(out: &Path) {
    let files = files_under(out);
    assert!(
        files.iter().all(|f| !f.ends_with(".tmp")),
        "no temporary file is left: {files:?}"
    );
    let recording = std::fs::metadata(out.join("recording.rrd")).expect("the recording under its final name");
    assert!(recording.len() > 0, "the recording has content");
    assert!(json(&out.join("categories.json")).is_array(), "categories written");
    let summary = json(&out.join("summary.json"));
    assert_eq!(
        summary["finishing_steps"]["recording"]["outcome"], "done",
        "the recording was completed: {summary}"
    );
    assert!(!object_meshes(out).is_empty(), "object meshes written");
}

mod foreign;
mod kill_resume;
mod live;
mod newcomer;
mod own_data;
mod sweeps;
