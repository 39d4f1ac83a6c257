//! `catmap sweep` and `catmap report`: the quick sweep reproduces docs/RESULTS.md's quick tables
//! byte for byte, and the files emitted for GNU parallel, Slurm and Kubernetes run (parallel,
//! where it is installed) or parse.

use std::path::Path;

use super::{CONFIG, catmap};

/// The repository's root.
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

/// The lines of docs/RESULTS.md between `<!-- NAME: begin -->` and `<!-- NAME: end -->`.
fn generated_block(name: &str) -> String {
    let page = std::fs::read_to_string(format!("{ROOT}/docs/RESULTS.md")).expect("docs/RESULTS.md");
    let begin = format!("<!-- {name}: begin -->\n");
    let start = page.find(&begin).unwrap_or_else(|| panic!("RESULTS.md has {begin}")) + begin.len();
    let end = page[start..]
        .find(&format!("<!-- {name}: end -->"))
        .unwrap_or_else(|| panic!("RESULTS.md ends the {name} block"));
    page[start..start + end].to_owned()
}

fn run_ok(args: &[&str]) -> String {
    let output = catmap().args(args).output().expect("catmap runs");
    assert!(
        output.status.success(),
        "catmap {args:?}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).expect("UTF-8 output")
}

fn path(p: &Path) -> &str {
    p.to_str().expect("a UTF-8 temp path")
}

#[test]
fn the_quick_sweep_reproduces_the_quick_tables_of_results_md_byte_for_byte() {
    let work = tempfile::tempdir().expect("temp dir");
    let runs = work.path().join("runs");
    let spec = format!("{ROOT}/docs/sweeps/quick.toml");
    run_ok(&["sweep", &spec, "--out", path(&runs), "--jobs", "2"]);
    let report = run_ok(&["report", path(&runs), "--metrics-only"]);
    let expected =
        generated_block("catmap sweep docs/sweeps/quick.toml --out RUNS --jobs 2 && catmap report RUNS --metrics-only");
    if report != expected {
        let out = std::env::temp_dir().join("catmap-quick-report.md");
        let _ = std::fs::write(&out, &report);
        panic!(
            "the quick sweep's tables differ from docs/RESULTS.md's (this run's are in {}):\n{report}",
            out.display()
        );
    }
    // A second sweep into the same folder finds every run done and runs none again.
    let before = std::fs::metadata(runs.join("runs/small0-none-category-fast-m0/metrics.json"))
        .and_then(|m| m.modified())
        .expect("metrics.json");
    run_ok(&["sweep", &spec, "--out", path(&runs), "--jobs", "2"]);
    let after = std::fs::metadata(runs.join("runs/small0-none-category-fast-m0/metrics.json"))
        .and_then(|m| m.modified())
        .expect("metrics.json");
    assert_eq!(before, after, "a done run is not run again");
    let full = run_ok(&["report", path(&runs)]);
    assert!(full.starts_with(&report), "the metric tables come first");
    assert!(full.contains("#### quick: wall clock and memory"), "{full}");
}

const TWO_RUNS: &str = r#"
name = "two"
scenes = ["small:4"]
modes = ["category", "instance"]
config = "config.toml"
"#;

#[test]
fn the_jobs_emitted_for_gnu_parallel_slurm_and_kubernetes_name_every_job_and_parallel_runs_them() {
    let work = tempfile::tempdir().expect("temp dir");
    let spec = work.path().join("two.toml");
    std::fs::write(&spec, TWO_RUNS).expect("spec");
    std::fs::write(work.path().join("config.toml"), CONFIG).expect("config");
    let runs = work.path().join("runs");
    for engine in ["slurm", "kubernetes", "parallel"] {
        run_ok(&["sweep", path(&spec), "--out", path(&runs), "--emit", engine]);
    }
    let lines = std::fs::read_to_string(runs.join("jobs.txt")).expect("jobs.txt");
    let lines: Vec<&str> = lines.lines().collect();
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert!(
        lines[1].ends_with(&format!("sweep {} --out {} --only 1", path(&spec), path(&runs))),
        "{lines:?}"
    );
    let slurm = std::fs::read_to_string(runs.join("slurm.sbatch")).expect("slurm.sbatch");
    assert!(
        slurm.starts_with("#!/bin/sh\n") && slurm.contains("#SBATCH --array=0-1\n"),
        "{slurm}"
    );
    let job: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(runs.join("kubernetes-job.json")).expect("the Job"))
            .expect("the Job is JSON");
    assert_eq!(
        (job["kind"].as_str(), job["spec"]["completions"].as_u64()),
        (Some("Job"), Some(2))
    );
    assert_eq!(job["spec"]["completionMode"], "Indexed");
    assert!(
        !runs.join("runs/small4-none-category-fast-m0").exists(),
        "emitting runs nothing"
    );
    let installed = std::process::Command::new("parallel")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success());
    if !installed {
        assert!(
            std::env::var_os("CATMAP_REQUIRE_PARALLEL").is_none(),
            "CI installed GNU parallel, yet it does not run"
        );
        eprintln!("GNU parallel is not installed: its script was parsed, not run");
        return;
    }
    let output = std::process::Command::new("sh")
        .arg(runs.join("parallel.sh"))
        .env("JOBS", "2")
        .env("NO_COLOR", "1")
        .output()
        .expect("sh runs");
    assert!(
        output.status.success(),
        "parallel.sh: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report = std::fs::read_to_string(runs.join("report.md")).expect("the script writes the report");
    for mode in ["category", "instance"] {
        let row = report
            .lines()
            .find(|l| l.starts_with(&format!("| small:4 | none | {mode} | fast | 0 |")))
            .unwrap_or_else(|| panic!("a row for {mode}: {report}"));
        assert!(!row.contains('–'), "both runs left metrics: {row}");
    }
}
