//! [`ScheduleConfig`]: how training steps are given out (`catmap run --schedule`).

use serde::{Deserialize, Serialize};

use super::plateau::PlateauConfig;
use super::scheduler::SchedulePolicy;

/// The training schedule. A config file lists only what it changes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScheduleConfig {
    /// `fast` (the default): each tick trains only the fields that gain from it (seen in the new
    /// frame, or whose loss still falls), category members' own fields rest once their category
    /// field makes their mesh, and one phase after the stream trains until every field has
    /// converged or `max_steps_after_stream`. `paper` (to reproduce the paper's protocol; ~3.7×
    /// the time, better completion of objects seen only from one side — see docs/BENCHMARKS.md): every
    /// field on every step, `fields.final_steps` refinement steps, then
    /// `category_fields.iterations` category steps. Offline runs always follow `paper`.
    pub policy: SchedulePolicy,
    /// When a field's loss counts as converged (fast schedule).
    pub plateau: PlateauConfig,
    /// Fast schedule: most steps of the phase after the stream.
    pub max_steps_after_stream: usize,
}

impl Default for ScheduleConfig {
    fn default() -> Self {
        Self {
            policy: SchedulePolicy::Fast,
            plateau: PlateauConfig::default(),
            max_steps_after_stream: 5_000,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_config_file_may_name_only_the_policy() {
        let cfg: ScheduleConfig = toml::from_str(r#"policy = "paper""#).expect("valid TOML");
        assert_eq!(
            cfg,
            ScheduleConfig {
                policy: SchedulePolicy::Paper,
                ..ScheduleConfig::default()
            }
        );
        assert!(
            toml::from_str::<ScheduleConfig>("polcy = 1").is_err(),
            "unknown keys are errors"
        );
    }
}
