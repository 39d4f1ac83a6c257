//! `catmap compare A/metrics.json B/metrics.json`: two runs of one scene side by side.

use std::path::PathBuf;

use anyhow::Context as _;
use catmap::metrics::EvaluationReport;
use catmap::metrics::compare::{compare_groups, render_comparison};

/// Arguments of `catmap compare`.
#[derive(clap::Args, Debug)]
pub struct CompareArgs {
    /// The first run's `metrics.json` (A, e.g. instance mode).
    pub a: PathBuf,
    /// The second run's `metrics.json` (B, e.g. category mode).
    pub b: PathBuf,
}

/// Runs `catmap compare`.
pub fn compare(args: &CompareArgs) -> anyhow::Result<()> {
    let read = |path: &PathBuf| -> anyhow::Result<EvaluationReport> {
        let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("{} is not a catmap metrics.json", path.display()))
    };
    let (a, b) = (read(&args.a)?, read(&args.b)?);
    let groups = compare_groups(&a, &b).with_context(|| format!("{} vs {}", args.a.display(), args.b.display()))?;
    crate::print_stdout(&render_comparison(
        &groups,
        &args.a.display().to_string(),
        &args.b.display().to_string(),
    ));
    Ok(())
}
