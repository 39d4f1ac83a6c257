//! `catmap sweep SPEC --out RUNS`: a sweep spec's jobs run here, `--jobs N` at a time (each a
//! `catmap sweep … --only INDEX` process), or written out for an existing engine (`--emit`).
//! `RUNS` gets `sweep.json` (the spec and its jobs), `jobs.txt` (one command per job),
//! `scenes/` (each scene written once), `runs/NAME/` (each run's outputs) and `logs/NAME.txt`.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::Context as _;
use catmap::sweep::engines::{Engine, SweepCommand};
use catmap::sweep::{SweepJob, SweepManifest, SweepSpec};
use clap::Parser as _;

use crate::cli::progress::bar;

/// Arguments of `catmap sweep`.
#[derive(clap::Args, Debug)]
pub struct SweepArgs {
    /// The sweep spec (TOML; the specs of docs/RESULTS.md are in docs/sweeps/).
    pub spec: PathBuf,
    /// Output folder of the sweep.
    #[arg(long)]
    pub out: PathBuf,
    /// Runs at a time on this machine.
    #[arg(long, default_value_t = 1)]
    pub jobs: usize,
    /// Run job INDEX alone, in this process (the command each of an engine's tasks runs).
    #[arg(long, value_name = "INDEX", conflicts_with = "emit")]
    pub only: Option<usize>,
    /// Write the jobs for an engine instead of running them: `jobs.txt` and the engine's file
    /// (`parallel.sh`, `slurm.sbatch` or `kubernetes-job.json`).
    #[arg(long, value_enum)]
    pub emit: Option<EngineArg>,
}

/// `--emit` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum EngineArg {
    /// GNU parallel on one machine.
    Parallel,
    /// A Slurm array job.
    Slurm,
    /// A Kubernetes indexed Job.
    Kubernetes,
}

impl From<EngineArg> for Engine {
    fn from(engine: EngineArg) -> Self {
        match engine {
            EngineArg::Parallel => Self::GnuParallel,
            EngineArg::Slurm => Self::Slurm,
            EngineArg::Kubernetes => Self::Kubernetes,
        }
    }
}

/// Runs `catmap sweep`.
pub fn sweep(args: &SweepArgs) -> anyhow::Result<()> {
    let spec_path = std::path::absolute(&args.spec).with_context(|| format!("bad path {}", args.spec.display()))?;
    let out = std::path::absolute(&args.out).with_context(|| format!("bad path {}", args.out.display()))?;
    let spec = SweepSpec::load(&spec_path).context("cannot read the sweep spec")?;
    let jobs = spec.jobs()?;
    for dir in ["scenes", "runs", "logs"] {
        let dir = out.join(dir);
        std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    }
    let command = SweepCommand {
        name: spec.name.clone(),
        catmap: std::env::current_exe()
            .context("cannot find the catmap binary")?
            .display()
            .to_string(),
        spec: spec_path.display().to_string(),
        out: out.display().to_string(),
        jobs: jobs.len(),
    };
    if let Some(index) = args.only {
        let job = jobs
            .get(index)
            .with_context(|| format!("--only {index}: the sweep has jobs 0 to {}", jobs.len() - 1))?;
        return run_job(&spec, &spec_path, &out, job);
    }
    // Written by the sweep, not by its jobs (which run side by side).
    let manifest = SweepManifest {
        spec: spec.clone(),
        jobs: jobs.clone(),
    };
    let text = serde_json::to_string_pretty(&manifest).context("sweep.json")?;
    catmap::atomic_file::write_atomic(&out.join("sweep.json"), text.as_bytes())?;
    catmap::atomic_file::write_atomic(&out.join("jobs.txt"), command.job_lines().as_bytes())?;
    if let Some(engine) = args.emit {
        let engine = Engine::from(engine);
        let path = out.join(engine.file_name());
        catmap::atomic_file::write_atomic(&path, command.recipe(engine).as_bytes())?;
        tracing::info!(jobs = jobs.len(), file = %path.display(), lines = %out.join("jobs.txt").display(), "sweep written for the engine");
        return Ok(());
    }
    run_here(&jobs, &out, args.jobs.max(1))
}

/// Runs every job not yet done, `workers` at a time, each a `catmap sweep … --only INDEX`
/// process logging to `logs/NAME.txt`.
fn run_here(jobs: &[SweepJob], out: &Path, workers: usize) -> anyhow::Result<()> {
    let exe = std::env::current_exe().context("cannot find the catmap binary")?;
    let args: Vec<String> = std::env::args().skip(1).collect();
    let pending: Vec<&SweepJob> = jobs.iter().filter(|j| !done(out, j)).collect();
    tracing::info!(jobs = jobs.len(), to_run = pending.len(), workers, "sweep");
    let progress = bar(pending.len() as u64, "runs");
    let next = AtomicUsize::new(0);
    let failed = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..workers.min(pending.len()) {
            scope.spawn(|| {
                while let Some(job) = pending.get(next.fetch_add(1, Ordering::SeqCst)) {
                    let log = out.join("logs").join(format!("{}.txt", job.name()));
                    let ok = std::fs::File::create(&log).ok().and_then(|file| {
                        let err = file.try_clone().ok()?;
                        let mut child = std::process::Command::new(&exe);
                        child
                            .args(only_args(&args, job.index))
                            .env("NO_COLOR", "1")
                            .stdout(Stdio::from(file))
                            .stderr(Stdio::from(err));
                        child.status().ok()
                    });
                    if !ok.is_some_and(|s| s.success()) {
                        failed.lock().expect("no worker panics").push(log.display().to_string());
                    }
                    progress.inc(1);
                }
            });
        }
    });
    progress.finish_and_clear();
    let failed = failed.into_inner().expect("no worker panics");
    anyhow::ensure!(
        failed.is_empty(),
        "{} runs failed; their logs: {}",
        failed.len(),
        failed.join(", ")
    );
    tracing::info!(report = %format!("catmap report {}", out.display()), "sweep done");
    Ok(())
}

/// This process's `sweep` arguments with `--jobs` dropped and `--only INDEX` added.
fn only_args(args: &[String], index: usize) -> Vec<String> {
    let mut kept = Vec::new();
    let mut skip = false;
    for arg in args {
        if skip {
            skip = false;
        } else if arg == "--jobs" {
            skip = true;
        } else if !arg.starts_with("--jobs=") {
            kept.push(arg.clone());
        }
    }
    kept.extend(["--only".to_owned(), index.to_string()]);
    kept
}

/// Whether `job`'s run has left its metrics.
fn done(out: &Path, job: &SweepJob) -> bool {
    out.join("runs").join(job.name()).join("metrics.json").is_file()
}

/// Job `job`: its scene written unless another job wrote it, then the run (unless done; an
/// unfinished run's folder is started over).
fn run_job(spec: &SweepSpec, spec_path: &Path, out: &Path, job: &SweepJob) -> anyhow::Result<()> {
    if done(out, job) {
        tracing::info!(job = %job.name(), "done already");
        return Ok(());
    }
    let scene = out.join("scenes").join(job.scene_name());
    if !scene.join("scene.json").is_file() {
        // Written aside and renamed, so that two jobs of one scene never read half of it.
        let aside = out.join("scenes").join(format!(".{}.{}", job.scene_name(), job.index));
        let _ = std::fs::remove_dir_all(&aside);
        // A process of its own, so that the run's peak memory is the run's.
        let exe = std::env::current_exe().context("cannot find the catmap binary")?;
        let status = std::process::Command::new(exe)
            .arg("synth")
            .args(job.synth_args(&aside))
            .status()
            .context("cannot start catmap synth")?;
        anyhow::ensure!(
            status.success(),
            "job {}: catmap synth of scene {} with noise {} failed",
            job.name(),
            job.scene(),
            job.noise
        );
        if std::fs::rename(&aside, &scene).is_err() {
            anyhow::ensure!(scene.join("scene.json").is_file(), "cannot write {}", scene.display());
            let _ = std::fs::remove_dir_all(&aside);
        }
    }
    let run_out = out.join("runs").join(job.name());
    if run_out.exists() {
        std::fs::remove_dir_all(&run_out).with_context(|| format!("cannot clear {}", run_out.display()))?;
    }
    let spec_dir = spec_path.parent().unwrap_or(Path::new("."));
    let run =
        RunCli::try_parse_from(std::iter::once("run".to_owned()).chain(job.run_args(spec, spec_dir, &scene, &run_out)))
            .with_context(|| format!("job {}: the spec's run arguments", job.name()))?;
    crate::cli::run::run(&run.args)
}

/// `catmap run`'s arguments, parsed.
#[derive(clap::Parser)]
struct RunCli {
    #[command(flatten)]
    args: crate::cli::run::RunArgs,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_worker_runs_one_job_with_the_same_arguments_less_jobs() {
        let args: Vec<String> = ["s.toml", "--out", "R", "--jobs", "2"].map(String::from).to_vec();
        assert_eq!(only_args(&args, 3), ["s.toml", "--out", "R", "--only", "3"]);
        let args: Vec<String> = ["--jobs=4", "s.toml", "--out", "R"].map(String::from).to_vec();
        assert_eq!(only_args(&args, 0), ["s.toml", "--out", "R", "--only", "0"]);
    }
}
