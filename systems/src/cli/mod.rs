//! The `catmap` binary's own modules: one per subcommand (`run`, `synth`, `eval`, `compare`, `config`, `sweep`, `report`), and
//! what `run` is made of — the run plan (what was asked, saved in checkpoints), its phases with
//! checkpoints (`run_phases`), the files it writes (`run_outputs`) and progress bars; and `--color`.

pub mod color;
pub mod compare;
pub mod config;
pub mod eval;
pub mod progress;
pub mod report;
pub mod run;
pub mod run_outputs;
pub mod run_phases;
pub mod run_plan;
pub mod sensor_choice;
pub mod sweep;
pub mod synth;
