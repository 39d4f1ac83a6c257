//! A small seeded mutation fuzzer for the reader paths (no nightly toolchain, so no cargo-fuzz).
//!
//! Each target draws inputs from its own ChaCha stream (seed `CATMAP_FUZZ_SEED`, default 0, mixed
//! with the target's name), so a run is reproducible: the n-th input of a seed is always the same.
//! A target runs a fixed number of inputs, `CATMAP_FUZZ_INPUTS` (default [`DEFAULT_INPUTS`]), so
//! that what `cargo test` tries does not depend on the machine's load; for long fuzzing,
//! `CATMAP_FUZZ_SECONDS` runs each target for that many seconds instead. Each input is executed under `catch_unwind`, and a panic or a broken property (an error that does not name
//! the file, a decoded frame that fails validation) is a failure. Failing inputs are saved under
//! `$CARGO_TARGET_TMPDIR/fuzz-failures/<target>/` with the seed and iteration in the name; with
//! `CATMAP_FUZZ_TRACE` set, every input is first written to `in-flight.bin` there (to catch
//! inputs that abort the process, e.g. on a failed allocation).
#![allow(dead_code, reason = "each test crate uses a different subset")]

pub mod checks;
pub mod fixtures;
pub mod mutate;
pub mod png;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Inputs per target in a plain `cargo test`.
pub const DEFAULT_INPUTS: u64 = 2000;
/// A run stops early after this many failures.
const MAX_FAILURES: usize = 5;
/// In a run of at least [`VERDICT_CHECK_FROM`] inputs, each verdict must be given to at least this
/// share of them: a generator whose inputs were all rejected (or all accepted) would leave the
/// checks on accepted inputs (or on errors) vacuous.
const MIN_VERDICT_SHARE: f64 = 0.01;
/// Runs shorter than this (a debugging `CATMAP_FUZZ_INPUTS`) skip the verdict-share check.
const VERDICT_CHECK_FROM: u64 = 100;

/// What one execution did with its input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// The reader accepted the input (and its output passed the target's checks).
    Accepted,
    /// The reader rejected the input with an error that passed the target's checks.
    Rejected,
}

/// Result of one execution: a verdict, or the property that broke.
pub type Execution = Result<Verdict, String>;

/// Totals of one target's run.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Inputs executed.
    pub executions: u64,
    /// Inputs accepted.
    pub accepted: u64,
    /// Inputs rejected with a proper error.
    pub rejected: u64,
    /// Panics and broken properties, with the file the input was saved to.
    pub failures: Vec<String>,
    /// Wall-clock time.
    pub elapsed: Duration,
}

/// A uniformly drawn element of `items` (not empty).
pub fn pick<'a, T>(items: &'a [T], rng: &mut ChaCha8Rng) -> &'a T {
    &items[rng.random_range(0..items.len())]
}

/// How long a target runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Budget {
    /// This many inputs (at least one).
    Inputs(u64),
    /// Until this much time has passed (at least one input).
    Time(Duration),
}

impl Budget {
    /// Whether a run that executed `executions` inputs since `started` goes on.
    fn goes_on(self, executions: u64, started: Instant) -> bool {
        match self {
            Budget::Inputs(n) => executions < n.max(1),
            Budget::Time(limit) => executions == 0 || started.elapsed() < limit,
        }
    }
}

/// The budget per target: `CATMAP_FUZZ_SECONDS` when set, else `CATMAP_FUZZ_INPUTS` inputs
/// (default [`DEFAULT_INPUTS`]).
pub fn budget() -> Budget {
    let var = |name: &str| std::env::var(name).ok().map(|s| s.trim().to_owned());
    if let Some(seconds) = var("CATMAP_FUZZ_SECONDS").and_then(|s| s.parse::<f64>().ok())
        && seconds.is_finite()
        && seconds >= 0.0
    {
        return Budget::Time(Duration::from_secs_f64(seconds));
    }
    Budget::Inputs(
        var("CATMAP_FUZZ_INPUTS")
            .and_then(|s| s.parse().ok())
            .unwrap_or(DEFAULT_INPUTS),
    )
}

/// Base seed: `CATMAP_FUZZ_SEED`, else 0.
pub fn base_seed() -> u64 {
    std::env::var("CATMAP_FUZZ_SEED")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(0)
}

/// The generator of target `name` (FNV-1a of the name mixed into the base seed).
pub fn target_rng(name: &str) -> ChaCha8Rng {
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    });
    ChaCha8Rng::seed_from_u64(base_seed() ^ hash)
}

fn failure_dir(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join("fuzz-failures")
        .join(name)
}

fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_owned())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "non-string panic payload".to_owned())
}

/// Runs target `name` within its [`budget`]: `generate` draws an input, `execute` runs the reader on it.
/// `save` renders an input as bytes (plus a description) for the failure file. Panics when any
/// input panicked or broke a property, listing them all, and when either verdict was given to
/// less than [`MIN_VERDICT_SHARE`] of the inputs.
pub fn fuzz<I>(
    name: &str,
    mut generate: impl FnMut(&mut ChaCha8Rng) -> I,
    mut execute: impl FnMut(&I) -> Execution,
    save: impl Fn(&I) -> (String, Vec<u8>),
) {
    let budget = budget();
    let trace = std::env::var_os("CATMAP_FUZZ_TRACE").is_some();
    let mut rng = target_rng(name);
    let started = Instant::now();
    let mut report = Report::default();
    while budget.goes_on(report.executions, started) && report.failures.len() < MAX_FAILURES {
        let iteration = report.executions;
        let input = generate(&mut rng);
        report.executions += 1;
        if trace {
            // An allocation failure aborts the process before a failure could be saved.
            let dir = failure_dir(name);
            let _ = std::fs::create_dir_all(&dir);
            let _ = std::fs::write(dir.join("in-flight.bin"), save(&input).1);
        }
        let problem = match catch_unwind(AssertUnwindSafe(|| execute(&input))) {
            Ok(Ok(Verdict::Accepted)) => {
                report.accepted += 1;
                continue;
            }
            Ok(Ok(Verdict::Rejected)) => {
                report.rejected += 1;
                continue;
            }
            Ok(Err(broken)) => broken,
            Err(payload) => format!("panic: {}", panic_text(payload.as_ref())),
        };
        let (description, bytes) = save(&input);
        let dir = failure_dir(name);
        let file = dir.join(format!("seed{}-iteration{iteration}.bin", base_seed()));
        let saved = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&file, &bytes));
        let place = saved.map_or_else(|e| format!("not saved: {e}"), |()| file.display().to_string());
        report.failures.push(format!(
            "iteration {iteration} ({description}): {problem} [input: {place}]"
        ));
    }
    report.elapsed = started.elapsed();
    eprintln!(
        "fuzz {name}: {} executions in {:.1} s ({:.0}/s), {} accepted, {} rejected, {} failures (seed {})",
        report.executions,
        report.elapsed.as_secs_f64(),
        report.executions as f64 / report.elapsed.as_secs_f64().max(1e-9),
        report.accepted,
        report.rejected,
        report.failures.len(),
        base_seed()
    );
    assert!(
        report.failures.is_empty(),
        "fuzz target {name} found {} failures:\n{}",
        report.failures.len(),
        report.failures.join("\n")
    );
    report.assert_both_verdicts(name);
}

impl Report {
    /// Panics when either verdict was given to less than [`MIN_VERDICT_SHARE`] of a run of at
    /// least [`VERDICT_CHECK_FROM`] inputs.
    fn assert_both_verdicts(&self, name: &str) {
        if self.executions < VERDICT_CHECK_FROM {
            return;
        }
        let least = (MIN_VERDICT_SHARE * self.executions as f64).ceil() as u64;
        assert!(
            self.accepted >= least && self.rejected >= least,
            "fuzz target {name}: {} accepted and {} rejected of {} inputs; each needs at least {least}, or the checks of the other are vacuous",
            self.accepted,
            self.rejected,
            self.executions
        );
    }
}

/// `Ok(Rejected)` when `error` mentions `needle` (a file name or folder), else the broken property.
pub fn rejected_naming(error: &impl std::fmt::Display, needle: &str) -> Execution {
    rejected_naming_one_of(error, &[needle])
}

/// `Ok(Rejected)` when `error` mentions one of `needles` (the files an edit touched), else the
/// broken property.
pub fn rejected_naming_one_of(error: &impl std::fmt::Display, needles: &[&str]) -> Execution {
    let text = error.to_string();
    if needles.iter().any(|needle| text.contains(needle)) {
        Ok(Verdict::Rejected)
    } else {
        Err(format!("error does not name one of {needles:?}: {text}"))
    }
}
