//! Markdown tables of an [`EvaluationReport`]: per object, per class, and the mean.

use std::fmt::Write as _;

use super::object_matching::Pairing;
use super::object_scores::PredictionStatus;
use super::report::{EvaluationReport, MetricSummary};

/// Column headers of the score columns.
const SCORE_HEADER: &str = "Acc. [cm] | Comp. [cm] | C.R. <5cm [%] | C.R. <1cm [%]";
const SCORE_ALIGN: &str = "---:|---:|---:|---:";

/// Renders `report` as three Markdown tables: objects, classes and the mean over objects.
/// A distance that does not exist (missing object, nothing in the crop) shows as `–`.
pub fn render_markdown(report: &EvaluationReport) -> String {
    let s = &report.settings;
    let mut out = format!(
        "# Reconstruction metrics\n\ncrop: {}, {} samples per mesh, seed {}; {} objects, {} missing\n\n",
        s.crop, s.samples_per_mesh, s.seed, report.mean.objects, report.mean.missing
    );
    // The observed share of each object's surface, when the ground truth states it.
    let seen = report.objects.iter().any(|o| o.observed_surface_fraction.is_some());
    let (seen_header, seen_align) = if seen { (" seen [%] |", "---:|") } else { ("", "") };
    // Paired by geometry: which prediction, and how pure it is.
    let paired = report.settings.pairing == Pairing::Geometry;
    let (pair_header, pair_align) = if paired {
        (" prediction | purity [%] |", "---:|---:|")
    } else {
        ("", "")
    };
    out.push_str(&format!(
        "## Objects\n\n| object | class |{seen_header}{pair_header} {SCORE_HEADER} | far >5cm [%] |\n|---:|---|{seen_align}{pair_align}{SCORE_ALIGN}|---:|\n"
    ));
    for o in &report.objects {
        let v = &o.scores;
        let row = match v.status {
            PredictionStatus::Missing => "missing | missing | 0.0 | 0.0 | –".to_owned(),
            PredictionStatus::Reconstructed => {
                scores(
                    v.accuracy_cm,
                    v.completion_cm,
                    v.completion_ratio_5cm_pct,
                    v.completion_ratio_1cm_pct,
                ) + &format!(" | {}", share(v.accuracy_far_5cm_pct))
            }
        };
        let seen_cell = match (seen, o.observed_surface_fraction) {
            (false, _) => String::new(),
            (true, None) => " – |".to_owned(),
            (true, Some(f)) => format!(" {:.1} |", 100.0 * f),
        };
        let pair_cell = match (paired, o.prediction, o.purity_pct) {
            (false, _, _) => String::new(),
            (true, Some(p), Some(purity)) => format!(" {p} | {purity:.1} |"),
            (true, _, _) => " – | – |".to_owned(),
        };
        let _ = writeln!(out, "| {} | {} |{seen_cell}{pair_cell} {row} |", o.id, o.class_name);
    }
    if paired {
        let extra: Vec<String> = report.extra_predictions.iter().map(ToString::to_string).collect();
        let _ = writeln!(
            out,
            "\nPredictions paired with no ground-truth object: {}",
            if extra.is_empty() {
                "none".to_owned()
            } else {
                extra.join(", ")
            }
        );
    }
    out.push_str(&format!(
        "\n## Classes\n\n| class | objects | missing | {SCORE_HEADER} |\n|---|---:|---:|{SCORE_ALIGN}|\n"
    ));
    for (name, summary) in &report.classes {
        let _ = writeln!(out, "| {name} | {} |", summary_cells(summary));
    }
    out.push_str(&format!(
        "\n## Mean over objects\n\n| objects | missing | {SCORE_HEADER} |\n|---:|---:|{SCORE_ALIGN}|\n"
    ));
    let _ = writeln!(out, "| {} |", summary_cells(&report.mean));
    out
}

fn summary_cells(s: &MetricSummary) -> String {
    let v = scores(
        s.accuracy_cm,
        s.completion_cm,
        s.completion_ratio_5cm_pct,
        s.completion_ratio_1cm_pct,
    );
    format!("{} | {} | {v}", s.objects, s.missing)
}

fn scores(accuracy_cm: Option<f32>, completion_cm: Option<f32>, ratio_pct: f32, ratio_1cm_pct: f32) -> String {
    format!(
        "{} | {} | {ratio_pct:.1} | {ratio_1cm_pct:.1}",
        distance(accuracy_cm),
        distance(completion_cm)
    )
}

fn share(pct: Option<f32>) -> String {
    pct.map_or_else(|| "–".to_owned(), |p| format!("{p:.1}"))
}

fn distance(cm: Option<f32>) -> String {
    cm.map_or_else(|| "–".to_owned(), |d| format!("{d:.2}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::ObjectId;
    use crate::metrics::{EvalSettings, ObjectMetrics, ObjectScores};

    #[test]
    fn tables_list_objects_classes_and_the_mean() {
        let scores = ObjectScores {
            status: PredictionStatus::Reconstructed,
            accuracy_cm: Some(1.234),
            completion_cm: Some(2.5),
            completion_ratio_5cm_pct: 96.0,
            completion_ratio_1cm_pct: 40.0,
            accuracy_samples: 10,
            accuracy_far_5cm_pct: Some(12.5),
        };
        let objects = vec![
            ObjectMetrics {
                id: ObjectId(4),
                class: None,
                class_name: "chair".into(),
                observed_surface_fraction: None,
                prediction: None,
                purity_pct: None,
                scores,
            },
            ObjectMetrics {
                id: ObjectId(7),
                class: None,
                class_name: "chair".into(),
                observed_surface_fraction: None,
                prediction: None,
                purity_pct: None,
                scores: ObjectScores::missing(),
            },
        ];
        let text = render_markdown(&EvaluationReport::new(EvalSettings::default(), objects));
        assert!(
            text.contains("| 4 | chair | 1.23 | 2.50 | 96.0 | 40.0 | 12.5 |"),
            "object row:\n{text}"
        );
        assert!(
            text.contains("| 7 | chair | missing | missing | 0.0 | 0.0 | – |"),
            "missing row:\n{text}"
        );
        assert!(
            text.contains("| chair | 2 | 1 | 1.23 | 2.50 | 48.0 | 20.0 |"),
            "class row:\n{text}"
        );
        assert!(
            text.contains("| 2 | 1 | 1.23 | 2.50 | 48.0 | 20.0 |"),
            "mean row:\n{text}"
        );
    }

    #[test]
    fn the_observed_fraction_gets_a_column_when_the_ground_truth_states_it() {
        let object = |id, fraction| ObjectMetrics {
            id: ObjectId(id),
            class: None,
            class_name: "chair".into(),
            observed_surface_fraction: fraction,
            prediction: None,
            purity_pct: None,
            scores: ObjectScores::missing(),
        };
        let text = render_markdown(&EvaluationReport::new(
            EvalSettings::default(),
            vec![object(1, Some(0.756)), object(2, None)],
        ));
        assert!(text.contains("| object | class | seen [%] | Acc."), "header:\n{text}");
        assert!(text.contains("| 1 | chair | 75.6 | missing |"), "stated:\n{text}");
        assert!(text.contains("| 2 | chair | – | missing |"), "not stated:\n{text}");
    }
}
