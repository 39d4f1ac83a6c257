//! [`LossWindow`]: has a field's training loss stopped falling?
//!
//! The per-step loss of a field is noisy (every step draws new rays), so single steps are never
//! compared. The window keeps the latest `2·W` losses; the field has *plateaued* when the mean of
//! the newest `W` is not at least `min_relative_drop` below the mean of the `W` before them.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

/// When a loss counts as no longer falling. A config file lists only what it changes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlateauConfig {
    /// Steps per window: the mean loss of the newest window is compared with the window before
    /// it, so a field trains at least twice this many steps before it can converge.
    pub window_steps: usize,
    /// The loss still falls while the newest window's mean is at least this fraction below the
    /// previous window's (0.01 = 1 %).
    pub min_relative_drop: f32,
    /// After the stream, a field whose loss has plateaued has its learning rate multiplied by
    /// `learning_rate_decay` and trains on, up to this many times, before it counts as
    /// converged (0: it converges at its first plateau). The lower rate averages out the noise
    /// of the sampled rays, which a fixed rate leaves in the surface.
    pub learning_rate_decays: u32,
    /// The factor of each decay (in (0, 1]).
    pub learning_rate_decay: f32,
    /// Steps the field of an object alone in its class takes before its loss may count as
    /// plateaued. Seen in a few frames only (a lamp at the edge of the first views), such a field
    /// reaches a plateau of its total loss in a few hundred steps, before its thin parts (a pole
    /// seen in two keyframes) have formed; no category field completes it later. Objects with
    /// twins and category fields converge at their first plateau.
    pub min_steps_alone: u64,
}

impl Default for PlateauConfig {
    fn default() -> Self {
        Self {
            window_steps: 100,
            min_relative_drop: 0.01,
            learning_rate_decays: 2,
            learning_rate_decay: 0.3,
            min_steps_alone: 2000,
        }
    }
}

impl PlateauConfig {
    /// The learning rate's factor after `decays` decays.
    pub fn learning_rate_scale(&self, decays: u32) -> f32 {
        self.learning_rate_decay.powi(decays.min(i32::MAX as u32) as i32)
    }
}

/// The latest losses of one field.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct LossWindow {
    losses: VecDeque<f32>,
}

impl LossWindow {
    /// Adds the loss of one step (non-finite losses are ignored), keeping the newest `2·W`.
    pub fn push(&mut self, loss: f32, cfg: &PlateauConfig) {
        if !loss.is_finite() {
            return;
        }
        self.losses.push_back(loss);
        while self.losses.len() > 2 * cfg.window_steps.max(1) {
            self.losses.pop_front();
        }
    }

    /// Forgets every loss (the field's data changed, e.g. a new keyframe).
    pub fn clear(&mut self) {
        self.losses.clear();
    }

    /// Losses held.
    pub fn len(&self) -> usize {
        self.losses.len()
    }

    /// Whether no loss is held.
    pub fn is_empty(&self) -> bool {
        self.losses.is_empty()
    }

    /// Whether two full windows are held and the newer one's mean is not at least
    /// `min_relative_drop` below the older one's.
    pub fn has_plateaued(&self, cfg: &PlateauConfig) -> bool {
        let w = cfg.window_steps.max(1);
        if self.losses.len() < 2 * w {
            return false;
        }
        let mean =
            |values: std::collections::vec_deque::Iter<'_, f32>| values.map(|&v| f64::from(v)).sum::<f64>() / w as f64;
        let older = mean(self.losses.range(..w));
        let newer = mean(self.losses.range(w..));
        newer > older * (1.0 - f64::from(cfg.min_relative_drop))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CFG: PlateauConfig = PlateauConfig {
        window_steps: 4,
        min_relative_drop: 0.05,
        learning_rate_decays: 0,
        learning_rate_decay: 1.0,
        min_steps_alone: 0,
    };

    fn window(losses: &[f32]) -> LossWindow {
        let mut w = LossWindow::default();
        for &l in losses {
            w.push(l, &CFG);
        }
        w
    }

    #[test]
    fn a_loss_that_keeps_falling_has_not_plateaued() {
        let falling: Vec<f32> = (0..20).map(|i| 10.0 * 0.9f32.powi(i)).collect();
        assert!(!window(&falling).has_plateaued(&CFG));
    }

    #[test]
    fn a_flat_noisy_loss_has_plateaued() {
        let flat = [1.0, 1.1, 0.9, 1.05, 0.95, 1.0, 1.1, 0.92];
        assert!(window(&flat).has_plateaued(&CFG));
    }

    #[test]
    fn fewer_than_two_windows_never_plateau_and_clear_starts_over() {
        let mut w = window(&[1.0; 7]);
        assert!(!w.has_plateaued(&CFG), "7 of 8 losses");
        w.push(1.0, &CFG);
        assert!(w.has_plateaued(&CFG), "8 equal losses");
        w.clear();
        assert!(w.is_empty() && !w.has_plateaued(&CFG));
    }

    #[test]
    fn only_the_newest_two_windows_count_and_non_finite_losses_are_ignored() {
        let mut w = window(&[100.0, 90.0, 80.0, 70.0]);
        for &l in &[1.0, f32::NAN, 1.0, 1.0, f32::INFINITY, 1.0, 1.0, 1.0, 1.0, 1.0] {
            w.push(l, &CFG);
        }
        assert_eq!(w.len(), 8, "the window holds 2·W finite losses");
        assert!(w.has_plateaued(&CFG), "the old, falling losses dropped out");
    }
}
