//! Issue 18: what a newcomer meets (see the binary's doc).

use super::*;

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
    // The priors of objects alone in their class: the table, the stool and the lamp report the
    // cells they drew from, the three chairs (completed by their twins) none.
    let fields = &summary["training"]["fields"];
    for object in objects {
        let name = object["class_name"].as_str().expect("a class name");
        let cells = &fields[format!("object {}", object["id"])]["prior_cells"];
        if name == "chair" {
            assert!(cells.is_null(), "a chair takes no prior: {cells}");
        } else {
            let (hidden, free) = (cells["hidden"].as_u64(), cells["seen_free"].as_u64());
            assert!(
                hidden.zip(free).is_some_and(|(h, f)| h + f > 0 && h + f <= 4096),
                "the {name}'s prior cells: {cells}"
            );
        }
    }
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
