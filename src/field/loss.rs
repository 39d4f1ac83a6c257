//! vMAP's per-object training loss (`loss.py::step_batch_loss`) on rendered rays.
//!
//! For one object, with masks over its R rays
//! `M_d = valid depth ∧ (this ∨ unknown)`, `M_c = this ∨ unknown`, `M_o = this ∨ other` (known):
//!
//! ```text
//! L_depth   = Σ_{M_d} |D̂ − d| / (√Var + 1e-4)  /  (|M_d| + 1e-10)
//! L_colour  = Σ_{M_c} Σ_rgb |Ĉ − c|            /  (|M_c| + 1e-10)
//! L_opacity = Σ_{M_o} |Ô − 1[this]|            /  (|M_o| + 1e-10)
//! L = L_depth + 5 L_colour + 10 L_opacity          (the batch total is Σ over objects)
//! ```
//!
//! Each term is a **mean over its masked rays** (sum over RGB inside the colour term), computed
//! per object and then summed over objects, exactly as vMAP's `reduce_batch_loss(avg=True)`.
//! A term whose mask is empty is 0 for that object (vMAP zeroes the term for *every* object of
//! the batch when any one object has an empty mask; we do not copy that quirk). |x| has
//! gradient sign(x) with sign(0) = 0 (PyTorch). Var carries no gradient.

use super::render::{RayRender, RenderGrad};
use super::samples::RaySamples;
use crate::objects::object_view::PixelState;

/// Weight of the colour term.
pub const COLOUR_WEIGHT: f32 = 5.0;
/// Weight of the opacity term.
pub const OPACITY_WEIGHT: f32 = 10.0;
/// Added to √Var in the depth term.
pub const DEPTH_STD_EPS: f32 = 1e-4;
/// Added to mask counts.
const COUNT_EPS: f32 = 1e-10;

/// One field's losses for one step (unweighted terms and the weighted total).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct FieldLosses {
    /// L_depth.
    pub depth: f32,
    /// L_colour (before the ×5).
    pub colour: f32,
    /// L_opacity (before the ×10).
    pub opacity: f32,
    /// L_depth + 5 L_colour + 10 L_opacity.
    pub total: f32,
}

impl FieldLosses {
    /// Sums two partial losses.
    pub(crate) fn add(self, o: Self) -> Self {
        Self {
            depth: self.depth + o.depth,
            colour: self.colour + o.colour,
            opacity: self.opacity + o.opacity,
            total: self.total + o.total,
        }
    }
}

/// The reciprocal mask counts of one field (0 where the mask is empty).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LossNorm {
    depth: f32,
    colour: f32,
    opacity: f32,
}

impl LossNorm {
    /// Counts the masks of `rays`.
    pub(crate) fn of(rays: &RaySamples) -> Self {
        let (mut nd, mut nc, mut no) = (0u32, 0u32, 0u32);
        for (state, depth) in rays.states.iter().zip(&rays.depth_m) {
            let obj = *state != PixelState::OtherObject;
            nd += u32::from(obj && *depth > 0.0);
            nc += u32::from(obj);
            no += u32::from(*state != PixelState::Unknown);
        }
        let inv = |n: u32| if n == 0 { 0.0 } else { 1.0 / (n as f32 + COUNT_EPS) };
        Self {
            depth: inv(nd),
            colour: inv(nc),
            opacity: inv(no),
        }
    }
}

/// sign(x) with sign(0) = 0.
fn sign(x: f32) -> f32 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// One ray's share of the losses and the gradient of the total with respect to its render.
pub(crate) fn ray_loss(
    r: &RayRender,
    depth_m: f32,
    rgb: [f32; 3],
    state: PixelState,
    norm: &LossNorm,
) -> (FieldLosses, RenderGrad) {
    let obj = state != PixelState::OtherObject;
    let known = state != PixelState::Unknown;
    let mut losses = FieldLosses::default();
    let mut grad = RenderGrad::default();
    if obj && depth_m > 0.0 {
        let info = 1.0 / (r.variance.sqrt() + DEPTH_STD_EPS);
        let res = r.depth - depth_m;
        losses.depth = res.abs() * info * norm.depth;
        grad.depth = sign(res) * info * norm.depth;
    }
    if obj {
        for ((g, rendered), measured) in grad.colour.iter_mut().zip(r.colour).zip(rgb) {
            let res = rendered - measured;
            losses.colour += res.abs() * norm.colour;
            *g = COLOUR_WEIGHT * sign(res) * norm.colour;
        }
    }
    if known {
        let target = if state == PixelState::ThisObject { 1.0 } else { 0.0 };
        let res = r.opacity - target;
        losses.opacity = res.abs() * norm.opacity;
        grad.opacity = OPACITY_WEIGHT * sign(res) * norm.opacity;
    }
    losses.total = losses.depth + COLOUR_WEIGHT * losses.colour + OPACITY_WEIGHT * losses.opacity;
    (losses, grad)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rays(states: Vec<PixelState>, depth_m: Vec<f32>) -> RaySamples {
        let n = states.len();
        RaySamples {
            samples_per_ray: 1,
            points: vec![[0.0; 3]; n],
            z: vec![1.0; n],
            depth_m,
            rgb: vec![[0.5; 3]; n],
            states,
            ..RaySamples::default()
        }
    }

    #[test]
    fn terms_are_means_over_their_masks() {
        use PixelState::{OtherObject as O, ThisObject as T, Unknown as U};
        let batch = rays(vec![T, O, U, T], vec![1.0, 1.0, 1.0, 0.0]);
        let norm = LossNorm::of(&batch);
        let r = RayRender {
            depth: 1.5,
            colour: [0.0; 3],
            opacity: 0.25,
            variance: 0.0,
        };
        let total = (0..4)
            .map(|i| ray_loss(&r, batch.depth_m[i], batch.rgb[i], batch.states[i], &norm).0)
            .fold(FieldLosses::default(), FieldLosses::add);
        // depth mask: rays 0 and 2 (ray 3 has no depth) → mean 0.5 / 1e-4.
        assert!((total.depth - 5000.0).abs() < 0.5, "{total:?}");
        // colour mask: rays 0, 2, 3 → Σ_rgb |0 − 0.5| = 1.5 each.
        assert!((total.colour - 1.5).abs() < 1e-5, "{total:?}");
        // opacity mask: rays 0, 1, 3 → (0.75 + 0.25 + 0.75) / 3.
        assert!((total.opacity - 1.75 / 3.0).abs() < 1e-6, "{total:?}");
    }

    #[test]
    fn an_empty_mask_gives_a_zero_term() {
        let batch = rays(vec![PixelState::OtherObject; 2], vec![1.0, 1.0]);
        let norm = LossNorm::of(&batch);
        let r = RayRender {
            depth: 3.0,
            colour: [1.0; 3],
            opacity: 0.5,
            variance: 0.1,
        };
        let (l, g) = ray_loss(&r, 1.0, [0.0; 3], PixelState::OtherObject, &norm);
        assert_eq!(
            (l.depth, l.colour, g.depth, g.colour),
            (0.0, 0.0, 0.0, [0.0; 3]),
            "other-object rays only teach free space"
        );
        assert!((l.opacity - 0.25).abs() < 1e-6 && (g.opacity - 5.0).abs() < 1e-5);
    }
}
