//! [`MlpBatch`]: B plain ReLU MLPs (`d0 → d1 → … → dL`, linear output) with an L1 loss, trained
//! in one fused batched step by the same machinery as [`super::super::FieldBatch`].
//!
//! This is the benchmark shape of FACTS.md (B = 16 MLPs 39→32→32→32→4, N = 1200 points each):
//! `L_b = mean_{points, outputs} |y − target|`; the step applies AdamW per MLP.
//! Inputs are row-major `[N × d0]`, targets `[N × dL]`.

use rand::{Rng, RngExt};
use rayon::prelude::*;

use super::super::adamw::{AdamWConfig, AdamWState};
use super::super::dense::{Activation, Dense, PackingPlan, Rows};
use super::super::gemm::{Init, Post};
use super::super::layout::ParamLayout;
use super::super::simd::Backend;
use super::super::tasks::{TaskPool, plan_tasks, tasks_by_field};
use crate::error::{CatmapError, Result};

/// Points per chunk.
const CHUNK_POINTS: usize = 120;
/// Upper bound of a task's work in point × parameter units.
const TASK_WORK: usize = 1200 * 4000;

/// Scratch of one chunk.
#[derive(Debug, Default)]
pub(crate) struct MlpScratch {
    h: Vec<Vec<f32>>,
    p: Vec<f32>,
    q: Vec<f32>,
}

/// B independent plain MLPs of one shape, with per-MLP AdamW state.
#[derive(Debug)]
pub struct MlpBatch {
    dims: Vec<usize>,
    layout: ParamLayout,
    layers: Vec<Dense>,
    packed_len: usize,
    grad_len: usize,
    params: Vec<Vec<f32>>,
    states: Vec<AdamWState>,
    optim: AdamWConfig,
    backend: Backend,
    packed: Vec<Vec<f32>>,
    grads: Vec<Vec<f32>>,
    pool: TaskPool<MlpScratch>,
}

impl MlpBatch {
    /// `count` MLPs with layer widths `dims`, initialised from `rng` (see [`ParamLayout::init`]).
    pub fn new(dims: &[usize], count: usize, optim: AdamWConfig, rng: &mut impl Rng) -> Result<Self> {
        if dims.len() < 2 || dims.contains(&0) {
            return Err(CatmapError::bad_value(
                "the MLP's layer widths",
                dims,
                "hold at least two widths, none of them 0",
            ));
        }
        let layout = ParamLayout::mlp(dims);
        let mut plan = PackingPlan::default();
        let layers = dims
            .windows(2)
            .enumerate()
            .map(|(l, w)| {
                plan.dense(
                    layout.offset(&format!("layers.{l}.weight")),
                    layout.offset(&format!("layers.{l}.bias")),
                    w[1],
                    &[w[0]],
                )
            })
            .collect();
        let params: Vec<Vec<f32>> = (0..count).map(|_| layout.init(rng)).collect();
        let states = vec![AdamWState::new(layout.len()); count];
        Ok(Self {
            dims: dims.to_vec(),
            layout,
            layers,
            packed_len: plan.packed_len,
            grad_len: plan.grad_len,
            params,
            states,
            optim,
            backend: Backend::detect(),
            packed: Vec::new(),
            grads: Vec::new(),
            pool: TaskPool::default(),
        })
    }

    /// Runs the kernels on `backend` instead of the detected one.
    pub fn set_backend(&mut self, backend: Backend) {
        self.backend = backend;
    }

    /// The parameter layout shared by all MLPs.
    pub fn layout(&self) -> &ParamLayout {
        &self.layout
    }

    /// Flat parameters of MLP `index`.
    pub fn params(&self, index: usize) -> Option<&[f32]> {
        self.params.get(index).map(Vec::as_slice)
    }

    /// Number of MLPs.
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Whether there is no MLP.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// One step: per MLP, L1 loss on (`inputs[b]`, `targets[b]`), backward and AdamW.
    /// Returns the losses before the update.
    pub fn train_step(&mut self, inputs: &[&[f32]], targets: &[&[f32]]) -> Result<Vec<f32>> {
        let losses = self.compute_gradients(inputs, targets)?;
        let optim = self.optim;
        self.params
            .par_iter_mut()
            .zip(&mut self.states)
            .zip(&self.grads)
            .for_each(|((p, s), g)| s.update(&optim, p, g));
        Ok(losses)
    }

    /// Losses and canonical gradients, without updating.
    pub fn loss_and_gradients(&mut self, inputs: &[&[f32]], targets: &[&[f32]]) -> Result<(Vec<f32>, Vec<Vec<f32>>)> {
        let losses = self.compute_gradients(inputs, targets)?;
        Ok((losses, self.grads[..self.params.len()].to_vec()))
    }

    fn compute_gradients(&mut self, inputs: &[&[f32]], targets: &[&[f32]]) -> Result<Vec<f32>> {
        let (d0, dl) = (self.dims[0], self.dims[self.dims.len() - 1]);
        let count = self.params.len();
        let bad = inputs.len() != count
            || targets.len() != count
            || inputs
                .iter()
                .zip(targets)
                .any(|(x, t)| !x.len().is_multiple_of(d0) || t.len() != x.len() / d0 * dl);
        if bad {
            return Err(CatmapError::mismatch(
                format!("inputs / targets of an MLP batch of {count}"),
                format!("multiples of widths {d0} / {dl}"),
                "other lengths",
            ));
        }
        self.packed.resize_with(count, Vec::new);
        let (layers, packed_len) = (&self.layers, self.packed_len);
        self.packed
            .par_iter_mut()
            .zip(&self.params)
            .for_each(|(packed, params)| {
                packed.resize(packed_len, 0.0);
                for layer in layers {
                    layer.pack(params, packed);
                }
            });
        let units: Vec<usize> = inputs.iter().map(|x| x.len() / d0).collect();
        let tasks = plan_tasks(&units, &vec![self.layout.len(); count], TASK_WORK);
        let (backend, packed, grad_len) = (self.backend, &self.packed, self.grad_len);
        let task_losses = self.pool.run(
            &tasks,
            |_| grad_len,
            |task, scratch, grad| {
                let f = task.field;
                let scale = 1.0 / (units[f] * dl) as f32;
                let mut loss = 0.0f32;
                let mut start = task.start;
                while start < task.end {
                    let end = (start + CHUNK_POINTS).min(task.end);
                    let x = &inputs[f][start * d0..end * d0];
                    let t = &targets[f][start * dl..end * dl];
                    loss += train_chunk(layers, backend, &packed[f], x, d0, t, dl, scale, scratch, grad);
                    start = end;
                }
                loss
            },
        );
        let by_field = tasks_by_field(&tasks, count);
        let task_grads = self.pool.grads();
        let losses = by_field
            .iter()
            .map(|ids| ids.iter().map(|&i| task_losses[i]).sum())
            .collect();
        let len = self.layout.len();
        self.grads.resize_with(count, Vec::new);
        self.grads.par_iter_mut().zip(&by_field).for_each(|(grad, ids)| {
            grad.clear();
            grad.resize(len, 0.0);
            for &i in ids {
                for layer in layers {
                    layer.unpack_grad(&task_grads[i], grad);
                }
            }
        });
        Ok(losses)
    }
}

/// Forward, L1 loss and backward of one chunk; returns the chunk's share of the loss.
fn train_chunk(
    layers: &[Dense],
    backend: Backend,
    packed: &[f32],
    x: &[f32],
    d0: usize,
    t: &[f32],
    dl: usize,
    scale: f32,
    s: &mut MlpScratch,
    grad: &mut [f32],
) -> f32 {
    let n = x.len() / d0;
    s.h.resize_with(layers.len(), Vec::new);
    let width = layers.iter().map(|l| l.out_pad).max().unwrap_or(0);
    for (h, l) in s.h.iter_mut().zip(layers) {
        h.resize(n * l.out_pad, 0.0);
    }
    s.p.resize(n * width, 0.0);
    s.q.resize(n * width, 0.0);
    let last = layers.len() - 1;
    for (l, layer) in layers.iter().enumerate() {
        let (before, after) = s.h.split_at_mut(l);
        let input = if l == 0 {
            Rows { data: x, ld: d0 }
        } else {
            Rows {
                data: &before[l - 1],
                ld: layers[l - 1].out_pad,
            }
        };
        let act = if l == last {
            Activation::Linear
        } else {
            Activation::Relu
        };
        layer.forward(backend, packed, n, &[input], &mut after[0], act);
    }
    // L1 loss and its gradient, written into p (row stride = the output's padded width).
    let out_pad = layers[last].out_pad;
    let mut loss = 0.0f32;
    let y = &s.h[last];
    s.p[..n * out_pad].fill(0.0);
    for i in 0..n {
        for c in 0..dl {
            let r = y[i * out_pad + c] - t[i * dl + c];
            loss += r.abs() * scale;
            // sign(r) · scale with sign(0) = 0, without branches (the signs are random).
            s.p[i * out_pad + c] = (f32::from(u8::from(r > 0.0)) - f32::from(u8::from(r < 0.0))) * scale;
        }
    }
    let (mut dy, mut dx) = (&mut s.p, &mut s.q);
    for l in (0..layers.len()).rev() {
        let dyr = Rows {
            data: dy,
            ld: layers[l].out_pad,
        };
        let input = if l == 0 {
            Rows { data: x, ld: d0 }
        } else {
            Rows {
                data: &s.h[l - 1],
                ld: layers[l - 1].out_pad,
            }
        };
        layers[l].backward_weights(backend, n, &[input], dyr, grad);
        if l > 0 {
            let prev = layers[l - 1].out_pad;
            layers[l].backward_input(
                backend,
                packed,
                n,
                0,
                dyr,
                dx,
                prev,
                Init::Zero,
                Post::Mask {
                    data: &s.h[l - 1],
                    ld: prev,
                },
            );
            std::mem::swap(&mut dy, &mut dx);
        }
    }
    loss
}

/// `count` rows of `len` values drawn uniformly from [−1, 1): the benchmark's random inputs or
/// targets.
pub fn random_rows(rng: &mut impl Rng, count: usize, len: usize) -> Vec<Vec<f32>> {
    (0..count)
        .map(|_| (0..len).map(|_| rng.random_range(-1.0..1.0)).collect())
        .collect()
}

#[cfg(test)]
mod tests {
    use candle_core::DType;

    use super::*;
    use crate::field::bench::mlp_reference;
    use crate::field::reference::worst_tensor_error;
    use crate::rng::{RngStream, seeded_rng};

    #[test]
    fn plain_mlp_gradients_match_candle_autograd() {
        let dims = [39, 32, 32, 32, 4];
        for (count, points) in [(1, 50), (3, 200), (2, 1200)] {
            let mut rng = seeded_rng(9, RngStream::Mapper);
            let mut mlps = MlpBatch::new(&dims, count, AdamWConfig::adam(1e-3), &mut rng).expect("valid widths");
            let inputs = random_rows(&mut rng, count, points * 39);
            let targets = random_rows(&mut rng, count, points * 4);
            let xs: Vec<&[f32]> = inputs.iter().map(Vec::as_slice).collect();
            let ts: Vec<&[f32]> = targets.iter().map(Vec::as_slice).collect();
            let (losses, grads) = mlps.loss_and_gradients(&xs, &ts).expect("shapes agree");
            for b in 0..count {
                let params = mlps.params(b).expect("exists");
                let (loss, grad) =
                    mlp_reference(&dims, params, &inputs[b], &targets[b], DType::F64).expect("candle runs");
                assert!(
                    (f64::from(losses[b]) - loss).abs() < 1e-5 * loss.abs(),
                    "loss {} vs {loss}",
                    losses[b]
                );
                let (rel, name) = worst_tensor_error(mlps.layout(), &grads[b], &grad);
                assert!(
                    rel <= 1e-4,
                    "B = {count}, N = {points}: gradient of {name} off by {rel:.2e}"
                );
            }
        }
    }
}
