//! `catmap eval`: score predicted object meshes against ground-truth meshes (METHOD.md §6).

use std::path::PathBuf;

use anyhow::{Context as _, bail};
use catmap::metrics::{Crop, evaluate_dirs, render_markdown};

/// Arguments of `catmap eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Folder of predicted meshes `obj_{id}.ply` (or `meshes/obj_{id}.ply`).
    #[arg(long)]
    pub pred: PathBuf,
    /// Ground-truth folder: `gt_meshes/obj_{id}.ply` (else `obj_{id}.ply`) and optional `scene.json`.
    #[arg(long)]
    pub gt: PathBuf,
    /// Crop protocol: the paper's (accuracy only, tight box) or vMAP's (both sets, box / 0.9).
    #[arg(long, value_enum, default_value_t = CropArg::Paper)]
    pub crop: CropArg,
    /// Also write the full report as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Seed of the surface sampling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Crop protocols on the command line.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum CropArg {
    /// Crop predicted samples to the ground-truth box for accuracy only.
    Paper,
    /// Crop both sample sets to the ground-truth box enlarged by 1/0.9.
    Vmap,
}

impl From<CropArg> for Crop {
    fn from(c: CropArg) -> Self {
        match c {
            CropArg::Paper => Crop::Paper,
            CropArg::Vmap => Crop::Vmap,
        }
    }
}

/// Runs `catmap eval`: prints the Markdown tables, writes JSON when asked.
pub fn eval(args: &EvalArgs) -> anyhow::Result<()> {
    if !args.pred.is_dir() {
        bail!("prediction folder {} does not exist", args.pred.display());
    }
    if !args.gt.is_dir() {
        bail!("ground-truth folder {} does not exist", args.gt.display());
    }
    let report = evaluate_dirs(&args.pred, &args.gt, args.crop.into(), args.seed)
        .with_context(|| format!("cannot evaluate {} against {}", args.pred.display(), args.gt.display()))?;
    if let Some(path) = &args.json {
        let mut text = serde_json::to_string_pretty(&report).context("cannot serialise the report")?;
        text.push('\n');
        catmap::atomic_file::write_atomic(path, text.as_bytes())
            .with_context(|| format!("cannot write the report to {}", path.display()))?;
    }
    crate::print_stdout(&render_markdown(&report));
    tracing::info!(
        objects = report.mean.objects,
        missing = report.mean.missing,
        "evaluation done"
    );
    Ok(())
}
