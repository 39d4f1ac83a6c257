//! Issue 34: the README's "Your own data" walk-through, run as written — `catmap synth --layout
//! tum` writes a sequence in TUM RGB-D's layout with a segmenter's per-frame masks, and
//! `catmap run --dataset DIR` maps it (the layout found by its files, the camera, the segmenter
//! and the per-frame ids by the probe), as written.

use super::*;

/// The `catmap …` lines of the first code block of the README's "Your own data" section.
fn walk_through_commands() -> Vec<String> {
    let readme = include_str!("../../../README.md");
    let section = readme
        .split("\n## ")
        .find(|s| s.starts_with("Your own data"))
        .expect("the README has a \"Your own data\" section");
    let block = section
        .split("```")
        .skip(1)
        .step_by(2)
        .find(|block| block.lines().any(|l| l.trim_start().starts_with("catmap ")))
        .expect("a code block of catmap commands in \"Your own data\"");
    block
        .lines()
        .map(|l| l.split(" #").next().unwrap_or("").trim())
        .filter(|l| l.starts_with("catmap "))
        .map(str::to_owned)
        .collect()
}

/// Runs `command` (a `catmap …` line) with the folders after `--out` and `--dataset` placed in
/// `work` and `more` appended.
fn run_line(command: &str, work: &Path, more: &[&str]) -> Output {
    let words: Vec<&str> = command.split_whitespace().skip(1).collect();
    let mut process = catmap();
    for (i, word) in words.iter().enumerate() {
        let is_folder = i > 0 && ["--out", "--dataset"].contains(&words[i - 1]);
        if is_folder {
            process.arg(work.join(word));
        } else {
            process.arg(word);
        }
    }
    process.args(more).output().expect("catmap runs")
}

#[test]
fn the_readmes_own_data_walk_through_maps_a_tum_layout_sequence_with_per_frame_masks() {
    let commands = walk_through_commands();
    let [synth, run] = &commands[..] else {
        panic!("two commands, synth then run: {commands:?}")
    };
    assert!(
        synth.starts_with("catmap synth") && synth.contains("--layout tum"),
        "{synth}"
    );
    assert!(
        run.starts_with("catmap run") && !run.contains("--instances"),
        "no flag: the probe finds the ids numbered anew in every frame: {run}"
    );
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    let output = run_line(synth, work, &[]);
    assert!(
        output.status.success(),
        "{synth}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let dataset = std::fs::read_dir(work)
        .expect("the synth output")
        .map(|e| e.expect("entry").path())
        .find(|p| p.is_dir())
        .expect("a dataset folder");
    for file in ["rgb.txt", "depth.txt", "groundtruth.txt", "intrinsics.json"] {
        assert!(dataset.join(file).is_file(), "{file} written");
    }
    for folder in ["rgb", "depth", "instance", "class", "gt_meshes"] {
        assert!(dataset.join(folder).is_dir(), "{folder}/ written");
    }

    // The run as written (no recording, which changes no map).
    let output = run_line(run, work, &["--no-recording"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{run}: {stderr}");
    let out = std::fs::read_dir(work)
        .expect("the run output")
        .map(|e| e.expect("entry").path())
        .find(|p| p.join("summary.json").is_file())
        .expect("an output folder with summary.json");
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["frames"], 30, "every frame mapped: {}", summary["frames"]);
    // No flag: the probe finds the camera's noise and the segmenter's borders and takes the
    // settings `--depth camera --masks segmenter` would.
    let sensor = &summary["sensor"];
    assert_eq!(
        (&sensor["depth"], &sensor["masks"], &sensor["instances"]),
        (
            &serde_json::json!("camera"),
            &serde_json::json!("segmenter"),
            &serde_json::json!("per-frame")
        ),
        "{sensor}"
    );
    assert_eq!(
        sensor["profile"]["instance_ids"]["agreeing"], 0,
        "no id labels the same surface in the next frame: {sensor}"
    );
    let objects = &summary["config"]["objects"];
    assert_eq!(
        (&objects["bleed_radius_px"], &objects["mask_border_px"]),
        (&serde_json::json!(4), &serde_json::json!(2)),
        "a segmenter's masks get the trim and the border band: {objects}"
    );
    let config = &summary["config"];
    assert_eq!(
        (
            &config["dataset"]["depth_smoothing"],
            &config["objects"]["box_min_voxel_points"],
        ),
        (&serde_json::json!("bilateral"), &serde_json::json!(3)),
        "a camera's depth is smoothed and lone voxels are left out of the boxes: {config}"
    );
    let sigma = &sensor["profile"]["depth_noise"];
    let at_2m = sigma["sigma_floor_m"].as_f64().unwrap_or(0.0) + 4.0 * sigma["sigma_per_m2"].as_f64().unwrap_or(0.0);
    assert!(
        (0.004..0.009).contains(&at_2m),
        "the probe's σ(2 m) is the Kinect-like camera's 6.1 mm: {sensor}"
    );
    // What the README states of this run: its six objects mapped, the three identical chairs
    // in one subcategory, the figures of the table in docs/ROBUSTNESS.md ("The README's
    // walk-through at a camera's resolution") within the stated margins.
    let metrics = json(&out.join("metrics.json"));
    let mean = &metrics["mean"];
    assert_eq!(
        (&mean["objects"], &mean["missing"]),
        (&serde_json::json!(6), &serde_json::json!(0)),
        "{mean}"
    );
    let figure = |key: &str| mean[key].as_f64().unwrap_or(f64::NAN);
    assert!(
        figure("completion_ratio_5cm_pct") >= WALK_THROUGH_CR_5CM_PCT - 1.0,
        "{mean}"
    );
    assert!(figure("accuracy_cm") <= WALK_THROUGH_ACCURACY_CM * 1.05, "{mean}");
    let categories = json(&out.join("categories.json"));
    let chairs: Vec<usize> = (categories.as_array().into_iter().flatten())
        .filter(|c| c["name"] == "chair")
        .flat_map(|c| c["subcategories"].as_array().into_iter().flatten())
        .map(|s| s["members"].as_array().map_or(0, Vec::len))
        .collect();
    assert_eq!(chairs, [3], "the three chairs share one subcategory: {categories}");
}

/// All objects' C.R. < 5 cm of the walk-through, % (docs/ROBUSTNESS.md; the test allows a point
/// less).
const WALK_THROUGH_CR_5CM_PCT: f64 = 86.0;
/// All objects' accuracy of the walk-through, cm (the test allows 5 % more).
const WALK_THROUGH_ACCURACY_CM: f64 = 1.72;
