//! A linear layer `y = W [x_0 ‖ x_1 ‖ …] + b` on sample-major chunks, with its input split into
//! segments (vMAP's skip concatenations), packed for [`super::gemm`].
//!
//! Canonical storage is PyTorch's: `W` is `[out, in]` row-major inside the field's flat
//! parameter vector. Before a step the weights are repacked into panels:
//!
//! * forward, per segment s of width K_s: `Wᵀ_s` as `⌈out/16⌉` panels of `K_s × 16`;
//! * input gradient, per segment: `W_s` as `⌈K_s/16⌉` panels of `out × 16`;
//!
//! and the gradient is accumulated as `dWᵀ_s` (`K_s × out_pad`, row-major) plus a padded bias
//! gradient, and unpacked into canonical order once per step. Padding lanes are zero.

use super::gemm::{ALayout, Gemm, Init, PANEL, Post, add_column_sums, padded};
use super::narrow_gradient::{NARROW_OUTPUTS, add_narrow_weight_gradient};
use super::simd::Backend;

/// Activation applied by [`Dense::forward`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Activation {
    /// None.
    Linear,
    /// ReLU.
    Relu,
}

/// A sample-major matrix: `n` rows with stride `ld`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rows<'a> {
    /// Values; row `s` starts at `s * ld`.
    pub data: &'a [f32],
    /// Row stride.
    pub ld: usize,
}

impl<'a> Rows<'a> {
    /// Rows of `data` with stride `ld`.
    pub(crate) fn new(data: &'a [f32], ld: usize) -> Self {
        Self { data, ld }
    }
}

/// One packed linear layer; see the module doc.
#[derive(Debug, Clone)]
pub(crate) struct Dense {
    /// Output width.
    pub out: usize,
    /// Output width padded to whole panels (row stride of outputs).
    pub out_pad: usize,
    /// Input segment widths.
    pub segments: Vec<usize>,
    weight: usize,
    bias: usize,
    fwd: Vec<usize>,
    bwd: Vec<usize>,
    packed_bias: usize,
    grad_w: Vec<usize>,
    grad_b: usize,
}

/// Allocates packed-weight and packed-gradient offsets for a sequence of layers.
#[derive(Debug, Default)]
pub(crate) struct PackingPlan {
    /// Floats of packed weights.
    pub packed_len: usize,
    /// Floats of packed gradients.
    pub grad_len: usize,
}

impl PackingPlan {
    /// A layer with canonical weight at `weight` (`[out, Σ segments]`) and bias at `bias`.
    pub(crate) fn dense(&mut self, weight: usize, bias: usize, out: usize, segments: &[usize]) -> Dense {
        let out_pad = padded(out);
        let mut fwd = Vec::new();
        let mut bwd = Vec::new();
        let mut grad_w = Vec::new();
        for &k in segments {
            fwd.push(self.packed_len);
            self.packed_len += k * out_pad;
            bwd.push(self.packed_len);
            self.packed_len += out * padded(k);
            grad_w.push(self.grad_len);
            self.grad_len += k * out_pad;
        }
        let packed_bias = self.packed_len;
        self.packed_len += out_pad;
        let grad_b = self.grad_len;
        self.grad_len += out_pad;
        Dense {
            out,
            out_pad,
            segments: segments.to_vec(),
            weight,
            bias,
            fwd,
            bwd,
            packed_bias,
            grad_w,
            grad_b,
        }
    }

    /// Reserves `len` floats of packed gradient for a non-dense parameter; returns the offset.
    pub(crate) fn extra_grad(&mut self, len: usize) -> usize {
        self.grad_len += len;
        self.grad_len - len
    }
}

impl Dense {
    fn in_total(&self) -> usize {
        self.segments.iter().sum()
    }

    fn segment_start(&self, seg: usize) -> usize {
        self.segments[..seg].iter().sum()
    }

    /// Writes this layer's panels into `packed` from the canonical `params`.
    pub(crate) fn pack(&self, params: &[f32], packed: &mut [f32]) {
        let inp = self.in_total();
        let w = &params[self.weight..self.weight + self.out * inp];
        for (seg, &k) in self.segments.iter().enumerate() {
            let c0 = self.segment_start(seg);
            let fwd = &mut packed[self.fwd[seg]..self.fwd[seg] + k * self.out_pad];
            fwd.fill(0.0);
            for o in 0..self.out {
                let (j, l) = (o / PANEL, o % PANEL);
                for kk in 0..k {
                    fwd[j * k * PANEL + kk * PANEL + l] = w[o * inp + c0 + kk];
                }
            }
            let bwd = &mut packed[self.bwd[seg]..self.bwd[seg] + self.out * padded(k)];
            bwd.fill(0.0);
            for o in 0..self.out {
                for i in 0..k {
                    let (j, l) = (i / PANEL, i % PANEL);
                    bwd[j * self.out * PANEL + o * PANEL + l] = w[o * inp + c0 + i];
                }
            }
        }
        let bias = &mut packed[self.packed_bias..self.packed_bias + self.out_pad];
        bias.fill(0.0);
        bias[..self.out].copy_from_slice(&params[self.bias..self.bias + self.out]);
    }

    /// `y = act(Σ_s x_s W_sᵀ + b)` for `n` samples; `y` has row stride `out_pad`.
    pub(crate) fn forward(
        &self,
        backend: Backend,
        packed: &[f32],
        n: usize,
        inputs: &[Rows<'_>],
        y: &mut [f32],
        act: Activation,
    ) {
        debug_assert_eq!(inputs.len(), self.segments.len());
        let last = inputs.len() - 1;
        for (seg, x) in inputs.iter().enumerate() {
            let k = self.segments[seg];
            let init = if seg == 0 {
                Init::Bias(&packed[self.packed_bias..self.packed_bias + self.out_pad])
            } else {
                Init::Accumulate
            };
            let post = if seg == last && act == Activation::Relu {
                Post::Relu
            } else {
                Post::Identity
            };
            Gemm {
                m: n,
                k,
                n: self.out_pad,
                a: x.data,
                a_layout: ALayout::Rows,
                lda: x.ld,
                b: &packed[self.fwd[seg]..],
                b_panel_stride: k * PANEL,
                b_row_stride: PANEL,
                c: y,
                ldc: self.out_pad,
                init,
                post,
            }
            .run(backend);
        }
    }

    /// Accumulates `dWᵀ_s += x_sᵀ dy` and `db += Σ dy` into the packed gradient `grad` (a layer of
    /// at most [`NARROW_OUTPUTS`] outputs sums scaled input rows, bit-identically:
    /// [`super::narrow_gradient`]).
    pub(crate) fn backward_weights(
        &self,
        backend: Backend,
        n: usize,
        inputs: &[Rows<'_>],
        dy: Rows<'_>,
        grad: &mut [f32],
    ) {
        for (seg, x) in inputs.iter().enumerate() {
            let k = self.segments[seg];
            let grad_w = &mut grad[self.grad_w[seg]..self.grad_w[seg] + k * self.out_pad];
            if self.out <= NARROW_OUTPUTS {
                add_narrow_weight_gradient(backend, n, *x, k, dy, self.out, grad_w, self.out_pad);
                continue;
            }
            Gemm {
                m: k,
                k: n,
                n: self.out_pad,
                a: x.data,
                a_layout: ALayout::Cols,
                lda: x.ld,
                b: dy.data,
                b_panel_stride: PANEL,
                b_row_stride: dy.ld,
                c: grad_w,
                ldc: self.out_pad,
                init: Init::Accumulate,
                post: Post::Identity,
            }
            .run(backend);
        }
        add_column_sums(
            backend,
            dy.data,
            n,
            dy.ld,
            &mut grad[self.grad_b..self.grad_b + self.out_pad],
        );
    }

    /// `dx_s = post(init + dy W_s)` for segment `seg`; `dx` has `padded(K_s)` useful columns.
    pub(crate) fn backward_input(
        &self,
        backend: Backend,
        packed: &[f32],
        n: usize,
        seg: usize,
        dy: Rows<'_>,
        dx: &mut [f32],
        ldx: usize,
        init: Init<'_>,
        post: Post<'_>,
    ) {
        let k = self.segments[seg];
        Gemm {
            m: n,
            k: self.out,
            n: padded(k),
            a: dy.data,
            a_layout: ALayout::Rows,
            lda: dy.ld,
            b: &packed[self.bwd[seg]..],
            b_panel_stride: self.out * PANEL,
            b_row_stride: PANEL,
            c: dx,
            ldc: ldx,
            init,
            post,
        }
        .run(backend);
    }

    /// Adds the packed gradient of this layer into the canonical gradient `out`.
    pub(crate) fn unpack_grad(&self, grad: &[f32], out: &mut [f32]) {
        let inp = self.in_total();
        for (seg, &k) in self.segments.iter().enumerate() {
            let c0 = self.segment_start(seg);
            let g = &grad[self.grad_w[seg]..self.grad_w[seg] + k * self.out_pad];
            for o in 0..self.out {
                let row = &mut out[self.weight + o * inp + c0..self.weight + o * inp + c0 + k];
                for (i, d) in row.iter_mut().enumerate() {
                    *d += g[i * self.out_pad + o];
                }
            }
        }
        for (d, g) in out[self.bias..self.bias + self.out]
            .iter_mut()
            .zip(&grad[self.grad_b..])
        {
            *d += g;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forward_and_gradients_of_a_two_segment_layer_match_the_formula() {
        // y = relu(W [a ‖ b] + bias), out = 3, a: 2 wide, b: 5 wide, 4 samples.
        let (out, ka, kb, n) = (3, 2, 5, 4);
        let params: Vec<f32> = (0..out * (ka + kb) + out)
            .map(|i| ((i * 37 % 19) as f32 - 9.0) / 10.0)
            .collect();
        let mut plan = PackingPlan::default();
        let layer = plan.dense(0, out * (ka + kb), out, &[ka, kb]);
        let mut packed = vec![0.0; plan.packed_len];
        layer.pack(&params, &mut packed);
        let a: Vec<f32> = (0..n * ka).map(|i| (i as f32 * 0.37).sin()).collect();
        let b: Vec<f32> = (0..n * kb).map(|i| (i as f32 * 0.91).cos()).collect();
        let inputs = [Rows { data: &a, ld: ka }, Rows { data: &b, ld: kb }];
        let mut y = vec![0.0; n * layer.out_pad];
        let backend = Backend::detect();
        layer.forward(backend, &packed, n, &inputs, &mut y, Activation::Linear);
        let w = |o: usize, i: usize| params[o * (ka + kb) + i];
        let x = |s: usize, i: usize| if i < ka { a[s * ka + i] } else { b[s * kb + i - ka] };
        for s in 0..n {
            for o in 0..out {
                let want: f32 = params[out * (ka + kb) + o] + (0..ka + kb).map(|i| w(o, i) * x(s, i)).sum::<f32>();
                assert!((y[s * layer.out_pad + o] - want).abs() < 1e-5, "y[{s},{o}]");
            }
        }
        // Gradients of L = Σ y ⊙ dy.
        let dy: Vec<f32> = (0..n * layer.out_pad)
            .map(|i| if i % 16 < out { (i as f32 * 0.13).sin() } else { 0.0 })
            .collect();
        let mut grad = vec![0.0; plan.grad_len];
        layer.backward_weights(
            backend,
            n,
            &inputs,
            Rows {
                data: &dy,
                ld: layer.out_pad,
            },
            &mut grad,
        );
        let mut canonical = vec![0.0; params.len()];
        layer.unpack_grad(&grad, &mut canonical);
        for o in 0..out {
            for i in 0..ka + kb {
                let want: f32 = (0..n).map(|s| dy[s * 16 + o] * x(s, i)).sum();
                assert!((canonical[o * (ka + kb) + i] - want).abs() < 1e-5, "dW[{o},{i}]");
            }
            let want: f32 = (0..n).map(|s| dy[s * 16 + o]).sum();
            assert!((canonical[out * (ka + kb) + o] - want).abs() < 1e-5, "db[{o}]");
        }
        let mut db = vec![0.0; n * 16];
        layer.backward_input(
            backend,
            &packed,
            n,
            1,
            Rows { data: &dy, ld: 16 },
            &mut db,
            16,
            Init::Zero,
            Post::Identity,
        );
        for s in 0..n {
            for i in 0..kb {
                let want: f32 = (0..out).map(|o| dy[s * 16 + o] * w(o, ka + i)).sum();
                assert!((db[s * 16 + i] - want).abs() < 1e-5, "dx_b[{s},{i}]");
            }
        }
    }
}
