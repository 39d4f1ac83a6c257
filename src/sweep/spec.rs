//! A sweep spec (TOML): synthetic scenes × sensor noise × field modes × schedules × mapper seeds,
//! and the jobs it expands to, in one fixed order. Each job is one synthetic scene (written once,
//! shared by every job of that scene and noise) mapped once.
//!
//! ```toml
//! name = "quick"
//! scenes = ["small:0"]                  # `catmap synth --preset P --seed S`
//! noise = ["none", "structured-light"]  # `catmap synth --noise`; noisy scenes get per-frame ids
//! modes = ["category", "instance"]      # `catmap run --mode`
//! schedules = ["fast"]                  # `catmap run --schedule`
//! seeds = [0]                           # `catmap run --seed`
//! config = "quick-config.toml"          # optional: `catmap run --config`, beside the spec
//! run_args = ["--max-frames", "8"]      # optional: more `catmap run` arguments
//! ```

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{CatmapError, Result};

/// A sweep spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// The sweep's name: its tables' heading and its jobs' prefix.
    pub name: String,
    /// Synthetic scenes, each `PRESET:SEED`.
    pub scenes: Vec<String>,
    /// Sensor noise of the scenes (`catmap synth --noise`; `none`: exact depth and masks).
    #[serde(default = "exact")]
    pub noise: Vec<String>,
    /// Field modes (`catmap run --mode`).
    #[serde(default = "category")]
    pub modes: Vec<String>,
    /// Schedules, i.e. profiles (`catmap run --schedule`).
    #[serde(default = "fast")]
    pub schedules: Vec<String>,
    /// Mapper seeds (`catmap run --seed`).
    #[serde(default = "seed_zero")]
    pub seeds: Vec<u64>,
    /// A config file every run reads, relative to the spec's folder.
    #[serde(default)]
    pub config: Option<PathBuf>,
    /// More `catmap run` arguments, the same for every run.
    #[serde(default)]
    pub run_args: Vec<String>,
}

fn exact() -> Vec<String> {
    vec!["none".to_owned()]
}

fn category() -> Vec<String> {
    vec!["category".to_owned()]
}

fn fast() -> Vec<String> {
    vec!["fast".to_owned()]
}

fn seed_zero() -> Vec<u64> {
    vec![0]
}

/// One job of a sweep: a scene, its noise, and how it is mapped.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct SweepJob {
    /// Position in the sweep's order (`catmap sweep --only INDEX`).
    pub index: usize,
    /// `catmap synth --preset`.
    pub preset: String,
    /// `catmap synth --seed`.
    pub scene_seed: u64,
    /// `catmap synth --noise`.
    pub noise: String,
    /// `catmap run --mode`.
    pub mode: String,
    /// `catmap run --schedule`.
    pub schedule: String,
    /// `catmap run --seed`.
    pub seed: u64,
}

impl SweepJob {
    /// The scene's folder name, shared by the jobs that map it: `small0-none`.
    pub fn scene_name(&self) -> String {
        format!("{}{}-{}", self.preset, self.scene_seed, self.noise)
    }

    /// The run's folder name: `small0-none-category-fast-m0`.
    pub fn name(&self) -> String {
        format!("{}-{}-{}-m{}", self.scene_name(), self.mode, self.schedule, self.seed)
    }

    /// The scene as `PRESET:SEED`, as the spec names it.
    pub fn scene(&self) -> String {
        format!("{}:{}", self.preset, self.scene_seed)
    }

    /// Whether the scene is written with a sensor's noise (and so a segmenter's per-frame ids).
    pub fn noisy(&self) -> bool {
        self.noise != "none"
    }

    /// `catmap synth`'s arguments for the scene, written to `dir`.
    pub fn synth_args(&self, dir: &Path) -> Vec<String> {
        let mut args = vec![
            "--preset".to_owned(),
            self.preset.clone(),
            "--seed".to_owned(),
            self.scene_seed.to_string(),
            "--noise".to_owned(),
            self.noise.clone(),
        ];
        if self.noisy() {
            args.extend(["--ids".to_owned(), "per-frame".to_owned()]);
        }
        args.extend(["--out".to_owned(), dir.display().to_string()]);
        args
    }

    /// `catmap run`'s arguments for the run of `spec` (read from `spec_dir`) mapping `scene`
    /// into `out`, without a recording.
    pub fn run_args(&self, spec: &SweepSpec, spec_dir: &Path, scene: &Path, out: &Path) -> Vec<String> {
        let mut args = vec![
            "--dataset".to_owned(),
            scene.display().to_string(),
            "--mode".to_owned(),
            self.mode.clone(),
            "--schedule".to_owned(),
            self.schedule.clone(),
            "--seed".to_owned(),
            self.seed.to_string(),
            "--no-recording".to_owned(),
            "--out".to_owned(),
            out.display().to_string(),
        ];
        if let Some(config) = &spec.config {
            args.extend(["--config".to_owned(), spec_dir.join(config).display().to_string()]);
        }
        args.extend(spec.run_args.iter().cloned());
        args
    }
}

/// What `catmap sweep` writes beside its runs (`sweep.json`): the spec and its jobs, so that
/// `catmap report` reads the folder alone.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepManifest {
    /// The spec, as read.
    pub spec: SweepSpec,
    /// Its jobs.
    pub jobs: Vec<SweepJob>,
}

impl SweepSpec {
    /// Reads a spec file; errors name the file (and the line of a TOML error).
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
        let spec: Self = toml::from_str(&text).map_err(|e| CatmapError::Parse {
            path: path.to_path_buf(),
            line: e
                .span()
                .map_or(0, |span| 1 + text[..span.start.min(text.len())].matches('\n').count()),
            reason: e.message().trim().to_owned(),
        })?;
        spec.jobs().map_err(|e| CatmapError::Parse {
            path: path.to_path_buf(),
            line: 0,
            reason: e.to_string(),
        })?;
        Ok(spec)
    }

    /// The jobs, scene by scene, then by noise, mode, schedule and seed.
    pub fn jobs(&self) -> Result<Vec<SweepJob>> {
        let bad = |msg: String| Err(CatmapError::ConfigValue(msg));
        if self.name.is_empty()
            || !self
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return bad(format!("name {:?}: letters, digits, '-' and '_' only", self.name));
        }
        for (axis, len) in [
            ("scenes", self.scenes.len()),
            ("noise", self.noise.len()),
            ("modes", self.modes.len()),
            ("schedules", self.schedules.len()),
            ("seeds", self.seeds.len()),
        ] {
            if len == 0 {
                return bad(format!("{axis}: at least one value"));
            }
        }
        let mut jobs = Vec::new();
        for scene in &self.scenes {
            let Some((preset, seed)) = scene.split_once(':') else {
                return bad(format!("scenes: {scene:?} is not PRESET:SEED"));
            };
            let Ok(scene_seed) = seed.parse::<u64>() else {
                return bad(format!("scenes: {scene:?}: the seed is not a number"));
            };
            for noise in &self.noise {
                for mode in &self.modes {
                    for schedule in &self.schedules {
                        for &seed in &self.seeds {
                            jobs.push(SweepJob {
                                index: jobs.len(),
                                preset: preset.to_owned(),
                                scene_seed,
                                noise: noise.clone(),
                                mode: mode.clone(),
                                schedule: schedule.clone(),
                                seed,
                            });
                        }
                    }
                }
            }
        }
        let mut names: Vec<String> = jobs.iter().map(SweepJob::name).collect();
        names.sort();
        if let Some(twice) = names.windows(2).find(|w| w[0] == w[1]) {
            return bad(format!(
                "the job {} appears twice (a value repeated on an axis)",
                twice[0]
            ));
        }
        Ok(jobs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> SweepSpec {
        toml::from_str(text).expect("a spec")
    }

    #[test]
    fn a_spec_expands_scene_by_scene_then_noise_mode_schedule_and_seed() {
        let s = spec(
            "name = \"t\"\nscenes = [\"small:0\", \"default:2\"]\nnoise = [\"none\", \"time-of-flight\"]\nmodes = [\"category\", \"instance\"]\nseeds = [0, 1]\n",
        );
        let jobs = s.jobs().expect("valid");
        assert_eq!(jobs.len(), 2 * 2 * 2 * 2);
        assert!(jobs.iter().enumerate().all(|(i, j)| j.index == i));
        let names: Vec<String> = jobs.iter().take(3).map(SweepJob::name).collect();
        assert_eq!(
            names,
            [
                "small0-none-category-fast-m0",
                "small0-none-category-fast-m1",
                "small0-none-instance-fast-m0"
            ]
        );
        assert_eq!(jobs[15].name(), "default2-time-of-flight-instance-fast-m1");
        assert_eq!(jobs[15].scene(), "default:2");
    }

    #[test]
    fn a_noisy_scene_is_written_with_per_frame_ids_and_every_run_gets_the_specs_config_and_arguments() {
        let s = spec(
            "name = \"t\"\nscenes = [\"small:3\"]\nnoise = [\"active-stereo\"]\nconfig = \"c.toml\"\nrun_args = [\"--max-frames\", \"8\"]\n",
        );
        let job = &s.jobs().expect("valid")[0];
        assert_eq!(
            job.synth_args(Path::new("S")),
            [
                "--preset",
                "small",
                "--seed",
                "3",
                "--noise",
                "active-stereo",
                "--ids",
                "per-frame",
                "--out",
                "S"
            ]
        );
        assert_eq!(
            job.run_args(&s, Path::new("specs"), Path::new("S"), Path::new("R")),
            [
                "--dataset",
                "S",
                "--mode",
                "category",
                "--schedule",
                "fast",
                "--seed",
                "0",
                "--no-recording",
                "--out",
                "R",
                "--config",
                "specs/c.toml",
                "--max-frames",
                "8"
            ]
        );
    }

    #[test]
    fn bad_specs_are_errors_naming_what_is_wrong() {
        let err = |text: &str| spec(text).jobs().expect_err("bad").to_string();
        assert!(err("name = \"t\"\nscenes = [\"small\"]\n").contains("PRESET:SEED"));
        assert!(err("name = \"t\"\nscenes = [\"small:x\"]\n").contains("not a number"));
        assert!(err("name = \"t\"\nscenes = []\n").contains("scenes"));
        assert!(err("name = \"a b\"\nscenes = [\"small:0\"]\n").contains("name"));
        assert!(err("name = \"t\"\nscenes = [\"small:0\"]\nseeds = [1, 1]\n").contains("twice"));
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("s.toml");
        std::fs::write(&path, "name = \"t\"\nscenes = [\"small:0\"]\nmode = [\"x\"]\n").expect("write");
        let e = SweepSpec::load(&path).expect_err("unknown key").to_string();
        assert!(e.contains("s.toml:3") && e.contains("mode"), "{e}");
    }
}
