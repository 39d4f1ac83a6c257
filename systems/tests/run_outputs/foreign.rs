//! Issue 16: a run on a dataset catmap did not write keeps every output (see the binary's doc).

use super::*;

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

/// `catmap run` on the foreign dataset `work/scene` (every third frame) into `work/out`.
fn run_foreign(work: &Path, camera: &str) -> Output {
    catmap()
        .env("RUST_LOG", "info")
        .arg("run")
        .arg("--dataset")
        .arg(work.join("scene"))
        .args(["--format", "replica", "--camera", camera])
        .arg("--config")
        .arg(work.join("config.toml"))
        .args(["--stride", "3", "--out"])
        .arg(work.join("out"))
        .output()
        .expect("catmap runs")
}

/// Object id and class name of every object in `out/metrics.json`.
fn scored_classes(out: &Path) -> Vec<(u64, String)> {
    json(&out.join("metrics.json"))["objects"]
        .as_array()
        .expect("objects scored")
        .iter()
        .map(|o| {
            (
                o["id"].as_u64().expect("id"),
                o["class_name"].as_str().expect("name").to_owned(),
            )
        })
        .collect()
}

/// Rewrites every class image of the Replica-layout `scene`: class `from` becomes `to`.
fn relabel_classes(scene: &Path, changes: &[(u16, u16)]) {
    let relabel = |c: u16| changes.iter().find(|(from, _)| *from == c).map_or(c, |(_, to)| *to);
    for entry in std::fs::read_dir(scene.join("semantic_class")).expect("class images") {
        let path = entry.expect("entry").path();
        match image::open(&path).expect("class image decodes") {
            image::DynamicImage::ImageLuma8(mut grey) => {
                grey.pixels_mut()
                    .for_each(|p| p.0[0] = relabel(u16::from(p.0[0])) as u8);
                grey.save(&path).expect("class image written");
            }
            image::DynamicImage::ImageLuma16(mut grey) => {
                grey.pixels_mut().for_each(|p| p.0[0] = relabel(p.0[0]));
                grey.save(&path).expect("class image written");
            }
            other => panic!("{}: a grey class image, not {:?}", path.display(), other.color()),
        }
    }
}

fn run_on_a_foreign_dataset(kind: ForeignSceneFile) {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    let (classes, camera) = make_foreign(work, kind);
    let output = run_foreign(work, &camera);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{kind:?}: the run exits 0: {stderr}");
    let out = work.join("out");
    assert_outputs_whole(&out);
    let scored = scored_classes(&out);
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

#[test]
fn a_replica_dataset_catmap_did_not_write_names_replicas_classes_and_its_own_info_file_wins() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    small_scene(work);
    let (classes, camera) = make_foreign(work, ForeignSceneFile::Absent);
    let scene = work.join("scene");
    relabel_classes(&scene, &[(78, 76), (47, 44)]);
    std::fs::create_dir(scene.join("habitat")).expect("habitat folder");
    let info = r#"{"classes": [{"id": 80, "name": "dining-table"}], "objects": [], "id_to_label": []}"#;
    std::fs::write(scene.join("habitat/info_semantic.json"), info).expect("info written");
    let output = run_foreign(work, &camera);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the run exits 0: {stderr}");
    let renamed = |name: &str| {
        match name {
            "stool" => "sofa",
            "lamp" => "indoor-plant",
            "table" => "dining-table",
            other => other,
        }
        .to_owned()
    };
    let expected: Vec<(u64, String)> = classes.iter().map(|(id, name)| (*id, renamed(name))).collect();
    assert!(
        expected.iter().any(|(_, n)| n == "sofa"),
        "the scene has a stool to relabel: {classes:?}"
    );
    assert_eq!(
        scored_classes(&work.join("out")),
        expected,
        "metrics.json names Replica's classes"
    );
    let summary = json(&work.join("out/summary.json"));
    let summary_names: Vec<&str> = summary["objects"]
        .as_array()
        .expect("objects")
        .iter()
        .map(|o| o["class_name"].as_str().expect("name"))
        .collect();
    assert!(
        summary_names.contains(&"sofa") && summary_names.contains(&"dining-table"),
        "{summary_names:?}"
    );
}
