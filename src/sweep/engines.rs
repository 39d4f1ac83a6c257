//! A sweep's jobs handed to an existing engine: one shell command per job (`catmap sweep SPEC
//! --out RUNS --only INDEX`), and the files that run them — a GNU parallel script, a Slurm array
//! job and a Kubernetes indexed Job. catmap schedules nothing itself; each engine runs the jobs'
//! commands, and `catmap report RUNS` reads what they wrote.

use serde_json::json;

/// The engines a sweep's jobs can be handed to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Engine {
    /// GNU parallel on one machine (`parallel --jobs N`).
    GnuParallel,
    /// A Slurm array job, one task per job.
    Slurm,
    /// A Kubernetes indexed Job, one completion per job.
    Kubernetes,
}

impl Engine {
    /// The file the engine's recipe is written to, in the sweep's output folder.
    pub fn file_name(self) -> &'static str {
        match self {
            Self::GnuParallel => "parallel.sh",
            Self::Slurm => "slurm.sbatch",
            Self::Kubernetes => "kubernetes-job.json",
        }
    }
}

/// What every emitted file needs: the catmap binary, the spec, the output folder and the jobs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SweepCommand {
    /// The sweep's name (the Slurm and Kubernetes job's name).
    pub name: String,
    /// The catmap binary, as the engine's machines find it.
    pub catmap: String,
    /// The spec file.
    pub spec: String,
    /// The sweep's output folder.
    pub out: String,
    /// How many jobs the spec has.
    pub jobs: usize,
}

impl SweepCommand {
    /// Job `index`'s command.
    pub fn job(&self, index: usize) -> String {
        format!("{} --only {index}", self.prefix())
    }

    /// Every job's command, one per line (`jobs.txt`).
    pub fn job_lines(&self) -> String {
        (0..self.jobs).map(|i| self.job(i) + "\n").collect()
    }

    /// `catmap sweep SPEC --out RUNS`, quoted for a shell.
    fn prefix(&self) -> String {
        format!(
            "{} sweep {} --out {}",
            shell_quoted(&self.catmap),
            shell_quoted(&self.spec),
            shell_quoted(&self.out)
        )
    }

    /// The engine's recipe (the file [`Engine::file_name`] names).
    pub fn recipe(&self, engine: Engine) -> String {
        match engine {
            Engine::GnuParallel => self.gnu_parallel(),
            Engine::Slurm => self.slurm(),
            Engine::Kubernetes => self.kubernetes(),
        }
    }

    /// A shell script running `jobs.txt` with GNU parallel, `JOBS` at a time (2 unless set), and
    /// the report after.
    fn gnu_parallel(&self) -> String {
        let out = shell_quoted(&self.out);
        format!(
            "#!/bin/sh\n# The sweep {name}: {jobs} jobs, JOBS at a time (default 2); then the report.\nset -e\nparallel --jobs \"${{JOBS:-2}}\" --halt now,fail=1 --joblog {log} < {lines}\n{catmap} report {out} > {report}\n",
            name = self.name,
            jobs = self.jobs,
            log = shell_quoted(&format!("{}/parallel.log", self.out)),
            lines = shell_quoted(&format!("{}/jobs.txt", self.out)),
            catmap = shell_quoted(&self.catmap),
            report = shell_quoted(&format!("{}/report.md", self.out)),
        )
    }

    /// A Slurm array job: task `SLURM_ARRAY_TASK_ID` runs that job (`sbatch slurm.sbatch`; the
    /// report once every task is done: `catmap report RUNS`).
    fn slurm(&self) -> String {
        format!(
            "#!/bin/sh\n#SBATCH --job-name={name}\n#SBATCH --array=0-{last}\n#SBATCH --cpus-per-task=2\n#SBATCH --mem=8G\n#SBATCH --output={log}\nexec {prefix} --only \"$SLURM_ARRAY_TASK_ID\"\n",
            name = self.name,
            last = self.jobs.saturating_sub(1),
            log = format_args!("{}/logs/slurm-%A_%a.txt", self.out),
            prefix = self.prefix(),
        )
    }

    /// A Kubernetes indexed Job (`kubectl apply -f kubernetes-job.json`): completion
    /// `JOB_COMPLETION_INDEX` runs that job. The image must hold the catmap binary, and the
    /// output folder must be a volume every pod shares (`CATMAP_IMAGE` and the `runs` volume are
    /// the two things to fill in).
    fn kubernetes(&self) -> String {
        let manifest = json!({
            "apiVersion": "batch/v1",
            "kind": "Job",
            "metadata": { "name": format!("catmap-sweep-{}", self.name.to_lowercase().replace('_', "-")) },
            "spec": {
                "completionMode": "Indexed",
                "completions": self.jobs,
                "parallelism": self.jobs.min(8),
                "backoffLimitPerIndex": 1,
                "template": {
                    "spec": {
                        "restartPolicy": "Never",
                        "containers": [{
                            "name": "catmap",
                            "image": "CATMAP_IMAGE",
                            "command": ["/bin/sh", "-c", format!("exec {} --only \"$JOB_COMPLETION_INDEX\"", self.prefix())],
                            "resources": { "requests": { "cpu": "2", "memory": "8Gi" } },
                            "volumeMounts": [{ "name": "runs", "mountPath": self.out }]
                        }],
                        "volumes": [{ "name": "runs", "persistentVolumeClaim": { "claimName": "catmap-runs" } }]
                    }
                }
            }
        });
        serde_json::to_string_pretty(&manifest).expect("a JSON value prints") + "\n"
    }
}

/// `text` as one shell word: as is when it holds only safe characters, else in single quotes.
pub fn shell_quoted(text: &str) -> String {
    let safe = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./:=+,@%".contains(c));
    if safe {
        text.to_owned()
    } else {
        format!("'{}'", text.replace('\'', "'\\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn command() -> SweepCommand {
        SweepCommand {
            name: "quick".into(),
            catmap: "/opt/catmap".into(),
            spec: "docs/sweeps/quick.toml".into(),
            out: "my runs".into(),
            jobs: 3,
        }
    }

    #[test]
    fn every_job_has_one_quoted_command_line() {
        assert_eq!(
            command().job_lines(),
            "/opt/catmap sweep docs/sweeps/quick.toml --out 'my runs' --only 0\n/opt/catmap sweep docs/sweeps/quick.toml --out 'my runs' --only 1\n/opt/catmap sweep docs/sweeps/quick.toml --out 'my runs' --only 2\n"
        );
        assert_eq!(shell_quoted("it's"), "'it'\\''s'");
        assert_eq!(shell_quoted(""), "''");
    }

    #[test]
    fn the_slurm_array_has_a_task_per_job_and_the_kubernetes_job_a_completion_per_job() {
        let slurm = command().recipe(Engine::Slurm);
        assert!(slurm.contains("#SBATCH --array=0-2\n"), "{slurm}");
        assert!(slurm.contains("--only \"$SLURM_ARRAY_TASK_ID\""), "{slurm}");
        let job: serde_json::Value = serde_json::from_str(&command().recipe(Engine::Kubernetes)).expect("JSON");
        assert_eq!(job["kind"], "Job");
        assert_eq!(job["spec"]["completionMode"], "Indexed");
        assert_eq!(job["spec"]["completions"], 3);
        let shell = job["spec"]["template"]["spec"]["containers"][0]["command"][2]
            .as_str()
            .expect("a command");
        assert!(shell.ends_with("--only \"$JOB_COMPLETION_INDEX\""), "{shell}");
        let parallel = command().recipe(Engine::GnuParallel);
        assert!(parallel.contains("parallel --jobs \"${JOBS:-2}\""), "{parallel}");
        assert!(parallel.contains("< 'my runs/jobs.txt'"), "{parallel}");
    }
}
