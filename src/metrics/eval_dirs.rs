//! Evaluating a folder of predicted object meshes against a folder of ground-truth meshes.
//!
//! ```text
//! gt_dir/gt_meshes/obj_{id}.ply   ground truth (or gt_dir/obj_{id}.ply when there is no gt_meshes/)
//! gt_dir/scene.json               optional: objects[].id, class, class_name
//! pred_dir/obj_{id}.ply           prediction (or pred_dir/meshes/obj_{id}.ply)
//! ```
//!
//! Every ground-truth object is scored; a prediction without ground truth is ignored. Objects
//! are scored in parallel, each with its own random stream, so the figures do not depend on
//! the thread count.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Deserialize;

use super::crop::Crop;
use super::object_scores::score_object;
use super::report::{EvalSettings, EvaluationReport, ObjectMetrics};
use crate::classes::replica_name;
use crate::error::{CatmapError, Result};
use crate::ids::{ClassId, ObjectId};
use crate::mesh::TriangleMesh;
use crate::rng::{RngStream, seeded_rng};

/// Class name of objects whose class is not known.
pub const UNKNOWN_CLASS: &str = "unknown";

/// One ground-truth object found on disk.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GroundTruthEntry {
    /// Instance id (from the file name `obj_{id}.ply`).
    pub id: ObjectId,
    /// Semantic class from `scene.json`, when listed.
    pub class: Option<ClassId>,
    /// Class name from `scene.json`, else the Replica name of the class, else `unknown`.
    pub class_name: String,
    /// The mesh file.
    pub mesh_path: PathBuf,
}

/// [`evaluate_dirs_with`] with the default 10 000 samples per mesh.
pub fn evaluate_dirs(pred_dir: &Path, gt_dir: &Path, crop: Crop, seed: u64) -> Result<EvaluationReport> {
    evaluate_dirs_with(
        pred_dir,
        gt_dir,
        &EvalSettings {
            crop,
            seed,
            ..EvalSettings::default()
        },
    )
}

/// Scores every ground-truth object of `gt_dir` against its prediction in `pred_dir` (see the
/// module doc). Errors when a folder is missing, `gt_dir` holds no `obj_{id}.ply`, or a file
/// cannot be read or parsed; a missing prediction is reported, not an error.
pub fn evaluate_dirs_with(pred_dir: &Path, gt_dir: &Path, settings: &EvalSettings) -> Result<EvaluationReport> {
    if !pred_dir.is_dir() {
        return Err(CatmapError::layout(pred_dir, "prediction folder does not exist"));
    }
    let entries = list_ground_truth(gt_dir)?;
    let objects = entries
        .par_iter()
        .map(|entry| -> Result<ObjectMetrics> {
            let gt = TriangleMesh::read_ply(&entry.mesh_path)?;
            let prediction = prediction_path(pred_dir, entry.id)
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
                scores,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(EvaluationReport::new(*settings, objects))
}

/// The predicted mesh of object `id`: `pred_dir/obj_{id}.ply`, else `pred_dir/meshes/obj_{id}.ply`.
pub fn prediction_path(pred_dir: &Path, id: ObjectId) -> Option<PathBuf> {
    let name = mesh_file_name(id);
    [pred_dir.join(&name), pred_dir.join("meshes").join(&name)]
        .into_iter()
        .find(|p| p.is_file())
}

/// `obj_{id}.ply`.
pub fn mesh_file_name(id: ObjectId) -> String {
    format!("obj_{id}.ply")
}

/// The ground-truth objects of `gt_dir`, in id order, with their classes (see the module doc).
pub fn list_ground_truth(gt_dir: &Path) -> Result<Vec<GroundTruthEntry>> {
    if !gt_dir.is_dir() {
        return Err(CatmapError::layout(gt_dir, "ground-truth folder does not exist"));
    }
    let nested = gt_dir.join("gt_meshes");
    let mesh_dir = if nested.is_dir() { nested } else { gt_dir.to_owned() };
    let classes = read_scene_classes(&gt_dir.join("scene.json"))?;
    let mut ids: Vec<ObjectId> = std::fs::read_dir(&mesh_dir)
        .map_err(|e| CatmapError::io(&mesh_dir, e))?
        .filter_map(|entry| entry.ok()?.file_name().to_str().and_then(parse_mesh_file_name))
        .collect();
    ids.sort_unstable();
    ids.dedup();
    if ids.is_empty() {
        return Err(CatmapError::layout(
            &mesh_dir,
            "no ground-truth meshes named obj_{id}.ply",
        ));
    }
    Ok(ids
        .into_iter()
        .map(|id| {
            let listed = classes.iter().find(|c| c.id == id.0);
            let class = listed.and_then(|c| c.class).map(ClassId);
            let class_name = listed
                .and_then(|c| c.class_name.clone())
                .or_else(|| class.and_then(replica_name).map(str::to_owned))
                .unwrap_or_else(|| UNKNOWN_CLASS.to_owned());
            GroundTruthEntry {
                id,
                class,
                class_name,
                mesh_path: mesh_dir.join(mesh_file_name(id)),
            }
        })
        .collect())
}

/// The id in a file name `obj_{id}.ply`.
fn parse_mesh_file_name(name: &str) -> Option<ObjectId> {
    name.strip_prefix("obj_")?
        .strip_suffix(".ply")?
        .parse()
        .ok()
        .map(ObjectId)
}

/// What `scene.json` says about one object (other fields are ignored).
#[derive(Debug, Deserialize)]
struct SceneObjectClass {
    id: u32,
    #[serde(default)]
    class: Option<u32>,
    #[serde(default)]
    class_name: Option<String>,
}

#[derive(Debug, Deserialize)]
struct SceneClasses {
    #[serde(default)]
    objects: Vec<SceneObjectClass>,
}

/// The object classes listed in `path`; none when the file does not exist.
fn read_scene_classes(path: &Path) -> Result<Vec<SceneObjectClass>> {
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
    let scene: SceneClasses = serde_json::from_str(&text).map_err(|e| CatmapError::Parse {
        path: path.to_owned(),
        line: e.line(),
        reason: e.to_string(),
    })?;
    Ok(scene.objects)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::primitives::cuboid;

    fn write(path: &Path, mesh: &TriangleMesh) {
        mesh.write_ply(path).expect("writable temp dir");
    }

    #[test]
    fn flat_folders_without_scene_json_have_unknown_classes() {
        let (gt, pred) = (
            tempfile::tempdir().expect("temp dir"),
            tempfile::tempdir().expect("temp dir"),
        );
        let cube = cuboid([0.0; 3], [0.3; 3]);
        write(&gt.path().join("obj_2.ply"), &cube);
        write(&gt.path().join("obj_10.ply"), &cube);
        std::fs::write(gt.path().join("notes.txt"), "ignored").expect("write");
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
    fn scene_json_names_the_classes() {
        let gt = tempfile::tempdir().expect("temp dir");
        write(&gt.path().join("gt_meshes/obj_1.ply"), &cuboid([0.0; 3], [0.2; 3]));
        write(&gt.path().join("gt_meshes/obj_2.ply"), &cuboid([0.0; 3], [0.2; 3]));
        let scene =
            r#"{"seed": 0, "objects": [{"id": 1, "class": 20, "class_name": "my chair"}, {"id": 2, "class": 80}]}"#;
        std::fs::write(gt.path().join("scene.json"), scene).expect("write");
        let entries = list_ground_truth(gt.path()).expect("valid folder");
        assert_eq!(entries[0].class_name, "my chair", "class_name wins");
        assert_eq!(
            (entries[1].class, entries[1].class_name.as_str()),
            (Some(ClassId(80)), "table"),
            "else the Replica name"
        );
    }

    #[test]
    fn missing_folders_and_empty_ground_truth_are_named_in_errors() {
        let dir = tempfile::tempdir().expect("temp dir");
        let missing = dir.path().join("nope");
        let err = evaluate_dirs(&missing, dir.path(), Crop::Paper, 0).expect_err("no prediction folder");
        assert!(err.to_string().contains("nope"), "{err}");
        let err = evaluate_dirs(dir.path(), &missing, Crop::Paper, 0).expect_err("no ground-truth folder");
        assert!(err.to_string().contains("nope"), "{err}");
        let err = evaluate_dirs(dir.path(), dir.path(), Crop::Paper, 0).expect_err("no meshes");
        assert!(err.to_string().contains("obj_{id}.ply"), "{err}");
    }

    #[test]
    fn mesh_file_names_parse_only_object_ids() {
        assert_eq!(parse_mesh_file_name("obj_12.ply"), Some(ObjectId(12)));
        assert_eq!(parse_mesh_file_name("obj_x.ply"), None);
        assert_eq!(parse_mesh_file_name("obj_3.ply.tmp"), None);
    }
}
