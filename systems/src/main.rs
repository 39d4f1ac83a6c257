//! The `catmap` command line: `run` maps a dataset (or a synthetic scene), `synth` writes a
//! synthetic scene, `config` prints the default configuration (or a run's, resolved).

use clap::{Parser, Subcommand};

mod cli;

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
    run: cli::run::RunArgs,
    /// Colour the log lines on stderr: `auto` when stderr is a terminal (a file or a pipe gets
    /// plain text), `always`, or `never`.
    #[arg(long, value_enum, default_value_t = cli::color::ColorChoice::Auto, global = true)]
    color: cli::color::ColorChoice,
}

/// The version, with the commit it was built from when built from a git checkout (`build.rs`).
pub(crate) const VERSION: &str = env!("CATMAP_VERSION");

#[derive(Subcommand, Debug)]
enum Command {
    /// Map a dataset (default: synthesise the default scene into OUT/scene and map it).
    Run(cli::run::RunArgs),
    /// Write a synthetic scene in the Replica (vMAP) or TUM RGB-D layout, with ground-truth meshes.
    Synth(cli::synth::SynthArgs),
    /// Score predicted object meshes against ground-truth meshes (accuracy, completion, C.R.).
    Eval(cli::eval::EvalArgs),
    /// Compare two runs' metrics.json side by side (per class, repeated vs unique objects, all).
    Compare(cli::compare::CompareArgs),
    /// Run a sweep spec's jobs here (--jobs N at a time), or write them out for GNU parallel,
    /// Slurm or Kubernetes (--emit).
    Sweep(cli::sweep::SweepArgs),
    /// The Markdown tables of sweeps' runs (all, repeated and unique objects, per class; wall
    /// clock, memory and build).
    Report(cli::report::ReportArgs),
    /// Print the default configuration as TOML (a config file lists only what it changes), or
    /// with --resolved the settings `catmap run` with the same options maps with.
    Config(cli::config::ConfigArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(cli.color.ansi_on_stderr())
        .with_target(false)
        .init();
    match cli.command.unwrap_or(Command::Run(cli.run)) {
        Command::Run(args) => cli::run::run(&args),
        Command::Synth(args) => cli::synth::synth(&args),
        Command::Eval(args) => cli::eval::eval(&args),
        Command::Compare(args) => cli::compare::compare(&args),
        Command::Sweep(args) => cli::sweep::sweep(&args),
        Command::Report(args) => {
            print_stdout(&cli::report::report(&args)?);
            Ok(())
        }
        Command::Config(args) => {
            print_stdout(&cli::config::config(&args)?);
            Ok(())
        }
    }
}

/// Writes text to standard output (the binary's one place that prints results).
#[expect(clippy::print_stdout, reason = "the CLI prints its results")]
fn print_stdout(text: &str) {
    print!("{text}");
}

#[cfg(test)]
mod tests {
    use clap::{CommandFactory, Parser};

    use super::Cli;

    /// The pages whose command lines are checked: the README and every page of `docs/` (a test
    /// below keeps this list equal to the folder).
    const PAGES: [(&str, &str); 10] = [
        ("README.md", include_str!("../../README.md")),
        ("docs/ARCHITECTURE.md", include_str!("../../docs/ARCHITECTURE.md")),
        ("docs/BENCHMARKS.md", include_str!("../../docs/BENCHMARKS.md")),
        ("docs/CONFIG.md", include_str!("../../docs/CONFIG.md")),
        ("docs/DEVELOPMENT.md", include_str!("../../docs/DEVELOPMENT.md")),
        ("docs/METHOD.md", include_str!("../../docs/METHOD.md")),
        ("docs/RERUN.md", include_str!("../../docs/RERUN.md")),
        ("docs/RESULTS.md", include_str!("../../docs/RESULTS.md")),
        ("docs/ROBUSTNESS.md", include_str!("../../docs/ROBUSTNESS.md")),
        ("docs/USAGE.md", include_str!("../../docs/USAGE.md")),
    ];

    /// A page's `catmap …` command lines: inline code spans, and lines of code blocks
    /// (`cargo run --release -- ARGS` counts as `catmap ARGS`; the indented lines that follow
    /// one continue it), split at `&&` and `;`.
    fn command_lines(page: &str) -> Vec<String> {
        let (mut prose, mut commands) = (String::new(), Vec::<String>::new());
        let (mut in_block, mut continues) = (false, false);
        for line in page.lines() {
            if line.trim_start().starts_with("```") {
                in_block = !in_block;
                continues = false;
            } else if in_block {
                let indented = line.starts_with(' ');
                let line = line.split(" #").next().unwrap_or("").trim();
                if let Some(args) = line.strip_prefix("cargo run --release -- ") {
                    commands.push(format!("catmap {args}"));
                    continues = true;
                } else if line.starts_with("catmap ") {
                    commands.push(line.to_owned());
                    continues = true;
                } else if continues && indented && !line.is_empty() {
                    let last = commands.last_mut().expect("a command to continue");
                    last.push(' ');
                    last.push_str(line);
                } else {
                    continues = false;
                }
            } else {
                prose.push_str(line);
                prose.push(' ');
            }
        }
        for (i, span) in prose.split('`').enumerate() {
            if i % 2 == 1 && (span == "catmap" || span.starts_with("catmap ")) {
                commands.push(span.to_owned());
            }
        }
        commands
            .iter()
            .flat_map(|c| c.split("&&").flat_map(|c| c.split(';')))
            .map(|c| c.split('>').next().unwrap_or("").trim().to_owned())
            .filter(|c| c.starts_with("catmap"))
            .collect()
    }

    #[test]
    fn the_pages_whose_command_lines_are_checked_are_the_readme_and_every_page_of_docs() {
        let folder = concat!(env!("CARGO_MANIFEST_DIR"), "/../docs");
        let mut on_disk: Vec<String> = std::fs::read_dir(folder)
            .expect("docs/ is readable")
            .map(|entry| entry.expect("a docs/ entry").file_name().to_string_lossy().into_owned())
            .filter(|name| name.ends_with(".md"))
            .map(|name| format!("docs/{name}"))
            .collect();
        on_disk.sort();
        let listed: Vec<String> = PAGES
            .iter()
            .map(|(name, _)| (*name).to_owned())
            .filter(|name| name.starts_with("docs/"))
            .collect();
        assert_eq!(listed, on_disk, "list every page of docs/ in PAGES");
    }

    /// Every long option of the command line, with the subcommand it belongs to ("" at the top).
    fn long_options() -> Vec<(String, String)> {
        let cli = Cli::command();
        let mut options: Vec<(String, String)> = cli
            .get_arguments()
            .filter_map(|a| a.get_long().map(|l| (String::new(), format!("--{l}"))))
            .collect();
        for sub in cli.get_subcommands() {
            options.extend(
                sub.get_arguments()
                    .filter_map(|a| a.get_long().map(|l| (sub.get_name().to_owned(), format!("--{l}")))),
            );
        }
        options.extend([("".into(), "--help".into()), ("".into(), "--version".into())]);
        options
    }

    #[test]
    fn every_catmap_command_line_in_the_readme_and_docs_parses_and_every_option_it_names_exists() {
        let commands: Vec<(&str, String)> = PAGES
            .iter()
            .flat_map(|(name, page)| command_lines(page).into_iter().map(move |c| (*name, c)))
            .collect();
        assert!(commands.len() > 20, "the pages' command lines: {commands:?}");
        let in_readme = commands.iter().filter(|(name, _)| *name == "README.md").count();
        assert!(in_readme > 10, "the README's command lines: {in_readme}");
        let options = long_options();
        let mut parsed = 0;
        for (page, command) in &commands {
            let words: Vec<&str> = command.split_whitespace().collect();
            let sub = words.get(1).filter(|w| !w.starts_with('-')).copied().unwrap_or("run");
            for word in words.iter().filter(|w| w.contains("--")) {
                for flag in word.split(['[', ']', '|', '(', ')']).filter(|f| f.starts_with("--")) {
                    let flag = flag.split('=').next().unwrap_or(flag);
                    assert!(
                        options.iter().any(|(s, o)| o == flag && (s == sub || s.is_empty())),
                        "{page}: `{command}` names {flag}, which `catmap {sub}` does not have"
                    );
                }
            }
            // A synopsis (with [optional] parts or alternatives) is checked by its options alone;
            // `catmap SUB` alone names a subcommand.
            if ["[", "|", "…", "..."].iter().any(|mark| command.contains(mark)) {
                continue;
            }
            if words.len() == 2 && !words[1].starts_with('-') {
                assert!(
                    Cli::command().get_subcommands().any(|s| s.get_name() == words[1]),
                    "{page}: `{command}`: no such subcommand"
                );
                continue;
            }
            // Placeholders for numbers (`--seed S`, `--stride K`) stand for 1.
            let words: Vec<&str> = words
                .iter()
                .map(|w| {
                    if w.len() <= 2 && w.chars().all(|c| c.is_ascii_uppercase()) {
                        "1"
                    } else {
                        w
                    }
                })
                .collect();
            if let Err(e) = Cli::try_parse_from(&words) {
                assert!(
                    matches!(
                        e.kind(),
                        clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
                    ),
                    "{page}: `{command}` does not parse: {e}"
                );
            }
            parsed += 1;
        }
        assert!(
            parsed > 15,
            "most are whole command lines: {parsed} of {}",
            commands.len()
        );
    }
}
