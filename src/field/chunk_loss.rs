//! The middle of a fused training pass, shared by every network: render a chunk's rays from the
//! heads' outputs, add up vMAP's losses, and turn their gradients into gradients of the raw
//! head outputs (before the sigmoids), ready for the network's backward pass.

use std::ops::Range;

use super::loss::{FieldLosses, LossNorm, ray_loss};
use super::occupancy::ALPHA_SCALE;
use super::render::{render_ray, render_ray_backward};
use super::samples::RaySamples;

/// Row stride of the head-gradient buffers (one padded row per sample).
pub(crate) const HEAD_LD: usize = 16;

/// One chunk's per-sample buffers, indexed from the chunk's first sample.
#[derive(Debug)]
pub(crate) struct ChunkHeads<'a> {
    /// Occupancy `o = sigmoid(α)` of each sample.
    pub occ: &'a [f32],
    /// Colour (after the sigmoid) of each sample.
    pub rgb: &'a [[f32; 3]],
    /// Rendering weights (written).
    pub weights: &'a mut [f32],
    /// Transmittance (written).
    pub trans: &'a mut [f32],
    /// ∂L/∂o (written).
    pub d_occ: &'a mut [f32],
    /// ∂L/∂colour (written).
    pub d_rgb: &'a mut [[f32; 3]],
    /// ∂L/∂(raw alpha head), column 0 of rows of [`HEAD_LD`] (the rest zeroed).
    pub d_alpha: &'a mut [f32],
    /// ∂L/∂(raw colour head), columns 0..3 of rows of [`HEAD_LD`] (the rest zeroed).
    pub d_colour: &'a mut [f32],
}

/// Renders rays `rays_range` of `rays` from `heads`, returns the chunk's share of the losses
/// (normalised by `norm`) and writes the head gradients into `heads`.
pub(crate) fn render_loss_backward(
    rays: &RaySamples,
    rays_range: Range<usize>,
    norm: &LossNorm,
    heads: ChunkHeads<'_>,
) -> FieldLosses {
    let spr = rays.samples_per_ray;
    let n = rays_range.len() * spr;
    let z = &rays.z[rays_range.start * spr..rays_range.end * spr];
    let ChunkHeads {
        occ,
        rgb,
        weights,
        trans,
        d_occ,
        d_rgb,
        d_alpha,
        d_colour,
    } = heads;
    let mut losses = FieldLosses::default();
    d_alpha[..n * HEAD_LD].fill(0.0);
    d_colour[..n * HEAD_LD].fill(0.0);
    for (i, ray) in rays_range.enumerate() {
        let r = i * spr..(i + 1) * spr;
        let (o, c, zr) = (&occ[r.clone()], &rgb[r.clone()], &z[r.clone()]);
        let render = render_ray(o, c, zr, &mut weights[r.clone()], &mut trans[r.clone()]);
        let (l, g) = ray_loss(&render, rays.depth_m[ray], rays.rgb[ray], rays.states[ray], norm);
        losses = losses.add(l);
        let (w, t) = (&weights[r.clone()], &trans[r.clone()]);
        render_ray_backward(&g, o, c, zr, w, t, &mut d_occ[r.clone()], &mut d_rgb[r.clone()]);
        for k in r {
            let o = occ[k];
            d_alpha[k * HEAD_LD] = ALPHA_SCALE * d_occ[k] * o * (1.0 - o);
            for ch in 0..3 {
                let v = rgb[k][ch];
                d_colour[k * HEAD_LD + ch] = d_rgb[k][ch] * v * (1.0 - v);
            }
        }
    }
    losses
}
