//! `catmap run` killed with SIGKILL and continued with `catmap run --resume`:
//! - at random checkpoint generations and inside checkpoint writes (checkpoints every 2 frames
//!   and every 50 steps; at least two kills leave a write unfinished): after every kill the
//!   checkpoint on disk is intact and no output file is half-written;
//! - a default run with checkpoints by the clock alone, killed once its second one is written.
//!
//! Kills are timed by the generations the manifest names, never by another run's wall clock, so a
//! loaded machine changes when they land, not whether the test holds.
//!
//! Either way the final meshes, categories.json and metrics.json equal those of a run that was
//! never interrupted, byte for byte.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use catmap::checkpoint::{MANIFEST, read_manifest, verify_checkpoint};
use catmap::geometry::mesh::TriangleMesh;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

const CONFIG: &str = r#"
seed = 2

[stream]
stride = 2

[fields]
steps_per_frame = 3
final_steps = 100

[categories]
min_field_steps = 20

[category_fields]
iterations = 100

[meshes]
background_voxel_m = 0.1

[meshes.object]
voxel_size_m = 0.04

[checkpoint]
every_frames = 2
every_steps = 50

# The paper's fixed phases (the refinement, then the category phase, 100 steps each), so that
# kills land in every phase; the fast schedule would run one phase until its fields converge.
[schedule]
policy = "paper"
"#;

fn catmap() -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_catmap"));
    command
        .env("RUST_LOG", "warn")
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    command
}

fn run_args(command: &mut Command, work: &Path, out: &Path) {
    command
        .arg("run")
        .arg("--dataset")
        .arg(work.join("scene"))
        .arg("--config")
        .arg(work.join("config.toml"))
        .arg("--mode")
        .arg("category")
        .arg("--out")
        .arg(out);
}

/// Every finished output file under `out` is whole: JSON parses, PLY reads; `.tmp` files are
/// the only unfinished ones. The checkpoint, if any, verifies.
fn assert_outputs_whole(out: &Path) {
    let mut stack = vec![out.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("lists") {
            let path = entry.expect("entry").path();
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default().to_owned();
            if path.is_dir() {
                stack.push(path);
            } else if name.ends_with(".json") {
                let text = std::fs::read_to_string(&path).expect("reads");
                serde_json::from_str::<serde_json::Value>(&text)
                    .unwrap_or_else(|e| panic!("{} is not whole JSON: {e}", path.display()));
            } else if name.ends_with(".ply") {
                TriangleMesh::read_ply(&path).unwrap_or_else(|e| panic!("{} is not a whole PLY: {e}", path.display()));
            }
        }
    }
    let checkpoint = out.join("checkpoint");
    if checkpoint.join(MANIFEST).exists() {
        verify_checkpoint(&checkpoint).unwrap_or_else(|e| panic!("the checkpoint on disk is damaged: {e}"));
    }
}

/// Whether the checkpoint folder holds an unfinished write: a `.tmp` file, or a generation file
/// its manifest does not name (a kill between the parts of a write).
fn unfinished_write(checkpoint: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(checkpoint) else {
        return false;
    };
    let named: Vec<String> = catmap::checkpoint::read_manifest(checkpoint)
        .map(|m| vec![m.state.name, m.tensors.name])
        .unwrap_or_default();
    entries.filter_map(Result::ok).any(|e| {
        let name = e.file_name().to_string_lossy().into_owned();
        name.ends_with(".tmp") || (name != MANIFEST && !named.contains(&name))
    })
}

/// The generation of the checkpoint in `checkpoint` (0 when there is none yet).
fn generation(checkpoint: &Path) -> u64 {
    read_manifest(checkpoint).map_or(0, |m| m.generation)
}

/// Whether a checkpoint file is being written (a `.tmp` file exists in the folder).
fn writing(checkpoint: &Path) -> bool {
    std::fs::read_dir(checkpoint).is_ok_and(|entries| {
        entries
            .filter_map(Result::ok)
            .any(|e| e.path().extension() == Some("tmp".as_ref()))
    })
}

fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("lists")
        .map(|e| e.expect("entry").path())
        .collect();
    files.sort();
    files
}

/// The outputs a resumed run must reproduce byte for byte: the meshes, categories.json and
/// metrics.json.
fn assert_same_outputs(reference: &Path, resumed: &Path) {
    let meshes: Vec<_> = files_under(&reference.join("meshes"));
    assert!(meshes.len() >= 5, "meshes written: {meshes:?}");
    let names = |files: &[PathBuf]| {
        files
            .iter()
            .map(|p| p.file_name().map(|n| n.to_owned()))
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&files_under(&resumed.join("meshes"))), names(&meshes));
    for file in meshes
        .iter()
        .map(|p| PathBuf::from("meshes").join(p.file_name().expect("name")))
        .chain(["categories.json".into(), "metrics.json".into()])
    {
        let a = std::fs::read(reference.join(&file)).expect("reference output");
        let b = std::fs::read(resumed.join(&file)).expect("resumed output");
        assert!(
            a == b,
            "{} differs between the uninterrupted and the resumed run",
            file.display()
        );
    }
}

/// The small scene of seed 4 in `work/scene`.
fn synthesise(work: &Path) {
    let status = catmap()
        .args(["synth", "--preset", "small", "--seed", "4", "--out"])
        .arg(work.join("scene"))
        .status()
        .expect("catmap runs");
    assert!(status.success(), "synth");
}

#[test]
fn a_run_killed_at_random_generations_and_inside_checkpoint_writes_resumes_like_an_uninterrupted_one() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    std::fs::write(work.join("config.toml"), CONFIG).expect("config written");
    synthesise(work);

    let reference = work.join("reference");
    let mut command = catmap();
    run_args(&mut command, work, &reference);
    assert!(command.status().expect("catmap runs").success(), "uninterrupted run");
    assert!(
        !reference.join("checkpoint").exists(),
        "the checkpoint is removed after success"
    );

    let killed = work.join("killed");
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut kills, mut resumes, mut torn_writes) = (0, 0, 0);
    loop {
        let mut command = catmap();
        if killed.join("checkpoint").join(MANIFEST).exists() {
            command.arg("run").arg("--resume").arg(&killed);
            resumes += 1;
        } else {
            run_args(&mut command, work, &killed);
        }
        let checkpoint = killed.join("checkpoint");
        let start = generation(&checkpoint);
        let mut child = command.spawn().expect("catmap starts");
        // Odd kills land as soon as a checkpoint file is being written (from the sixth on, every
        // kill until two writes were torn); even ones once the manifest names a generation one
        // or two past the one the attempt started from (drawn from the seeded generator): the
        // run has ~20 generations, so it cannot finish before the eighth kill.
        let at_write = kills % 2 == 1 || (kills >= 6 && torn_writes < 2);
        let kill_at = start + rng.random_range(1..=2u64);
        let status = loop {
            if let Some(status) = child.try_wait().expect("waits") {
                break Some(status);
            }
            // At least 8 kills, and more until two of them left a write unfinished (at most 24).
            let wanted = kills < 8 || (torn_writes < 2 && kills < 24);
            let due = wanted
                && if at_write {
                    writing(&checkpoint)
                } else {
                    generation(&checkpoint) >= kill_at
                };
            if due {
                child.kill().expect("SIGKILL");
                child.wait().expect("reaped");
                break None;
            }
            if !at_write {
                std::thread::sleep(Duration::from_millis(5));
            }
        };
        match status {
            Some(status) => {
                assert!(status.success(), "a resumed run completes");
                break;
            }
            None => {
                kills += 1;
                if unfinished_write(&killed.join("checkpoint")) {
                    torn_writes += 1;
                }
                assert_outputs_whole(&killed);
            }
        }
    }
    println!("{kills} kills ({torn_writes} inside a checkpoint write), {resumes} resumes");
    assert!(kills >= 8 && resumes >= 1, "the run was interrupted and resumed");
    assert!(
        torn_writes >= 2,
        "{torn_writes} of {kills} kills left a checkpoint write unfinished; the resume from one is what this test is for"
    );
    assert!(
        !killed.join("checkpoint").exists(),
        "the checkpoint is removed after success"
    );
    assert_same_outputs(&reference, &killed);
}

#[test]
fn a_default_run_killed_after_its_second_clock_checkpoint_resumes_to_the_same_outputs() {
    let work = tempfile::tempdir().expect("temp dir");
    let work = work.path();
    synthesise(work);
    // The default configuration: the run and its reference differ only in the cadence of
    // checkpoints, by the clock alone and scaled to this short run (the default is every 20 s).
    let reference = work.join("reference");
    let started = Instant::now();
    let status = catmap()
        .args(["run", "--dataset"])
        .arg(work.join("scene"))
        .arg("--out")
        .arg(&reference)
        .status()
        .expect("catmap runs");
    assert!(status.success(), "uninterrupted run");
    let full = started.elapsed();
    let every_seconds = (full.as_secs_f64() / 8.0).max(0.2);
    std::fs::write(
        work.join("config.toml"),
        format!("[checkpoint]\nevery_frames = 0\nevery_steps = 0\nevery_seconds = {every_seconds}\n"),
    )
    .expect("config written");

    let killed = work.join("killed");
    let mut child = catmap()
        .args(["run", "--dataset"])
        .arg(work.join("scene"))
        .arg("--config")
        .arg(work.join("config.toml"))
        .arg("--out")
        .arg(&killed)
        .spawn()
        .expect("catmap starts");
    // Killed as soon as the manifest names the second checkpoint: with one every eighth of the
    // run, a quarter of the way through.
    let checkpoint = killed.join("checkpoint");
    while generation(&checkpoint) < 2 {
        assert!(
            child.try_wait().expect("waits").is_none(),
            "the run wrote two checkpoints by the clock (every {every_seconds:.2} s) before it ended"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().expect("SIGKILL");
    child.wait().expect("reaped");
    assert_outputs_whole(&killed);
    let manifest = verify_checkpoint(&checkpoint)
        .unwrap_or_else(|e| panic!("a checkpoint every {every_seconds:.2} s left one to resume from: {e}"));
    assert!(manifest.generation >= 2, "killed after the second checkpoint");
    println!(
        "full run {full:?}; killed at checkpoint {} ({})",
        manifest.generation, manifest.label
    );
    let status = catmap()
        .arg("run")
        .arg("--resume")
        .arg(&killed)
        .status()
        .expect("catmap runs");
    assert!(status.success(), "the resumed run completes");
    assert_same_outputs(&reference, &killed);
}
