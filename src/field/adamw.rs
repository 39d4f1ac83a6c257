//! AdamW with PyTorch's semantics (`torch.optim.AdamW`, non-fused, no amsgrad), one state per field.
//!
//! ```text
//! t ← t + 1
//! p ← p · (1 − lr·wd)                           (decoupled weight decay, on every parameter)
//! m ← β1 m + (1 − β1) g        v ← β2 v + (1 − β2) g²
//! p ← p − (lr / (1 − β1^t)) · m / (√v / √(1 − β2^t) + ε)
//! ```
//!
//! Each field owns its moments and step count, so adding a field never resets another's state
//! (vMAP re-stacks all objects' parameters into a new optimiser group when an object appears,
//! which restarts every object's moments).

/// Hyper-parameters of AdamW.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdamWConfig {
    /// Learning rate.
    pub lr: f32,
    /// Decoupled weight decay.
    pub weight_decay: f32,
    /// β1.
    pub beta1: f32,
    /// β2.
    pub beta2: f32,
    /// ε.
    pub eps: f32,
}

impl Default for AdamWConfig {
    /// vMAP's values: lr 1e-3, weight decay 0.013, PyTorch's β and ε.
    fn default() -> Self {
        Self {
            lr: 1e-3,
            weight_decay: 0.013,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
        }
    }
}

impl AdamWConfig {
    /// Plain Adam (no weight decay) with learning rate `lr`.
    pub fn adam(lr: f32) -> Self {
        Self {
            lr,
            weight_decay: 0.0,
            ..Self::default()
        }
    }
}

/// One optimiser per field of `active`: `base` with its learning rate multiplied by the
/// field's scale (finite, positive; one per active field).
pub(crate) fn scaled_optimisers(
    base: &AdamWConfig,
    active: &[usize],
    learning_rate_scales: &[f32],
) -> crate::Result<Vec<AdamWConfig>> {
    if learning_rate_scales.len() != active.len() {
        return Err(crate::CatmapError::mismatch(
            "learning-rate scales of the fields to train",
            active.len(),
            learning_rate_scales.len(),
        ));
    }
    if let Some(bad) = learning_rate_scales.iter().find(|s| !(s.is_finite() && **s > 0.0)) {
        return Err(crate::CatmapError::bad_value(
            "a learning-rate scale",
            bad,
            "be positive and finite",
        ));
    }
    Ok(learning_rate_scales
        .iter()
        .map(|&scale| AdamWConfig {
            lr: base.lr * scale,
            ..*base
        })
        .collect())
}

/// First and second moments and the step count of one field.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AdamWState {
    /// First moments, one per parameter.
    pub m: Vec<f32>,
    /// Second moments, one per parameter.
    pub v: Vec<f32>,
    /// Steps taken.
    pub step: u64,
}

impl AdamWState {
    /// Zero state for `len` parameters.
    pub fn new(len: usize) -> Self {
        Self {
            m: vec![0.0; len],
            v: vec![0.0; len],
            step: 0,
        }
    }

    /// One AdamW step of `params` with gradient `grad`.
    pub fn update(&mut self, cfg: &AdamWConfig, params: &mut [f32], grad: &[f32]) {
        debug_assert!(params.len() == grad.len() && self.m.len() == params.len());
        self.step += 1;
        let t = self.step as i32;
        let bc1 = 1.0 - cfg.beta1.powi(t);
        let bc2_sqrt = (1.0 - cfg.beta2.powi(t)).sqrt();
        let step_size = cfg.lr / bc1;
        let decay = 1.0 - cfg.lr * cfg.weight_decay;
        for (((p, g), m), v) in params.iter_mut().zip(grad).zip(&mut self.m).zip(&mut self.v) {
            *p *= decay;
            *m = cfg.beta1 * *m + (1.0 - cfg.beta1) * g;
            *v = cfg.beta2 * *v + (1.0 - cfg.beta2) * g * g;
            let denom = v.sqrt() / bc2_sqrt + cfg.eps;
            *p -= step_size * *m / denom;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_step_moves_each_parameter_by_about_lr() {
        // Golden values from torch.optim.AdamW([p], lr=1e-3, weight_decay=0.013) with
        // p = [1.0, -2.0, 0.5], grad = [0.1, -0.3, 0.0]:
        // p·(1 − 1.3e-5) − 1e-3·sign(g) (m̂/√v̂ = ±1 on the first step, 0 for g = 0).
        let cfg = AdamWConfig::default();
        let mut p = [1.0f32, -2.0, 0.5];
        let mut state = AdamWState::new(3);
        state.update(&cfg, &mut p, &[0.1, -0.3, 0.0]);
        let want = [
            1.0 * (1.0 - 1.3e-5) - 1e-3,
            -2.0 * (1.0 - 1.3e-5) + 1e-3,
            0.5 * (1.0 - 1.3e-5),
        ];
        for (got, want) in p.iter().zip(want) {
            assert!((got - want).abs() < 1e-6, "{got} vs {want}");
        }
        assert_eq!(state.step, 1);
    }

    #[test]
    fn second_step_uses_bias_corrected_moments() {
        let cfg = AdamWConfig {
            weight_decay: 0.0,
            ..AdamWConfig::default()
        };
        let mut p = [0.0f32];
        let mut state = AdamWState::new(1);
        state.update(&cfg, &mut p, &[1.0]);
        state.update(&cfg, &mut p, &[3.0]);
        // m = 0.1·0.9 + 0.3 = 0.39, v = 0.001·0.999 + 0.009 = 0.009999
        let (m_hat, v_hat) = (0.39 / (1.0 - 0.81), 0.009_999 / (1.0 - 0.998_001));
        let want = -1e-3 - 1e-3 * m_hat / (f64::sqrt(v_hat) + 1e-8);
        assert!((f64::from(p[0]) - want).abs() < 1e-7, "{} vs {want}", p[0]);
    }
}
