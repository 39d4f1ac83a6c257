//! Evaluating a folder of predicted object meshes against the ground truth
//! ([`GroundTruth`]: `gt_meshes/obj_{id}.ply`, the objects' classes).
//!
//! ```text
//! pred_dir/obj_{id}.ply           prediction (or pred_dir/meshes/obj_{id}.ply)
//! ```
//!
//! Every ground-truth object is scored; a prediction without ground truth is ignored. Objects
//! are scored in parallel, each with its own random stream, so the figures do not depend on
//! the thread count.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::crop::Crop;
use super::ground_truth::{GroundTruth, ObjectClasses, mesh_file_name, parse_mesh_file_name};
use super::object_matching::{GeometryPairing, Pairing, pair, vote};
use super::object_scores::score_object;
use super::report::{EvalSettings, EvaluationReport, ObjectMetrics};
use crate::error::{CatmapError, Result};
use crate::geometry::mesh::TriangleMesh;
use crate::ids::ObjectId;
use crate::rng::{RngStream, seeded_rng};

/// Scores `pred_dir` against the ground truth of `gt_dir` with the default 10 000 samples per
/// mesh; classes come only from catmap's own `scene.json` (see [`GroundTruth::load`]).
pub fn evaluate_dirs(pred_dir: &Path, gt_dir: &Path, crop: Crop, seed: u64) -> Result<EvaluationReport> {
    let ground_truth = GroundTruth::load(gt_dir, &ObjectClasses::new())?;
    let settings = EvalSettings {
        crop,
        seed,
        ..EvalSettings::default()
    };
    evaluate_ground_truth(pred_dir, &ground_truth, &settings)
}

/// Scores every object of `ground_truth` against its prediction in `pred_dir` (see the module
/// doc). Errors when the prediction folder is missing or a mesh cannot be read or parsed (the
/// error names the file); a missing prediction is reported, not an error.
pub fn evaluate_ground_truth(
    pred_dir: &Path,
    ground_truth: &GroundTruth,
    settings: &EvalSettings,
) -> Result<EvaluationReport> {
    if !pred_dir.is_dir() {
        return Err(CatmapError::layout(pred_dir, "prediction folder does not exist"));
    }
    let pairing = match settings.pairing {
        Pairing::ById => None,
        Pairing::Geometry => Some(pair_by_geometry(pred_dir, ground_truth, settings.seed)?),
    };
    let objects = ground_truth
        .entries
        .par_iter()
        .map(|entry| -> Result<ObjectMetrics> {
            let gt = TriangleMesh::read_ply(&entry.mesh_path)?;
            let paired = pairing.as_ref().map(|p| p.paired.get(&entry.id).copied());
            let predicted_id = match paired {
                None => Some(entry.id),
                Some(pair) => pair.map(|(prediction, _)| prediction),
            };
            let prediction = predicted_id
                .and_then(|id| prediction_path(pred_dir, id))
                .map(|p| TriangleMesh::read_ply(&p))
                .transpose()?;
            let mut rng = seeded_rng(settings.seed, RngStream::Object(entry.id));
            let scores = score_object(
                &gt,
                prediction.as_ref(),
                settings.crop,
                settings.samples_per_mesh,
                &mut rng,
            )
            .map_err(|e| CatmapError::layout(&entry.mesh_path, format!("unusable ground truth: {e}")))?;
            Ok(ObjectMetrics {
                id: entry.id,
                class: entry.class,
                class_name: entry.class_name.clone(),
                observed_surface_fraction: entry.observed_surface_fraction,
                prediction: paired.flatten().map(|(prediction, _)| prediction),
                purity_pct: paired.flatten().map(|(_, purity)| 100.0 * purity),
                scores,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let mut report = EvaluationReport::new(*settings, objects);
    report.extra_predictions = pairing.map(|p| p.extra).unwrap_or_default();
    Ok(report)
}

/// Every prediction of `pred_dir` (`obj_{id}.ply`, or in `meshes/`) paired with the ground
/// truth by geometry.
fn pair_by_geometry(pred_dir: &Path, ground_truth: &GroundTruth, seed: u64) -> Result<GeometryPairing> {
    let mut ids: Vec<ObjectId> = Vec::new();
    for dir in [pred_dir.to_owned(), pred_dir.join("meshes")] {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        ids.extend(entries.filter_map(|e| e.ok()?.file_name().to_str().and_then(parse_mesh_file_name)));
    }
    ids.sort_unstable();
    ids.dedup();
    let read = |id: ObjectId, path: Option<PathBuf>| -> Result<Option<(ObjectId, TriangleMesh)>> {
        path.map(|p| Ok((id, TriangleMesh::read_ply(&p)?))).transpose()
    };
    let predictions = ids
        .par_iter()
        .map(|&id| read(id, prediction_path(pred_dir, id)))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect::<Vec<_>>();
    let truths = ground_truth
        .entries
        .par_iter()
        .map(|e| read(e.id, Some(e.mesh_path.clone())))
        .collect::<Result<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect::<Vec<_>>();
    Ok(pair(&vote(&predictions, &truths, seed)?))
}

/// The predicted mesh of object `id`: `pred_dir/obj_{id}.ply`, else `pred_dir/meshes/obj_{id}.ply`.
pub fn prediction_path(pred_dir: &Path, id: ObjectId) -> Option<PathBuf> {
    let name = mesh_file_name(id);
    [pred_dir.join(&name), pred_dir.join("meshes").join(&name)]
        .into_iter()
        .find(|p| p.is_file())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::ground_truth::{ClassLabel, UNKNOWN_CLASS};
    use crate::synth::primitives::cuboid;

    fn write(path: &Path, mesh: &TriangleMesh) {
        mesh.write_ply(path).expect("writable temp dir");
    }

    #[test]
    fn flat_folders_are_scored_with_missing_predictions_reported() {
        let (gt, pred) = (
            tempfile::tempdir().expect("temp dir"),
            tempfile::tempdir().expect("temp dir"),
        );
        let cube = cuboid([0.0; 3], [0.3; 3]);
        write(&gt.path().join("obj_2.ply"), &cube);
        write(&gt.path().join("obj_10.ply"), &cube);
        write(&pred.path().join("meshes/obj_10.ply"), &cube);
        let report = evaluate_dirs(pred.path(), gt.path(), Crop::Paper, 1).expect("valid folders");
        let ids: Vec<u32> = report.objects.iter().map(|o| o.id.0).collect();
        assert_eq!(ids, [2, 10], "objects in numeric id order");
        assert_eq!(
            report.objects[0].scores.status,
            crate::metrics::PredictionStatus::Missing,
            "obj_2 has no prediction"
        );
        assert!(
            report.objects[1]
                .scores
                .completion_cm
                .expect("obj_10 predicted in meshes/")
                < 1.0
        );
        assert_eq!(report.objects[1].class_name, UNKNOWN_CLASS);
        assert_eq!(report.mean.missing, 1);
    }

    #[test]
    fn known_classes_group_the_report() {
        let gt = tempfile::tempdir().expect("temp dir");
        let cube = cuboid([0.0; 3], [0.3; 3]);
        write(&gt.path().join("gt_meshes/obj_1.ply"), &cube);
        write(&gt.path().join("gt_meshes/obj_2.ply"), &cube);
        std::fs::write(gt.path().join("scene.json"), r#"{"objects": [{"name": "x"}]}"#).expect("write");
        let label = ClassLabel {
            class: crate::ClassId(20),
            name: "chair".to_owned(),
        };
        let known = ObjectClasses::from([(ObjectId(1), label.clone()), (ObjectId(2), label)]);
        let truth = GroundTruth::load(gt.path(), &known).expect("the meshes suffice");
        let report = evaluate_ground_truth(gt.path(), &truth, &EvalSettings::default()).expect("valid folders");
        assert_eq!(report.classes.keys().collect::<Vec<_>>(), ["chair"]);
        assert_eq!(report.classes["chair"].objects, 2);
    }

    #[test]
    fn an_unreadable_ground_truth_mesh_is_named_in_the_error() {
        let gt = tempfile::tempdir().expect("temp dir");
        write(&gt.path().join("gt_meshes/obj_1.ply"), &cuboid([0.0; 3], [0.3; 3]));
        std::fs::write(gt.path().join("gt_meshes/obj_2.ply"), b"ply\nnot a mesh").expect("write");
        let err = evaluate_dirs(gt.path(), gt.path(), Crop::Paper, 0).expect_err("obj_2 is garbage");
        assert!(err.to_string().contains("obj_2.ply"), "{err}");
    }

    #[test]
    fn a_missing_prediction_folder_is_named_in_the_error() {
        let dir = tempfile::tempdir().expect("temp dir");
        write(&dir.path().join("obj_1.ply"), &cuboid([0.0; 3], [0.3; 3]));
        let missing = dir.path().join("nope");
        let err = evaluate_dirs(&missing, dir.path(), Crop::Paper, 0).expect_err("no prediction folder");
        assert!(err.to_string().contains("nope"), "{err}");
    }
}
