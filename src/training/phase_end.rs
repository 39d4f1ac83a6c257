//! [`PhaseEnd`]: why a training phase after the stream ended.

use serde::{Deserialize, Serialize};

/// Why a training phase ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhaseEnd {
    /// No field gained from more steps (every one converged or frozen).
    Converged,
    /// The phase's step cap was reached.
    StepCap,
    /// A live run's finishing time after the stream (`stream.live.finish_seconds`) was spent.
    FinishTime,
}

impl PhaseEnd {
    /// Whether a phase that has run `done` of at most `cap` steps ends, given how many fields
    /// its latest plan trained (`planned`; none = nothing gains from more steps).
    pub fn of(done: u64, cap: u64, planned: usize) -> Option<Self> {
        if planned == 0 {
            Some(Self::Converged)
        } else if done >= cap {
            Some(Self::StepCap)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_phase_ends_when_nothing_trains_or_at_its_cap() {
        assert_eq!(PhaseEnd::of(50, 100, 3), None);
        assert_eq!(PhaseEnd::of(100, 100, 3), Some(PhaseEnd::StepCap));
        assert_eq!(PhaseEnd::of(50, 100, 0), Some(PhaseEnd::Converged));
    }
}
