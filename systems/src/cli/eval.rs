//! `catmap eval`: score predicted object meshes against ground-truth meshes (METHOD.md §6).

use std::path::{Path, PathBuf};

use anyhow::{Context as _, bail};
use catmap::metrics::object_matching::Pairing;
use catmap::metrics::{Crop, EvalSettings, ObjectClasses, evaluate_ground_truth, render_markdown};
use catmap_systems::summary::read_object_classes;

/// Arguments of `catmap eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// Folder of predicted meshes `obj_{id}.ply` (or `meshes/obj_{id}.ply`).
    #[arg(long)]
    pub pred: PathBuf,
    /// Ground-truth folder: `gt_meshes/obj_{id}.ply` (else `obj_{id}.ply`); a `scene.json` is
    /// used only when `catmap synth` wrote it.
    #[arg(long)]
    pub gt: PathBuf,
    /// The objects' classes: a catmap run's `summary.json`, or its run folder. Default: the
    /// `summary.json` beside or above `--pred` when there is one.
    #[arg(long, value_name = "SUMMARY")]
    pub classes: Option<PathBuf>,
    /// Crop protocol: the paper's (accuracy only, tight box) or vMAP's (both sets, box / 0.9).
    #[arg(long, value_enum, default_value_t = CropArg::Paper)]
    pub crop: CropArg,
    /// Also write the full report as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Seed of the surface sampling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// How predictions pair with ground-truth objects: by id (`obj_{id}.ply` against
    /// `obj_{id}.ply`), or by geometry (each ground-truth object takes the prediction whose
    /// surface lies on it over the largest area: for runs with `--instances per-frame`, whose ids
    /// are their own).
    #[arg(long, value_enum, default_value_t = PairingArg::Id)]
    pub pairing: PairingArg,
    /// Surface samples per mesh (both the prediction's and the ground truth's). The paper's
    /// 10 000 leave a sampling floor: the ground truth scored against itself gets ~0.7 cm
    /// accuracy and completion and C.R. < 1 cm ~82 % on the default scene; more samples lower it.
    #[arg(long, default_value_t = catmap::metrics::SAMPLES_PER_MESH)]
    pub samples: usize,
}

/// Pairings on the command line.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum PairingArg {
    /// By id.
    Id,
    /// By geometry.
    Geometry,
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
    if args.samples == 0 {
        bail!("--samples must be at least 1");
    }
    if !args.pred.is_dir() {
        bail!("prediction folder {} does not exist", args.pred.display());
    }
    if !args.gt.is_dir() {
        bail!("ground-truth folder {} does not exist", args.gt.display());
    }
    let classes = match &args.classes {
        Some(path) => read_object_classes(path).context("--classes")?,
        None => classes_beside(&args.pred),
    };
    let pairing = match args.pairing {
        PairingArg::Id => Pairing::ById,
        PairingArg::Geometry => Pairing::Geometry,
    };
    let classes = if pairing == Pairing::ById {
        classes
    } else {
        ObjectClasses::new()
    };
    let ground_truth = crate::cli::run_outputs::load_ground_truth(&args.gt, &classes)?;
    let settings = EvalSettings {
        crop: args.crop.into(),
        seed: args.seed,
        samples_per_mesh: args.samples,
        pairing,
    };
    let report = evaluate_ground_truth(&args.pred, &ground_truth, &settings)
        .with_context(|| format!("cannot evaluate {} against {}", args.pred.display(), args.gt.display()))?;
    if let Some(path) = &args.json {
        let mut text = serde_json::to_string_pretty(&report).context("cannot serialise the report")?;
        text.push('\n');
        catmap::atomic_file::write_atomic(path, text.as_bytes())
            .with_context(|| format!("cannot write the report to {}", path.display()))?;
    }
    crate::print_stdout(&render_markdown(&report));
    if report.mean.objects > 0 && report.mean.missing == report.mean.objects {
        bail!(
            "no predicted mesh in {} matches a ground-truth object: expected obj_{{id}}.ply files (in \
             the folder or its meshes/) for the ids of {} — is --pred a catmap run's output folder or \
             its meshes/, of a run on this dataset?",
            args.pred.display(),
            args.gt.display()
        );
    }
    if report.mean.missing > 0 {
        tracing::warn!(
            missing = report.mean.missing,
            of = report.mean.objects,
            "some ground-truth objects have no predicted mesh (scored as missing)"
        );
    }
    tracing::info!(
        objects = report.mean.objects,
        missing = report.mean.missing,
        "evaluation done"
    );
    Ok(())
}

/// The classes of the catmap run that wrote `pred` (`pred/summary.json`, or `../summary.json`
/// of `OUT/meshes`), when there is one; none (with a warning) when it is unreadable.
fn classes_beside(pred: &Path) -> ObjectClasses {
    let candidates = [
        Some(pred.join("summary.json")),
        pred.parent().map(|p| p.join("summary.json")),
    ];
    let Some(summary) = candidates.into_iter().flatten().find(|p| p.is_file()) else {
        return ObjectClasses::new();
    };
    match read_object_classes(&summary) {
        Ok(classes) => {
            tracing::info!(summary = %summary.display(), "object classes from the run's summary");
            classes
        }
        Err(e) => {
            tracing::warn!("{e:#}; classes from the ground truth only (--classes names another summary)");
            ObjectClasses::new()
        }
    }
}
