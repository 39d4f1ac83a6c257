//! The `catmap` command line: `run` maps a dataset (or a synthetic scene), `synth` writes a
//! synthetic scene, `config` prints the default configuration.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::{Parser, Subcommand};

mod cli_compare;
mod cli_eval;
mod cli_run;
mod cli_synth;
mod progress;
mod run_outputs;
mod run_phases;
mod run_plan;

/// Object-level RGB-D mapping with category-level neural fields.
///
/// `catmap [OPTIONS]` without a subcommand is `catmap run [OPTIONS]`.
#[derive(Parser, Debug)]
#[command(name = "catmap", version = VERSION, about, long_about = None, args_conflicts_with_subcommands = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// The options of `catmap run`, for `catmap` without a subcommand.
    #[command(flatten)]
    run: cli_run::RunArgs,
}

/// The version, with the commit it was built from when built from a git checkout (`build.rs`).
pub(crate) const VERSION: &str = env!("CATMAP_VERSION");

#[derive(Subcommand, Debug)]
enum Command {
    /// Map a dataset (default: synthesise the default scene into OUT/scene and map it).
    Run(cli_run::RunArgs),
    /// Write a synthetic scene in the Replica (vMAP) layout, with ground-truth meshes.
    Synth(cli_synth::SynthArgs),
    /// Score predicted object meshes against ground-truth meshes (accuracy, completion, C.R.).
    Eval(cli_eval::EvalArgs),
    /// Compare two runs' metrics.json side by side (per class, repeated vs unique objects, all).
    Compare(cli_compare::CompareArgs),
    /// Print the default configuration as TOML (a config file lists only what it changes).
    Config,
}

fn main() -> anyhow::Result<()> {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .init();
    let cli = Cli::parse();
    match cli.command.unwrap_or(Command::Run(cli.run)) {
        Command::Run(args) => cli_run::run(&args),
        Command::Synth(args) => cli_synth::synth(&args),
        Command::Eval(args) => cli_eval::eval(&args),
        Command::Compare(args) => cli_compare::compare(&args),
        Command::Config => {
            print_stdout(&catmap::MapperConfig::default().to_toml());
            Ok(())
        }
    }
}

/// Writes text to standard output (the binary's one place that prints results).
#[expect(clippy::print_stdout, reason = "the CLI prints its results")]
fn print_stdout(text: &str) {
    print!("{text}");
}

/// Reads a config file (TOML, overrides only), or the defaults.
fn load_config(path: Option<&PathBuf>) -> anyhow::Result<catmap::MapperConfig> {
    match path {
        None => Ok(catmap::MapperConfig::default()),
        // The error names the file (and the line of a TOML error).
        Some(path) => catmap::MapperConfig::load(path).context("cannot load the config"),
    }
}
