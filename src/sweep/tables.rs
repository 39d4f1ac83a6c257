//! The Markdown tables of a sweep's runs (`catmap report`): the metrics over all objects, over
//! the repeated ones (classes with more than one object: those that can share a category
//! field) and the unique ones, per class, and each run's wall clock, peak memory and build. The
//! metric tables are the same on every machine; the time table is the machine's.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use super::spec::SweepJob;
use crate::metrics::{EvaluationReport, MetricSummary, ObjectGroup};

/// What one run of a sweep left.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRun {
    /// The job.
    pub job: SweepJob,
    /// Its `metrics.json` (`None`: the run left none).
    pub metrics: Option<EvaluationReport>,
    /// Its `summary.json`'s figures.
    pub facts: RunFacts,
}

/// The machine's figures of one run (from its `summary.json`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunFacts {
    /// Frames mapped.
    pub frames: Option<u64>,
    /// Wall-clock seconds.
    pub seconds: Option<f64>,
    /// Largest resident memory, MiB.
    pub peak_mib: Option<f64>,
    /// The catmap build (`catmap --version`).
    pub version: Option<String>,
}

/// Which tables a report holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tables {
    /// The metric tables only: the same on every machine.
    Metrics,
    /// The metric tables and the time table.
    MetricsAndTime,
}

/// The report of one sweep's runs, in job order.
pub fn render(name: &str, runs: &[SweepRun], tables: Tables) -> String {
    let mut out = String::new();
    for (group, title) in [
        (ObjectGroup::All, "all objects"),
        (
            ObjectGroup::Repeated,
            "repeated objects (classes with more than one object)",
        ),
        (ObjectGroup::Unique, "unique objects"),
    ] {
        let _ = writeln!(out, "#### {name}: {title}\n");
        out.push_str(
            "| scene | noise | mode | schedule | seed | objects | missing | Acc. [cm] | Comp. [cm] | C.R. <5cm [%] | C.R. <1cm [%] |\n",
        );
        out.push_str("|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
        for run in runs {
            let summary = run.metrics.as_ref().map(|m| m.group_summary(group));
            let _ = writeln!(out, "| {} | {} |", axes(&run.job), cells(summary.as_ref()));
        }
        out.push('\n');
    }
    let _ = writeln!(out, "#### {name}: per class\n");
    out.push_str(
        "| class | scene | noise | mode | schedule | seed | objects | missing | Acc. [cm] | Comp. [cm] | C.R. <5cm [%] | C.R. <1cm [%] |\n",
    );
    out.push_str("|---|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|\n");
    let classes: BTreeSet<&str> = runs
        .iter()
        .filter_map(|r| r.metrics.as_ref())
        .flat_map(|m| m.classes.keys().map(String::as_str))
        .collect();
    for class in classes {
        for run in runs {
            if let Some(summary) = run.metrics.as_ref().and_then(|m| m.classes.get(class)) {
                let _ = writeln!(out, "| {class} | {} | {} |", axes(&run.job), cells(Some(summary)));
            }
        }
    }
    if tables == Tables::MetricsAndTime {
        let _ = writeln!(out, "\n#### {name}: wall clock and memory (this machine's)\n");
        out.push_str("| run | frames | wall clock [s] | peak memory [MiB] | build |\n|---|---:|---:|---:|---|\n");
        for run in runs {
            let f = &run.facts;
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} |",
                run.job.name(),
                f.frames.map_or("–".into(), |n| n.to_string()),
                f.seconds.map_or("–".into(), |s| format!("{s:.1}")),
                f.peak_mib.map_or("–".into(), |m| format!("{m:.0}")),
                f.version.as_deref().unwrap_or("–"),
            );
        }
    }
    out
}

/// The job's axes as table cells.
fn axes(job: &SweepJob) -> String {
    format!(
        "{} | {} | {} | {} | {}",
        job.scene(),
        job.noise,
        job.mode,
        job.schedule,
        job.seed
    )
}

/// A summary's cells (a run without metrics: dashes).
fn cells(summary: Option<&MetricSummary>) -> String {
    let Some(s) = summary else {
        return ["–"; 6].join(" | ");
    };
    let distance = |d: Option<f32>| d.map_or("–".to_owned(), |d| format!("{d:.2}"));
    format!(
        "{} | {} | {} | {} | {:.1} | {:.1}",
        s.objects,
        s.missing,
        distance(s.accuracy_cm),
        distance(s.completion_cm),
        s.completion_ratio_5cm_pct,
        s.completion_ratio_1cm_pct
    )
}

#[cfg(test)]
#[path = "tables_tests.rs"]
mod tests;
