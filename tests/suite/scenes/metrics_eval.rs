//! Pipeline test of the reconstruction metrics on a synthetic scene's ground truth: exact copies
//! score only the sampling noise (~0), a shifted copy scores up to its shift, a deleted mesh is
//! reported missing, and the report survives a JSON round trip.

use std::path::{Path, PathBuf};
use std::sync::LazyLock;

use catmap::ObjectId;
use catmap::geometry::mesh::TriangleMesh;
use catmap::metrics::{
    Crop, EvaluationReport, ObjectMetrics, PredictionStatus, SAMPLES_PER_MESH, evaluate_dirs, render_markdown,
};
use catmap::synth::{Preset, SyntheticScene, write_replica_layout};
use nalgebra::Isometry3;

/// The known perturbation of the shifted object, metres.
const SHIFT_M: f32 = 0.03;

/// The small scene's ground truth and the perturbed predictions, written once per test run.
struct Folders {
    gt: PathBuf,
    pred: PathBuf,
    exact: ObjectId,
    shifted: ObjectId,
    deleted: ObjectId,
}

/// Writes the small scene, copies its ground truth as predictions (one shifted up by
/// [`SHIFT_M`], one deleted). Lives in Cargo's per-target temporary folder, replaced each run.
static FOLDERS: LazyLock<Folders> = LazyLock::new(|| {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("metrics_eval");
    if root.exists() {
        std::fs::remove_dir_all(&root).expect("the previous run's folder can be removed");
    }
    let (gt, pred) = (root.join("scene"), root.join("pred"));
    let scene = SyntheticScene::generate(3, Preset::Small).expect("the small preset fits its room");
    write_replica_layout(&scene, &gt, |_, _| {}).expect("writable target folder");
    let ids: Vec<ObjectId> = scene.objects().iter().map(|o| o.id).collect();
    assert!(
        ids.len() >= 4,
        "the small preset has several objects, got {}",
        ids.len()
    );
    let (shifted, deleted, exact) = (ids[0], ids[1], ids[2]);
    std::fs::create_dir_all(&pred).expect("writable target folder");
    for &id in &ids {
        let name = format!("obj_{id}.ply");
        let gt_path = gt.join("gt_meshes").join(&name);
        if id == shifted {
            let moved = read(&gt_path).transformed(&Isometry3::translation(0.0, 0.0, SHIFT_M));
            moved.write_ply(&pred.join(&name)).expect("writable target folder");
        } else if id != deleted {
            std::fs::copy(&gt_path, pred.join(&name)).expect("copy ground truth");
        }
    }
    Folders {
        gt,
        pred,
        exact,
        shifted,
        deleted,
    }
});

fn evaluate(crop: Crop) -> EvaluationReport {
    evaluate_dirs(&FOLDERS.pred, &FOLDERS.gt, crop, 7).expect("valid folders")
}

/// Mean distance between two independent uniform sample sets of one surface, cm: for a
/// Poisson process of density N/A in the plane, the nearest neighbour lies 0.5·√(A/N) away.
fn sampling_noise_cm(id: ObjectId) -> f32 {
    let area = read(&FOLDERS.gt.join("gt_meshes").join(format!("obj_{id}.ply"))).area();
    100.0 * 0.5 * (area / SAMPLES_PER_MESH as f32).sqrt()
}

fn read(path: &Path) -> TriangleMesh {
    TriangleMesh::read_ply(path).expect("ground truth was just written")
}

fn object(report: &EvaluationReport, id: ObjectId) -> &ObjectMetrics {
    report
        .objects
        .iter()
        .find(|o| o.id == id)
        .expect("every ground-truth object is reported")
}

#[test]
fn exact_copies_score_only_sampling_noise_and_full_completion() {
    let report = evaluate(Crop::Paper);
    let f = &*FOLDERS;
    for o in report.objects.iter().filter(|o| o.id != f.shifted && o.id != f.deleted) {
        let s = &o.scores;
        let (acc, comp) = (
            s.accuracy_cm.expect("inside its own box"),
            s.completion_cm.expect("predicted"),
        );
        let noise = sampling_noise_cm(o.id);
        assert!(
            acc < 1.2 * noise && comp < 1.2 * noise,
            "object {} ({}) is its own ground truth (noise {noise} cm): {s:?}",
            o.id,
            o.class_name
        );
        assert_eq!(
            s.completion_ratio_5cm_pct, 100.0,
            "object {} is complete within 5 cm",
            o.id
        );
        assert_ne!(o.class_name, "unknown", "scene.json names object {}'s class", o.id);
    }
}

#[test]
fn a_shifted_copy_scores_up_to_its_shift() {
    let report = evaluate(Crop::Paper);
    let f = &*FOLDERS;
    let shifted = object(&report, f.shifted).scores;
    let (noise, shift_cm) = (sampling_noise_cm(f.shifted), 100.0 * SHIFT_M);
    // Horizontal faces moved 3 cm along their normal, vertical ones slid within their plane:
    // the mean distance lies between the sampling noise and the shift.
    let completion = shifted.completion_cm.expect("the shifted copy is present");
    assert!(
        completion > 1.5 * noise && completion < shift_cm + 0.3,
        "completion {completion} cm for a {shift_cm} cm shift"
    );
    let accuracy = shifted.accuracy_cm.expect("most of the shifted copy stays in the box");
    assert!(
        accuracy > 1.5 * noise && accuracy < shift_cm + 0.3,
        "accuracy {accuracy} cm for a {shift_cm} cm shift"
    );
    assert!(
        shifted.accuracy_samples < SAMPLES_PER_MESH,
        "the top of the shifted copy leaves the box: {shifted:?}"
    );
    assert_eq!(
        shifted.completion_ratio_5cm_pct, 100.0,
        "every point moved by at most 3 cm < 5 cm"
    );
    let exact = object(&report, f.exact).scores;
    assert!(
        shifted.completion_ratio_1cm_pct < exact.completion_ratio_1cm_pct - 10.0,
        "fewer points within 1 cm: {shifted:?}"
    );
}

#[test]
fn a_deleted_prediction_is_reported_missing_and_counted() {
    let report = evaluate(Crop::Paper);
    let deleted = object(&report, FOLDERS.deleted).scores;
    assert_eq!(
        deleted.status,
        PredictionStatus::Missing,
        "object {} has no prediction file",
        FOLDERS.deleted
    );
    assert_eq!(
        (
            deleted.accuracy_cm,
            deleted.completion_cm,
            deleted.completion_ratio_5cm_pct
        ),
        (None, None, 0.0)
    );
    assert_eq!(report.mean.missing, 1, "one object is missing");
    assert_eq!(
        report.mean.objects,
        report.objects.len(),
        "every ground-truth object is counted"
    );
    let deleted = object(&report, FOLDERS.deleted);
    let seen = deleted
        .observed_surface_fraction
        .expect("catmap's scene.json states the observed fraction");
    let table = render_markdown(&report);
    assert!(
        table.contains(&format!(
            "| {} | {} | {:.1} | missing | missing | 0.0 | 0.0 |",
            FOLDERS.deleted,
            deleted.class_name,
            100.0 * seen
        )),
        "{table}"
    );
}

#[test]
fn the_vmap_crop_scores_exact_copies_the_same_way() {
    let report = evaluate(Crop::Vmap);
    let f = &*FOLDERS;
    for o in report.objects.iter().filter(|o| o.id != f.shifted && o.id != f.deleted) {
        let noise = sampling_noise_cm(o.id);
        assert!(
            o.scores.completion_cm.expect("predicted") < 1.2 * noise,
            "object {}: {:?}",
            o.id,
            o.scores
        );
        assert_eq!(
            o.scores.accuracy_samples, SAMPLES_PER_MESH,
            "an exact copy lies inside the enlarged box"
        );
    }
    assert_eq!(report.settings.crop, Crop::Vmap);
}

#[test]
fn the_report_round_trips_through_a_json_file() {
    let report = evaluate(Crop::Paper);
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("report.json");
    let text = serde_json::to_string_pretty(&report).expect("serialisable");
    catmap::atomic_file::write_atomic(&path, text.as_bytes()).expect("writable temp dir");
    let back: EvaluationReport =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("readable")).expect("parses");
    assert_eq!(back, report, "the JSON file holds the whole report");
}
