//! Two evaluations side by side (`catmap compare A B`): per class, repeated vs unique objects,
//! and all objects, with the relative change of each metric from A to B.
//!
//! An object is *repeated* when its class has more than one object in the evaluation (the
//! objects that can share a category-level field), *unique* otherwise.

use std::fmt::Write as _;

use super::report::{EvaluationReport, MetricSummary, ObjectGroup, ObjectMetrics};
use crate::error::{CatmapError, Result};

/// The groups compared: (label, summary in A, summary in B).
pub type ComparedGroups = Vec<(String, MetricSummary, MetricSummary)>;

/// Summaries of every group in both runs. Errors when the runs evaluated different objects.
pub fn compare_groups(a: &EvaluationReport, b: &EvaluationReport) -> Result<ComparedGroups> {
    let ids = |r: &EvaluationReport| r.objects.iter().map(|o| o.id).collect::<Vec<_>>();
    if ids(a) != ids(b) {
        return Err(CatmapError::DifferentScenes);
    }
    let group = |r: &EvaluationReport, keep: &dyn Fn(&ObjectMetrics) -> bool| {
        MetricSummary::of(r.objects.iter().filter(|o| keep(o)))
    };
    let mut groups = Vec::new();
    for name in a.classes.keys() {
        let in_class = |o: &ObjectMetrics| &o.class_name == name;
        groups.push((name.clone(), group(a, &in_class), group(b, &in_class)));
    }
    for (label, kind) in [
        ("**repeated**", ObjectGroup::Repeated),
        ("**unique**", ObjectGroup::Unique),
        ("**all**", ObjectGroup::All),
    ] {
        groups.push((label.into(), a.group_summary(kind), b.group_summary(kind)));
    }
    Ok(groups)
}

/// The Markdown table of [`compare_groups`]: each metric as A → B (relative change).
pub fn render_comparison(groups: &ComparedGroups, label_a: &str, label_b: &str) -> String {
    let mut out = format!("A = {label_a}\nB = {label_b}\n\n");
    out.push_str(
        "| group | objects | Acc. [cm] A → B | Comp. [cm] A → B | C.R. <5cm [%] A → B | C.R. <1cm [%] A → B |\n",
    );
    out.push_str("|---|---:|---:|---:|---:|---:|\n");
    let distance = |a: Option<f32>, b: Option<f32>| match (a, b) {
        (Some(a), Some(b)) => format!("{a:.2} → {b:.2} ({:+.1} %)", 100.0 * (b - a) / a.max(1e-6)),
        (a, b) => format!("{} → {}", fmt_opt(a), fmt_opt(b)),
    };
    let ratio = |a: f32, b: f32| format!("{a:.1} → {b:.1} ({:+.1})", b - a);
    for (label, a, b) in groups {
        let _ = writeln!(
            out,
            "| {label} | {} | {} | {} | {} | {} |",
            a.objects,
            distance(a.accuracy_cm, b.accuracy_cm),
            distance(a.completion_cm, b.completion_cm),
            ratio(a.completion_ratio_5cm_pct, b.completion_ratio_5cm_pct),
            ratio(a.completion_ratio_1cm_pct, b.completion_ratio_1cm_pct),
        );
    }
    out
}

fn fmt_opt(v: Option<f32>) -> String {
    v.map_or_else(|| "–".to_owned(), |x| format!("{x:.2}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::report::report_of_completions as report;

    #[test]
    fn repeated_and_unique_objects_are_grouped_by_class_size() {
        let a = report(&[(1, "chair", 4.0), (2, "chair", 2.0), (3, "lamp", 1.0)]);
        let b = report(&[(1, "chair", 2.0), (2, "chair", 1.0), (3, "lamp", 1.0)]);
        let groups = compare_groups(&a, &b).unwrap();
        let find = |label: &str| groups.iter().find(|g| g.0 == label).unwrap();
        assert_eq!(find("**repeated**").1.completion_cm, Some(3.0));
        assert_eq!(find("**repeated**").2.completion_cm, Some(1.5));
        assert_eq!(find("**unique**").1.objects, 1);
        let table = render_comparison(&groups, "instance", "category");
        assert!(table.contains("3.00 → 1.50 (-50.0 %)"), "{table}");
        let other = report(&[(1, "chair", 4.0)]);
        assert!(compare_groups(&a, &other).is_err());
    }
}
