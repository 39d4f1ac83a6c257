//! `catmap report RUNS…`: the Markdown tables of one or more sweeps' runs (`catmap sweep`), read
//! from each folder's `sweep.json` and its runs' `metrics.json` and `summary.json`.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use catmap::metrics::EvaluationReport;
use catmap::sweep::SweepManifest;
use catmap::sweep::tables::{RunFacts, SweepRun, Tables, render};

/// Arguments of `catmap report`.
#[derive(clap::Args, Debug)]
pub struct ReportArgs {
    /// Output folders of `catmap sweep`.
    #[arg(required = true)]
    pub runs: Vec<PathBuf>,
    /// The metric tables alone, the same on every machine (without the table of wall clock,
    /// memory and build).
    #[arg(long)]
    pub metrics_only: bool,
}

/// The report `catmap report` prints.
pub fn report(args: &ReportArgs) -> anyhow::Result<String> {
    let tables = if args.metrics_only {
        Tables::Metrics
    } else {
        Tables::MetricsAndTime
    };
    let mut out = String::new();
    for dir in &args.runs {
        let path = dir.join("sweep.json");
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "cannot read {} (is {} a `catmap sweep` folder?)",
                path.display(),
                dir.display()
            )
        })?;
        let manifest: SweepManifest =
            serde_json::from_str(&text).with_context(|| format!("{} is not a catmap sweep.json", path.display()))?;
        let runs = manifest
            .jobs
            .iter()
            .map(|job| {
                let run = dir.join("runs").join(job.name());
                Ok(SweepRun {
                    job: job.clone(),
                    metrics: metrics(&run)?,
                    facts: facts(&run),
                })
            })
            .collect::<anyhow::Result<Vec<_>>>()?;
        let missing = runs.iter().filter(|r| r.metrics.is_none()).count();
        if missing > 0 {
            tracing::warn!(sweep = %manifest.spec.name, missing, "runs without metrics.json: their rows are dashes");
        }
        out.push_str(&render(&manifest.spec.name, &runs, tables));
    }
    Ok(out)
}

/// A run's `metrics.json` (`None` when it has none; an unreadable one is an error).
fn metrics(run: &Path) -> anyhow::Result<Option<EvaluationReport>> {
    let path = run.join("metrics.json");
    if !path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path).with_context(|| format!("cannot read {}", path.display()))?;
    let report =
        serde_json::from_str(&text).with_context(|| format!("{} is not a catmap metrics.json", path.display()))?;
    Ok(Some(report))
}

/// A run's frames, wall clock, memory and build, from its `summary.json` (what it lacks is none).
fn facts(run: &Path) -> RunFacts {
    let summary: Option<serde_json::Value> = std::fs::read_to_string(run.join("summary.json"))
        .ok()
        .and_then(|text| serde_json::from_str(&text).ok());
    let Some(s) = summary else {
        return RunFacts::default();
    };
    RunFacts {
        frames: s["frames"].as_u64(),
        seconds: s["total_seconds"].as_f64(),
        peak_mib: s["peak_resident_mib"].as_f64(),
        version: s["version"].as_str().map(str::to_owned),
    }
}
