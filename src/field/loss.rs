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
//! Prior rays (`PixelState::HiddenSolid`, samples in cells of the object's box no view saw into,
//! [`crate::objects::hidden_space`]) render nothing: each of their samples adds
//! `L_solid = Σ_hidden −ln o / |hidden samples|`, weighted by the rays' `solid_weight`, asking it to
//! be solid (the gradient of the raw α is `ALPHA_SCALE · (o − 1)`, which does not vanish where the
//! field is empty). The samples of the priors asking for empty space (`BelowSupport`, `SeenFree`)
//! add −ln(1 − o) instead ([`PixelState::sample_target`] 0).
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
    /// L_solid, the prior on samples no view saw into (before its weight; 0 without prior rays).
    #[serde(default)]
    pub solid: f32,
    /// L_depth + 5 L_colour + 10 L_opacity + w L_solid.
    pub total: f32,
}

impl FieldLosses {
    /// Sums two partial losses.
    pub(crate) fn add(self, o: Self) -> Self {
        Self {
            depth: self.depth + o.depth,
            colour: self.colour + o.colour,
            opacity: self.opacity + o.opacity,
            solid: self.solid + o.solid,
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
    /// Over the prior samples' count.
    solid: f32,
    /// The solid prior's weight.
    solid_weight: f32,
}

impl LossNorm {
    /// Counts the masks of `rays`.
    pub(crate) fn of(rays: &RaySamples) -> Self {
        let (mut nd, mut nc, mut no, mut nh) = (0u32, 0u32, 0u32, 0u32);
        for (state, depth) in rays.states.iter().zip(&rays.depth_m) {
            let obj = state.reads_colour();
            nd += u32::from(obj && *depth > 0.0);
            nc += u32::from(obj);
            no += u32::from(state.opacity_target().is_some());
            nh += u32::from(state.sample_target().is_some());
        }
        let inv = |n: u32| if n == 0 { 0.0 } else { 1.0 / (n as f32 + COUNT_EPS) };
        Self {
            depth: inv(nd),
            colour: inv(nc),
            opacity: inv(no),
            solid: inv(nh * rays.samples_per_ray as u32),
            solid_weight: rays.solid_weight,
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
    let obj = state.reads_colour();
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
    if let Some(target) = state.opacity_target() {
        let res = r.opacity - target;
        losses.opacity = res.abs() * norm.opacity;
        grad.opacity = OPACITY_WEIGHT * sign(res) * norm.opacity;
    }
    losses.total = losses.depth + COLOUR_WEIGHT * losses.colour + OPACITY_WEIGHT * losses.opacity;
    (losses, grad)
}

/// The smallest occupancy the solid prior's −ln o is taken of (a sample carved empty has o ≈ 0).
const MIN_SOLID_OCCUPANCY: f32 = 1e-30;

/// One prior sample's share of the losses (L_solid's −ln o / count, and its weighted share of
/// the total) and the gradient of the total with respect to its raw α head output,
/// `ALPHA_SCALE · (o − 1) · weight / count` (o = sigmoid(ALPHA_SCALE · raw)).
pub(crate) fn solid_sample_loss(occupancy: f32, target: f32, norm: &LossNorm) -> (FieldLosses, f32) {
    let agreeing = if target > 0.5 { occupancy } else { 1.0 - occupancy };
    let solid = -agreeing.max(MIN_SOLID_OCCUPANCY).ln() * norm.solid;
    let losses = FieldLosses {
        solid,
        total: norm.solid_weight * solid,
        ..FieldLosses::default()
    };
    let grad = super::heads::ALPHA_SCALE * (occupancy - target) * norm.solid_weight * norm.solid;
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
