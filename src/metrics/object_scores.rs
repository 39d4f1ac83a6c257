//! The reconstruction scores of one object (METHOD.md §6): accuracy, completion and completion
//! ratios from uniform surface samples of the predicted and the ground-truth mesh.
//!
//! - accuracy \[cm\] = mean distance from each (cropped) predicted sample to the nearest
//!   ground-truth sample;
//! - completion \[cm\] = mean distance from each ground-truth sample to the nearest predicted
//!   sample;
//! - completion ratio \[%\] = share of ground-truth samples within 5 cm (and 1 cm) of a
//!   predicted sample.
//!
//! The crop ([`Crop`]) uses the minimum-volume oriented box of the ground-truth vertices.

use nalgebra::Point3;
use rand::Rng;
use serde::{Deserialize, Serialize};

use super::crop::Crop;
use crate::error::Result;
use crate::geometry::mesh::TriangleMesh;
use crate::geometry::nearest::PointIndex;
use crate::geometry::oriented_box::fit_minimum_volume_box;

/// Surface samples per mesh (METHOD.md §6).
pub const SAMPLES_PER_MESH: usize = 10_000;
/// A ground-truth sample counts as completed within this distance, metres (C.R.).
pub const COMPLETION_THRESHOLD_M: f32 = 0.05;
/// The finer completion threshold vMAP also reports, metres.
pub const FINE_COMPLETION_THRESHOLD_M: f32 = 0.01;

/// Whether an object had a prediction to score.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PredictionStatus {
    /// A mesh with surface area was predicted.
    Reconstructed,
    /// No mesh, an empty mesh, or one without finite surface area.
    Missing,
}

/// Scores of one object. Distances are centimetres, ratios percent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ObjectScores {
    /// Whether there was a prediction.
    pub status: PredictionStatus,
    /// Mean predicted → ground-truth distance over the cropped predicted samples, cm; `None`
    /// when missing or when no predicted sample lies in the crop.
    pub accuracy_cm: Option<f32>,
    /// Mean ground-truth → predicted distance, cm; `None` (infinite) when missing or when no
    /// predicted sample survives the crop.
    pub completion_cm: Option<f32>,
    /// Share of ground-truth samples within 5 cm of the prediction, % (0 when missing). Read
    /// also under its earlier name `completion_ratio_pct`.
    #[serde(alias = "completion_ratio_pct")]
    pub completion_ratio_5cm_pct: f32,
    /// Share of ground-truth samples within 1 cm of the prediction, % (0 when missing).
    pub completion_ratio_1cm_pct: f32,
    /// Predicted samples inside the crop (those accuracy is averaged over).
    pub accuracy_samples: usize,
    /// Share of those predicted samples farther than 5 cm from the ground truth, % (surface
    /// that is not there: a table left solid under its top); `None` when accuracy is.
    #[serde(default)]
    pub accuracy_far_5cm_pct: Option<f32>,
}

impl ObjectScores {
    /// The scores of an object without prediction.
    pub fn missing() -> Self {
        Self {
            status: PredictionStatus::Missing,
            accuracy_cm: None,
            completion_cm: None,
            completion_ratio_5cm_pct: 0.0,
            completion_ratio_1cm_pct: 0.0,
            accuracy_samples: 0,
            accuracy_far_5cm_pct: None,
        }
    }
}

/// Scores `prediction` against the ground-truth mesh `gt`, drawing `samples` points on each
/// (ground truth first, then prediction) with `rng`.
///
/// A missing, empty or area-less prediction gives [`ObjectScores::missing`] (a missing or empty
/// one without looking at the ground truth); predicted samples with non-finite coordinates are
/// dropped. Errors only on an unusable ground truth (no vertices, no area, or non-finite
/// vertices).
pub fn score_object<R: Rng + ?Sized>(
    gt: &TriangleMesh,
    prediction: Option<&TriangleMesh>,
    crop: Crop,
    samples: usize,
    rng: &mut R,
) -> Result<ObjectScores> {
    let Some(predicted) = prediction.filter(|m| !m.is_empty()) else {
        return Ok(ObjectScores::missing());
    };
    let gt_box = fit_minimum_volume_box(&gt.vertices)?;
    let gt_samples = gt.sample_surface(samples, rng)?;
    let Ok(mut pred_samples) = predicted.sample_surface(samples, rng) else {
        return Ok(ObjectScores::missing());
    };
    pred_samples.retain(|p| p.coords.iter().all(|x| x.is_finite()));
    if pred_samples.is_empty() {
        return Ok(ObjectScores::missing());
    }
    let cropped = crop.apply(&gt_box, pred_samples, gt_samples);
    let accuracy = accuracy_distances(&cropped.ground_truth, &cropped.prediction_for_accuracy)?;
    let accuracy_cm = accuracy.as_deref().map(|d| 100.0 * mean(d));
    let accuracy_far_5cm_pct = accuracy
        .as_deref()
        .map(|d| 100.0 - percent_within(d, COMPLETION_THRESHOLD_M));
    let mut scores = ObjectScores {
        status: PredictionStatus::Reconstructed,
        accuracy_cm,
        completion_cm: None,
        completion_ratio_5cm_pct: 0.0,
        completion_ratio_1cm_pct: 0.0,
        accuracy_samples: cropped.prediction_for_accuracy.len(),
        accuracy_far_5cm_pct,
    };
    if cropped.prediction_for_completion.is_empty() || cropped.ground_truth.is_empty() {
        return Ok(scores);
    }
    let distances = PointIndex::new(&cropped.prediction_for_completion)?.nearest_distances(&cropped.ground_truth);
    scores.completion_cm = Some(100.0 * mean(&distances));
    scores.completion_ratio_5cm_pct = percent_within(&distances, COMPLETION_THRESHOLD_M);
    scores.completion_ratio_1cm_pct = percent_within(&distances, FINE_COMPLETION_THRESHOLD_M);
    Ok(scores)
}

/// The distance from each of `queries` to `reference`, metres; `None` when either set is empty.
fn accuracy_distances(reference: &[Point3<f32>], queries: &[Point3<f32>]) -> Result<Option<Vec<f32>>> {
    if reference.is_empty() || queries.is_empty() {
        return Ok(None);
    }
    Ok(Some(PointIndex::new(reference)?.nearest_distances(queries)))
}

/// Mean of `values` in f64 (0 for none).
fn mean(values: &[f32]) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    (values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64) as f32
}

/// Percentage of `distances` strictly below `threshold_m`.
fn percent_within(distances: &[f32], threshold_m: f32) -> f32 {
    if distances.is_empty() {
        return 0.0;
    }
    100.0 * distances.iter().filter(|&&d| d < threshold_m).count() as f32 / distances.len() as f32
}

#[cfg(test)]
#[path = "object_scores_tests.rs"]
mod tests;
