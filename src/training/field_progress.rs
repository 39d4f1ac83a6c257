//! [`FieldProgress`]: what the step scheduler knows of one field, and how its [`FieldState`]
//! moves under the fast policy (see [`super::StepScheduler`]).

use serde::{Deserialize, Serialize};

use super::facts::{ClassShare, FieldFacts, FieldRole, Sighting, StreamPhase};
use super::plateau::{LossWindow, PlateauConfig};

/// Why a field is (not) training, as of the latest plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FieldState {
    /// It takes steps.
    Training,
    /// Its loss stopped falling.
    Converged,
    /// A supporting member's field between keyframes.
    Waiting,
    /// Frozen.
    Frozen,
}

/// What the scheduler knows of one field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldProgress {
    /// Steps it has taken.
    pub steps: u64,
    /// Its state after the latest plan.
    pub state: FieldState,
    /// Steps it had taken when it last converged.
    pub converged_at: Option<u64>,
    /// How many times its learning rate has been decayed since its latest new keyframe.
    #[serde(default)]
    pub decays: u32,
    window: LossWindow,
}

impl Default for FieldProgress {
    fn default() -> Self {
        Self {
            steps: 0,
            state: FieldState::Training,
            converged_at: None,
            decays: 0,
            window: LossWindow::default(),
        }
    }
}

impl FieldProgress {
    /// The state of a field under the fast policy (a new keyframe also restarts its window).
    /// After the stream, a plateau first decays the learning rate (up to
    /// `plateau.learning_rate_decays` times, each restarting the window); a new keyframe restores it.
    pub(super) fn advance(&mut self, facts: &FieldFacts, plateau: &PlateauConfig) -> FieldState {
        if facts.sighting == Sighting::NewKeyframe {
            self.window.clear();
            self.decays = 0;
        }
        match (facts.role, facts.sighting) {
            (FieldRole::Frozen, _) => FieldState::Frozen,
            (FieldRole::Supporting, Sighting::NewKeyframe) => FieldState::Training,
            (FieldRole::Supporting, _) => FieldState::Waiting,
            (FieldRole::Learning, Sighting::Seen | Sighting::NewKeyframe) => FieldState::Training,
            (FieldRole::Learning, Sighting::Unseen)
                if self.window.has_plateaued(plateau) && !self.below_minimum(facts, plateau) =>
            {
                if facts.phase == StreamPhase::Ended && self.decays < plateau.learning_rate_decays {
                    self.decays += 1;
                    self.window.clear();
                    FieldState::Training
                } else {
                    FieldState::Converged
                }
            }
            (FieldRole::Learning, Sighting::Unseen) => FieldState::Training,
        }
    }

    /// Whether the field has taken fewer steps than its class share asks before it may converge
    /// ([`PlateauConfig::min_steps_alone`] for an object alone in its class, none otherwise).
    fn below_minimum(&self, facts: &FieldFacts, plateau: &PlateauConfig) -> bool {
        facts.class == ClassShare::Alone && self.steps < plateau.min_steps_alone
    }

    /// Records the loss of a step it took.
    pub(super) fn record(&mut self, loss: f32, plateau: &PlateauConfig) {
        self.window.push(loss, plateau);
    }
}
