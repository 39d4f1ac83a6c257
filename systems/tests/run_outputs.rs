//! What `catmap run` leaves on disk.
//! - Issue 6 (resilience): on degenerate datasets it finishes with a warning and whole outputs —
//!   a scene without objects, and a stream whose depth file is truncated mid-frame.
//! - Issue 16: a run never loses its outputs to an optional step — on a Replica-layout dataset
//!   whose `scene.json` is not catmap's (another schema, none, not JSON) every output is written
//!   under its final name and `metrics.json` names each object's class from the map; when the
//!   evaluation itself fails, the run exits 0 with its other outputs whole and the failure in the
//!   log and in `summary.json`.
//! - Issue 18: what a newcomer meets — the README's quick look prints what it promises and leaves
//!   the files it lists; a dataset in the wrong layout, or none, is refused with the expected
//!   files and the other format named, and leaves no output folder; `eval` on a folder without
//!   predictions fails and says what to try; `catmap [run options]` and `--version`.

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

/// What `scene.json` a foreign dataset has.
#[derive(Debug, Clone, Copy)]
enum ForeignSceneFile {
    /// A JSON file of another schema (as Replica exports have their own).
    OtherSchema,
    /// No `scene.json` at all.
    Absent,
    /// A file that is not JSON.
    NotJson,
}

/// Turns the synthetic scene in `work/scene` into a dataset catmap did not write: its own
/// `scene.json` replaced as `kind` says, no `intrinsics.json` (the camera is given on the command
/// line instead). Returns the ground-truth class name of every object and the `--camera` value.
fn make_foreign(work: &Path, kind: ForeignSceneFile) -> (Vec<(u64, String)>, String) {
    let scene = work.join("scene");
    let description = json(&scene.join("scene.json"));
    let classes: Vec<(u64, String)> = description["objects"]
        .as_array()
        .expect("objects listed")
        .iter()
        .map(|o| {
            let id = o["id"].as_u64().expect("id");
            (id, o["class_name"].as_str().expect("class name").to_owned())
        })
        .collect();
    let intrinsics = json(&scene.join("intrinsics.json"));
    let camera = ["width", "height", "fx", "fy", "cx", "cy"]
        .map(|k| intrinsics[k].to_string())
        .join(",");
    std::fs::remove_file(scene.join("intrinsics.json")).expect("intrinsics removed");
    let path = scene.join("scene.json");
    match kind {
        ForeignSceneFile::OtherSchema => {
            let other = r#"{"objects": [{"instance": 1, "label": "chair", "bbox": [0, 0, 1, 1]}], "rooms": 1}"#;
            std::fs::write(&path, other).expect("scene.json replaced");
        }
        ForeignSceneFile::Absent => std::fs::remove_file(&path).expect("scene.json removed"),
        ForeignSceneFile::NotJson => std::fs::write(&path, "objects:\n  - chair\n").expect("scene.json replaced"),
    }
    (classes, camera)
}

fn run_on_a_foreign_dataset(kind: ForeignSceneFile) {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    let (classes, camera) = make_foreign(work, kind);
    let output = catmap()
        .env("RUST_LOG", "info")
        .arg("run")
        .arg("--dataset")
        .arg(work.join("scene"))
        .args(["--format", "replica", "--camera", &camera])
        .arg("--config")
        .arg(work.join("config.toml"))
        .args(["--max-frames", "30", "--out"])
        .arg(work.join("out"))
        .output()
        .expect("catmap runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{kind:?}: the run exits 0: {stderr}");
    let out = work.join("out");
    assert_outputs_whole(&out);
    let metrics = json(&out.join("metrics.json"));
    let scored: Vec<(u64, String)> = metrics["objects"]
        .as_array()
        .expect("objects scored")
        .iter()
        .map(|o| {
            (
                o["id"].as_u64().expect("id"),
                o["class_name"].as_str().expect("name").to_owned(),
            )
        })
        .collect();
    assert_eq!(
        scored, classes,
        "{kind:?}: every object named by its class from the map"
    );
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["finishing_steps"]["eval"]["outcome"], "done", "{summary}");
    match kind {
        ForeignSceneFile::Absent => assert!(!stderr.contains("scene.json ignored"), "{stderr}"),
        ForeignSceneFile::OtherSchema | ForeignSceneFile::NotJson => assert_eq!(
            stderr.matches("scene.json ignored").count(),
            1,
            "{kind:?}: one info line says the file is ignored: {stderr}"
        ),
    }
}

#[test]
fn a_run_on_a_dataset_whose_scene_json_has_another_schema_names_every_class() {
    run_on_a_foreign_dataset(ForeignSceneFile::OtherSchema);
}

#[test]
fn a_run_on_a_dataset_without_scene_json_names_every_class() {
    run_on_a_foreign_dataset(ForeignSceneFile::Absent);
}

#[test]
fn a_run_on_a_dataset_whose_scene_json_is_not_json_names_every_class() {
    run_on_a_foreign_dataset(ForeignSceneFile::NotJson);
}

#[test]
fn a_failing_evaluation_leaves_a_complete_run_that_exits_0() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    let broken = work.join("scene/gt_meshes/obj_2.ply");
    std::fs::write(&broken, b"ply\nformat binary_little_endian 1.0\nelement vertex 9").expect("mesh broken");
    let output = run(work);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the run exits 0: {stderr}");
    assert!(
        stderr.contains("evaluation failed") && stderr.contains("obj_2.ply"),
        "the log names the failure and the file: {stderr}"
    );
    let out = work.join("out");
    assert_outputs_whole(&out);
    assert!(
        !out.join("metrics.json").exists(),
        "no metrics from a failed evaluation"
    );
    let summary = json(&out.join("summary.json"));
    let eval = &summary["finishing_steps"]["eval"];
    assert_eq!(eval["outcome"], "failed", "{summary}");
    assert!(
        eval["reason"].as_str().is_some_and(|r| r.contains("obj_2.ply")),
        "the summary names the file: {eval}"
    );
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains("eval failed (the map is complete)"),
        "the end table says so: {stdout}"
    );
}

/// The README's quick look: `catmap run --preset small --out quick`.
#[test]
fn the_readmes_quick_look_maps_the_small_preset_and_says_where_to_look() {
    let work = tempfile::tempdir().expect("temp dir");
    let out = work.path().join("quick");
    let output = catmap()
        .args(["run", "--preset", "small", "--out"])
        .arg(&out)
        .output()
        .expect("catmap runs");
    let (stdout, stderr) = (
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr),
    );
    assert!(output.status.success(), "the quick look completes: {stderr}");
    for line in [
        "# Reconstruction metrics",
        "6 objects, 0 missing",
        "mode: category (online)",
        "training (Fast schedule)",
        "**wall clock**",
        "outputs in ",
        "meshes/          6 object meshes obj_{id}.ply",
        "recording.rrd (",
        "summary.json     the run",
        "metrics.json     accuracy",
        "categories.json  each class",
    ] {
        assert!(stdout.contains(line), "the output promises {line:?}:\n{stdout}");
    }
    let meshes: Vec<String> = (1..=6).map(|id| format!("obj_{id}.ply")).collect();
    assert_eq!(object_meshes(&out), {
        let mut sorted = meshes.clone();
        sorted.sort();
        sorted
    });
    for file in [
        "recording.rrd",
        "summary.json",
        "metrics.json",
        "categories.json",
        "scene/traj_w_c.txt",
    ] {
        assert!(out.join(file).is_file(), "{file} written");
    }
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["seed"], 0);
    let version = summary["version"].as_str().expect("a version");
    assert!(version.starts_with(env!("CARGO_PKG_VERSION")), "{version}");
    assert!(
        summary["command_line"]
            .as_array()
            .is_some_and(|args| args.iter().any(|a| a == "--preset")),
        "the command line: {}",
        summary["command_line"]
    );
    assert_eq!(
        summary["config"]["category_fields"]["enabled"], true,
        "the paper's method"
    );
    let objects = summary["objects"].as_array().expect("objects");
    assert_eq!(objects.len(), 6);
    assert!(
        objects
            .iter()
            .all(|o| o["bounds"]["world_from_box"]["translation"].is_array()),
        "each object's box and pose: {objects:?}"
    );
}

/// Runs `catmap run --dataset DATASET --out OUT [more]`; its stderr, after asserting that it
/// failed and left no output folder.
fn refused_run(dataset: &Path, out: &Path, more: &[&str]) -> String {
    let output = catmap()
        .arg("run")
        .arg("--dataset")
        .arg(dataset)
        .arg("--out")
        .arg(out)
        .args(more)
        .output()
        .expect("catmap runs");
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(!output.status.success(), "refused: {stderr}");
    assert!(!out.exists(), "a run that cannot start leaves no {}", out.display());
    stderr
}

fn assert_says(stderr: &str, phrases: &[&str]) {
    for phrase in phrases {
        assert!(stderr.contains(phrase), "the message says {phrase:?}: {stderr}");
    }
}

#[test]
fn a_dataset_in_the_other_layout_is_refused_naming_the_expected_files_and_the_other_format() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    // A ScanNet export opened as Replica (the default format).
    let scannet = work.join("scannet");
    for folder in ["color", "depth", "pose", "instance-filt", "label-filt"] {
        std::fs::create_dir_all(scannet.join(folder)).expect("folder");
    }
    std::fs::write(scannet.join("depth/0.png"), b"").expect("a ScanNet depth file");
    let stderr = refused_run(&scannet, &work.join("out1"), &[]);
    assert_says(
        &stderr,
        &[
            "scannet",
            "depth_<i>.png",
            "traj_w_c.txt",
            "looks like a ScanNet export",
            "--format scannet",
        ],
    );
    // A Replica-layout folder opened as ScanNet.
    let replica = work.join("replica");
    for folder in ["depth", "rgb", "semantic_class", "semantic_instance"] {
        std::fs::create_dir_all(replica.join(folder)).expect("folder");
    }
    let stderr = refused_run(&replica, &work.join("out2"), &["--format", "scannet"]);
    assert_says(&stderr, &["color", "pose/", "instance-filt/", "--format replica"]);
    // An empty folder.
    let empty = work.join("empty");
    std::fs::create_dir_all(&empty).expect("folder");
    let stderr = refused_run(&empty, &work.join("out3"), &[]);
    assert_says(
        &stderr,
        &["empty", "no depth/ folder", "--format scannet", "catmap synth"],
    );
    assert_eq!(stderr.matches("No such file").count(), 0, "no bare OS error: {stderr}");
}

#[test]
fn a_missing_dataset_is_refused_naming_it_and_catmap_alone_takes_runs_options() {
    let work = tempfile::tempdir().expect("temp dir");
    let missing = work.path().join("no-such-dataset");
    let stderr = refused_run(&missing, &work.path().join("out"), &[]);
    assert_says(&stderr, &["no-such-dataset", "does not exist"]);
    // `catmap [run options]` is `catmap run [run options]`.
    let out = work.path().join("out2");
    let output = catmap()
        .args(["--stride", "2", "--dataset"])
        .arg(&missing)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("catmap runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && !out.exists());
    assert_says(&stderr, &["no-such-dataset", "does not exist"]);
    let version = catmap().arg("--version").output().expect("catmap runs");
    let version = String::from_utf8_lossy(&version.stdout);
    assert!(
        version.starts_with(&format!("catmap {}", env!("CARGO_PKG_VERSION"))),
        "{version}"
    );
    let in_git = std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .is_ok_and(|o| o.status.success());
    assert_eq!(
        version.contains("(commit "),
        in_git,
        "the commit when built from git: {version}"
    );
}

#[test]
fn eval_on_a_folder_without_predictions_fails_and_says_what_to_try() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    let pred = work.join("predictions");
    std::fs::create_dir_all(&pred).expect("folder");
    let output = catmap()
        .arg("eval")
        .arg("--pred")
        .arg(&pred)
        .arg("--gt")
        .arg(work.join("scene"))
        .output()
        .expect("catmap runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "nothing matched: a failure");
    assert_says(
        &stderr,
        &["predictions", "obj_{id}.ply", "meshes/", "catmap run's output folder"],
    );
}
