//! The heads every network ends in, and what a fused training pass does between its forward and
//! backward halves: the raw α and colour head outputs, their sigmoids, the rendering of a chunk's
//! rays, vMAP's losses, and the gradients of the raw head outputs (before the sigmoids), ready
//! for the network's backward pass. Shared by the per-object occupancy network and the category
//! network.

use std::ops::Range;

use super::loss::{FieldLosses, LossNorm, ray_loss, solid_sample_loss};
use super::render::{render_ray, render_ray_backward, sigmoid};
use super::samples::RaySamples;

/// α = ALPHA_SCALE · raw α head output (vMAP's "unisurf" scaling), in every network.
pub const ALPHA_SCALE: f32 = 10.0;

/// Head gradients of smaller magnitude are written as 0. They come from saturated sigmoids
/// (a sample carved empty, o ≈ e^−α) and from transmittances behind an opaque sample
/// (T ≈ 1e-10 per opaque sample passed); left as they are, the backward products turn them
/// into subnormal floats, which x86 processors handle in microcode, up to ~100× slower per
/// operation: on the default scene they made the category fields' training 1.5× slower. A
/// gradient this small is below float32's resolution of any sum of ordinary gradients it joins.
pub const TINY_GRADIENT: f32 = 1e-30;

/// `x`, or 0 when `|x| <` [`TINY_GRADIENT`].
#[inline]
fn flush_tiny(x: f32) -> f32 {
    if x.abs() < TINY_GRADIENT { 0.0 } else { x }
}

/// Row stride of the raw head outputs and their gradients (one padded row per sample).
pub(crate) const HEAD_LD: usize = 16;

/// A chunk's per-sample head buffers, indexed from the chunk's first sample.
#[derive(Debug, Default)]
pub struct HeadBuffers {
    /// Raw α head output (column 0 of rows of [`HEAD_LD`]), written by the network.
    pub(crate) alpha_raw: Vec<f32>,
    /// Raw colour head output (columns 0..3 of rows of [`HEAD_LD`]), written by the network.
    pub(crate) colour_raw: Vec<f32>,
    /// Occupancy `o = sigmoid(ALPHA_SCALE · α)` of each sample.
    occ: Vec<f32>,
    /// Colour (after the sigmoid) of each sample.
    rgb: Vec<[f32; 3]>,
    /// Rendering weights.
    weights: Vec<f32>,
    /// Transmittance.
    trans: Vec<f32>,
    /// ∂L/∂o.
    d_occ: Vec<f32>,
    /// ∂L/∂colour.
    d_rgb: Vec<[f32; 3]>,
    /// ∂L/∂(raw α), rows of [`HEAD_LD`].
    pub(crate) d_alpha: Vec<f32>,
    /// ∂L/∂(raw colour), rows of [`HEAD_LD`].
    pub(crate) d_colour: Vec<f32>,
}

fn ensure<T: Copy + Default>(buf: &mut Vec<T>, len: usize) {
    if buf.len() < len {
        buf.resize(len, T::default());
    }
}

impl HeadBuffers {
    /// Makes room for `n` samples.
    pub(crate) fn reserve(&mut self, n: usize) {
        for b in [
            &mut self.alpha_raw,
            &mut self.colour_raw,
            &mut self.d_alpha,
            &mut self.d_colour,
        ] {
            ensure(b, n * HEAD_LD);
        }
        for b in [&mut self.occ, &mut self.weights, &mut self.trans, &mut self.d_occ] {
            ensure(b, n);
        }
        ensure(&mut self.rgb, n);
        ensure(&mut self.d_rgb, n);
    }

    /// Occupancies of the first `n` samples from the raw α head.
    pub(crate) fn occupancy_from_raw(&mut self, n: usize) {
        for (o, a) in self.occ[..n].iter_mut().zip(self.alpha_raw.chunks_exact(HEAD_LD)) {
            *o = sigmoid(ALPHA_SCALE * a[0]);
        }
    }

    /// Colours of the first `nc` of `n` samples from the raw colour head; the others' are 0.
    pub(crate) fn colour_from_raw(&mut self, nc: usize, n: usize) {
        for (c, r) in self.rgb[..nc].iter_mut().zip(self.colour_raw.chunks_exact(HEAD_LD)) {
            *c = [sigmoid(r[0]), sigmoid(r[1]), sigmoid(r[2])];
        }
        self.rgb[nc..n].fill([0.0; 3]);
    }

    /// Occupancy of the first `n` samples.
    pub(crate) fn occupancy(&self, n: usize) -> &[f32] {
        &self.occ[..n]
    }

    /// α (= `ALPHA_SCALE` · raw) of the first `n` samples.
    pub(crate) fn alpha(&self, n: usize) -> Vec<f32> {
        self.alpha_raw
            .chunks_exact(HEAD_LD)
            .take(n)
            .map(|a| ALPHA_SCALE * a[0])
            .collect()
    }

    /// Colour of the first `n` samples.
    pub(crate) fn colour(&self, n: usize) -> &[[f32; 3]] {
        &self.rgb[..n]
    }

    /// The samples of rays `rays_range` of `rays` up to the last ray whose colour the loss
    /// reads (this object's or unknown pixels; rays of other objects' pixels only teach free
    /// space, and the sampler puts them last).
    pub(crate) fn colour_prefix(rays: &RaySamples, rays_range: Range<usize>) -> usize {
        let last = rays.states[rays_range]
            .iter()
            .rposition(|s| s.reads_colour())
            .map_or(0, |i| i + 1);
        last * rays.samples_per_ray
    }

    /// Renders rays `rays_range` of `rays` from the occupancies and colours, returns the chunk's
    /// share of the losses (normalised by `norm`) and writes the gradients of the raw heads.
    pub(crate) fn render_loss_backward(
        &mut self,
        rays: &RaySamples,
        rays_range: Range<usize>,
        norm: &LossNorm,
    ) -> FieldLosses {
        let spr = rays.samples_per_ray;
        let n = rays_range.len() * spr;
        let z = &rays.z[rays_range.start * spr..rays_range.end * spr];
        let mut losses = FieldLosses::default();
        self.d_alpha[..n * HEAD_LD].fill(0.0);
        self.d_colour[..n * HEAD_LD].fill(0.0);
        for (i, ray) in rays_range.enumerate() {
            let r = i * spr..(i + 1) * spr;
            if let Some(target) = rays.states[ray].sample_target() {
                for k in r {
                    let (l, d_alpha) = solid_sample_loss(self.occ[k], target, norm);
                    losses = losses.add(l);
                    self.d_alpha[k * HEAD_LD] = flush_tiny(d_alpha);
                }
                continue;
            }
            let (o, c, zr) = (&self.occ[r.clone()], &self.rgb[r.clone()], &z[r.clone()]);
            let render = render_ray(o, c, zr, &mut self.weights[r.clone()], &mut self.trans[r.clone()]);
            let (l, g) = ray_loss(&render, rays.depth_m[ray], rays.rgb[ray], rays.states[ray], norm);
            losses = losses.add(l);
            let (w, t) = (&self.weights[r.clone()], &self.trans[r.clone()]);
            render_ray_backward(
                &g,
                o,
                c,
                zr,
                w,
                t,
                &mut self.d_occ[r.clone()],
                &mut self.d_rgb[r.clone()],
            );
            for k in r {
                let o = self.occ[k];
                self.d_alpha[k * HEAD_LD] = flush_tiny(ALPHA_SCALE * self.d_occ[k] * o * (1.0 - o));
                for ch in 0..3 {
                    let v = self.rgb[k][ch];
                    self.d_colour[k * HEAD_LD + ch] = flush_tiny(self.d_rgb[k][ch] * v * (1.0 - v));
                }
            }
        }
        losses
    }
}
