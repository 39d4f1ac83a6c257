//! A scene's evaluation: per-object scores, per-class summaries and the mean over objects.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::crop::Crop;
use super::object_matching::Pairing;
use super::object_scores::{ObjectScores, PredictionStatus, SAMPLES_PER_MESH};
use crate::ids::{ClassId, ObjectId};

/// How a scene is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EvalSettings {
    /// Which samples are cropped to the ground-truth box.
    pub crop: Crop,
    /// Seed of the surface sampling; object `id` samples from stream `(seed, id)`.
    pub seed: u64,
    /// Surface samples per mesh.
    pub samples_per_mesh: usize,
    /// How predictions are paired with ground-truth objects: by id, or by geometry when the
    /// run's ids are not the dataset's ([`super::object_matching`]).
    pub pairing: Pairing,
}

impl Default for EvalSettings {
    fn default() -> Self {
        Self {
            crop: Crop::Paper,
            seed: 0,
            samples_per_mesh: SAMPLES_PER_MESH,
            pairing: Pairing::ById,
        }
    }
}

/// The scores of one ground-truth object, with its identity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ObjectMetrics {
    /// Instance id of the ground-truth object.
    pub id: ObjectId,
    /// Semantic class, when known.
    pub class: Option<ClassId>,
    /// Class name used to group objects (`unknown` when not known).
    pub class_name: String,
    /// Share of the object's surface some frame saw, when the ground truth says (catmap's own
    /// `scene.json`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub observed_surface_fraction: Option<f32>,
    /// The prediction paired with it by geometry ([`Pairing::Geometry`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub prediction: Option<ObjectId>,
    /// That prediction's purity: the share of its surface near some ground-truth object that is
    /// near this one, % ([`super::object_matching`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub purity_pct: Option<f32>,
    /// The scores.
    pub scores: ObjectScores,
}

/// Aggregate of a set of objects. Distances average over the objects that have them (missing
/// objects have no completion, i.e. an infinite one, and are counted in `missing` instead);
/// completion ratios average over all objects, a missing object counting 0 %.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MetricSummary {
    /// Objects in the set.
    pub objects: usize,
    /// Objects without prediction.
    pub missing: usize,
    /// Mean accuracy over the objects with one, cm.
    pub accuracy_cm: Option<f32>,
    /// Mean completion over the objects with one, cm.
    pub completion_cm: Option<f32>,
    /// Mean 5 cm completion ratio over all objects, % (read also as `completion_ratio_pct`).
    #[serde(alias = "completion_ratio_pct")]
    pub completion_ratio_5cm_pct: f32,
    /// Mean 1 cm completion ratio over all objects, %.
    pub completion_ratio_1cm_pct: f32,
}

impl MetricSummary {
    /// Summarises `objects`.
    pub fn of<'a>(objects: impl IntoIterator<Item = &'a ObjectMetrics>) -> Self {
        let scores: Vec<&ObjectScores> = objects.into_iter().map(|o| &o.scores).collect();
        let ratio_mean = |ratio: fn(&ObjectScores) -> f32| mean(scores.iter().map(|s| ratio(s))).unwrap_or(0.0);
        Self {
            objects: scores.len(),
            missing: scores.iter().filter(|s| s.status == PredictionStatus::Missing).count(),
            accuracy_cm: mean(scores.iter().filter_map(|s| s.accuracy_cm)),
            completion_cm: mean(scores.iter().filter_map(|s| s.completion_cm)),
            completion_ratio_5cm_pct: ratio_mean(|s| s.completion_ratio_5cm_pct),
            completion_ratio_1cm_pct: ratio_mean(|s| s.completion_ratio_1cm_pct),
        }
    }
}

/// Mean of `values` (in f64), `None` for none.
fn mean(values: impl Iterator<Item = f32>) -> Option<f32> {
    let (sum, count) = values.fold((0.0_f64, 0usize), |(s, n), v| (s + f64::from(v), n + 1));
    (count > 0).then(|| (sum / count as f64) as f32)
}

/// Everything an evaluation found, ready for JSON or [`super::render_markdown`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EvaluationReport {
    /// How the scene was evaluated.
    pub settings: EvalSettings,
    /// Per object, in id order.
    pub objects: Vec<ObjectMetrics>,
    /// Per class name, in name order.
    pub classes: BTreeMap<String, MetricSummary>,
    /// Over all objects.
    pub mean: MetricSummary,
    /// Predictions paired with no ground-truth object ([`Pairing::Geometry`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub extra_predictions: Vec<ObjectId>,
}

/// A group of an evaluation's objects.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObjectGroup {
    /// Every object.
    All,
    /// Objects whose class has more than one object (those that can share a category field).
    Repeated,
    /// Objects alone in their class.
    Unique,
}

impl EvaluationReport {
    /// The summary over `group`'s objects.
    pub fn group_summary(&self, group: ObjectGroup) -> MetricSummary {
        let repeated = |o: &&ObjectMetrics| self.classes.get(&o.class_name).is_some_and(|c| c.objects > 1);
        match group {
            ObjectGroup::All => self.mean,
            ObjectGroup::Repeated => MetricSummary::of(self.objects.iter().filter(repeated)),
            ObjectGroup::Unique => MetricSummary::of(self.objects.iter().filter(|o| !repeated(o))),
        }
    }

    /// Sorts `objects` by id and aggregates them per class and overall.
    pub fn new(settings: EvalSettings, mut objects: Vec<ObjectMetrics>) -> Self {
        objects.sort_by_key(|o| o.id);
        let mut by_class: BTreeMap<String, Vec<&ObjectMetrics>> = BTreeMap::new();
        for o in &objects {
            by_class.entry(o.class_name.clone()).or_default().push(o);
        }
        let classes = by_class
            .into_iter()
            .map(|(name, members)| (name, MetricSummary::of(members)))
            .collect();
        let mean = MetricSummary::of(&objects);
        Self {
            settings,
            objects,
            classes,
            mean,
            extra_predictions: Vec::new(),
        }
    }
}

/// A report of reconstructed objects `(id, class name, completion in cm)`, every other score
/// fixed (accuracy 2 cm, C.R. 90 % / 30 %): the tests' fixture.
#[cfg(test)]
pub(crate) fn report_of_completions(completions: &[(u32, &str, f32)]) -> EvaluationReport {
    let objects = completions
        .iter()
        .map(|&(id, class, completion)| ObjectMetrics {
            id: ObjectId(id),
            class: None,
            class_name: class.to_owned(),
            observed_surface_fraction: None,
            prediction: None,
            purity_pct: None,
            scores: ObjectScores {
                status: PredictionStatus::Reconstructed,
                accuracy_cm: Some(2.0),
                completion_cm: Some(completion),
                completion_ratio_5cm_pct: 90.0,
                completion_ratio_1cm_pct: 30.0,
                accuracy_samples: 100,
                accuracy_far_5cm_pct: Some(1.0),
            },
        })
        .collect();
    EvaluationReport::new(EvalSettings::default(), objects)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn object(id: u32, class_name: &str, scores: ObjectScores) -> ObjectMetrics {
        ObjectMetrics {
            id: ObjectId(id),
            class: None,
            class_name: class_name.to_owned(),
            observed_surface_fraction: None,
            prediction: None,
            purity_pct: None,
            scores,
        }
    }

    fn reconstructed(accuracy: f32, completion: f32, ratio: f32) -> ObjectScores {
        ObjectScores {
            status: PredictionStatus::Reconstructed,
            accuracy_cm: Some(accuracy),
            completion_cm: Some(completion),
            completion_ratio_5cm_pct: ratio,
            completion_ratio_1cm_pct: ratio / 2.0,
            accuracy_samples: 10,
            accuracy_far_5cm_pct: Some(0.0),
        }
    }

    #[test]
    fn missing_objects_count_zero_ratio_and_no_distance() {
        let objects = vec![
            object(3, "chair", ObjectScores::missing()),
            object(1, "chair", reconstructed(1.0, 2.0, 90.0)),
            object(2, "table", reconstructed(3.0, 4.0, 70.0)),
        ];
        let report = EvaluationReport::new(EvalSettings::default(), objects);
        assert_eq!(
            report.objects.iter().map(|o| o.id.0).collect::<Vec<_>>(),
            [1, 2, 3],
            "sorted by id"
        );
        let chair = report.classes["chair"];
        assert_eq!((chair.objects, chair.missing), (2, 1));
        assert_eq!(
            (chair.accuracy_cm, chair.completion_cm),
            (Some(1.0), Some(2.0)),
            "distances skip the missing chair"
        );
        assert_eq!(chair.completion_ratio_5cm_pct, 45.0, "the missing chair counts 0 %");
        assert_eq!(report.mean.completion_cm, Some(3.0));
        assert!((report.mean.completion_ratio_5cm_pct - 160.0 / 3.0).abs() < 1e-4);
    }

    #[test]
    fn a_report_round_trips_through_json() {
        let report = EvaluationReport::new(
            EvalSettings {
                crop: Crop::Vmap,
                seed: 4,
                samples_per_mesh: 100,
                pairing: Pairing::Geometry,
            },
            vec![
                object(1, "box", reconstructed(0.25, 1.5, 99.5)),
                object(2, "box", ObjectScores::missing()),
            ],
        );
        let text = serde_json::to_string(&report).expect("serialisable");
        assert!(
            text.contains("\"crop\":\"vmap\"") && text.contains("\"completion_cm\":null"),
            "{text}"
        );
        let back: EvaluationReport = serde_json::from_str(&text).expect("parses back");
        assert_eq!(back, report);
    }
}
