//! The plain MLP in candle autograd: the gradient reference of [`super::MlpBatch`] and the candle
//! baseline of the benchmark (B MLPs as batched 3-D matmuls, vMAP's `vmap` shape).

use candle_core::{D, DType, Device, Tensor, Var};

use super::super::adamw::AdamWConfig;
use super::super::layout::{ParamLayout, TensorSpec};
use super::super::reference::{flat_grads, linear, vars};
use crate::error::{CatmapError, Result};

/// A plain ReLU MLP (`dims`), L1 loss mean over `[N × dL]`: returns the loss and the gradient.
pub fn mlp_reference(
    dims: &[usize],
    params: &[f32],
    inputs: &[f32],
    targets: &[f32],
    dtype: DType,
) -> Result<(f64, Vec<f64>)> {
    let layout = ParamLayout::mlp(dims);
    let vars = vars(&layout, params, dtype)?;
    let n = inputs.len() / dims[0];
    let mut h = Tensor::from_slice(inputs, (n, dims[0]), &Device::Cpu).and_then(|x| x.to_dtype(dtype))?;
    let layers = dims.len() - 1;
    for l in 0..layers {
        h = linear(&h, &vars[2 * l], &vars[2 * l + 1])?;
        if l + 1 < layers {
            h = h.relu()?;
        }
    }
    let t = Tensor::from_slice(targets, h.dims(), &Device::Cpu).and_then(|x| x.to_dtype(dtype))?;
    let loss = h.sub(&t).and_then(|x| x.abs()).and_then(|x| x.mean_all())?;
    let value = loss.to_dtype(DType::F64).and_then(|x| x.to_scalar::<f64>())?;
    Ok((value, flat_grads(&layout, &vars, &loss)?))
}

/// B plain MLPs trained with candle autograd, batched as 3-D matmuls (vMAP's `vmap` shape), with
/// AdamW written in tensor ops: the candle baseline of the benchmark.
#[derive(Debug)]
pub struct CandleMlpBatch {
    weights: Vec<Var>,
    biases: Vec<Var>,
    moments: Vec<(Tensor, Tensor)>,
    optim: AdamWConfig,
    step: i32,
}

impl CandleMlpBatch {
    /// Builds the batch from per-MLP flat parameters (in [`ParamLayout::mlp`] order).
    pub fn new(dims: &[usize], params: &[&[f32]], optim: AdamWConfig) -> Result<Self> {
        let layout = ParamLayout::mlp(dims);
        let (mut weights, mut biases, mut moments) = (Vec::new(), Vec::new(), Vec::new());
        for l in 0..dims.len() - 1 {
            let (w, b) = (&layout.tensors()[2 * l], &layout.tensors()[2 * l + 1]);
            let stack = |spec: &TensorSpec, shape: &[usize]| -> candle_core::Result<Tensor> {
                let parts = params
                    .iter()
                    .map(|p| Tensor::from_slice(&p[spec.range()], spec.shape.to_vec(), &Device::Cpu))
                    .collect::<candle_core::Result<Vec<_>>>()?;
                Tensor::stack(&parts, 0)?.reshape(shape)
            };
            let bsz = params.len();
            // W stored as (B, in, out) so that h = x · W.
            let wt = stack(w, &[bsz, dims[l + 1], dims[l]])
                .and_then(|t| t.transpose(1, 2))
                .and_then(|t| t.contiguous())?;
            let bt = stack(b, &[bsz, 1, dims[l + 1]])?;
            for t in [&wt, &bt] {
                moments.push((t.zeros_like()?, t.zeros_like()?));
            }
            weights.push(Var::from_tensor(&wt)?);
            biases.push(Var::from_tensor(&bt)?);
        }
        Ok(Self {
            weights,
            biases,
            moments,
            optim,
            step: 0,
        })
    }

    /// One step on inputs `(B, N, d0)` and targets `(B, N, dL)`; returns the summed loss.
    pub fn step(&mut self, inputs: &Tensor, targets: &Tensor) -> Result<f32> {
        let mut run = || -> candle_core::Result<f32> {
            let mut h = inputs.clone();
            let layers = self.weights.len();
            for l in 0..layers {
                h = h
                    .matmul(self.weights[l].as_tensor())?
                    .broadcast_add(self.biases[l].as_tensor())?;
                if l + 1 < layers {
                    h = h.relu()?;
                }
            }
            let loss = h
                .sub(targets)?
                .abs()?
                .mean_keepdim(D::Minus1)?
                .mean_keepdim(D::Minus2)?
                .sum_all()?;
            let grads = loss.backward()?;
            self.step += 1;
            let c = self.optim;
            let bc1 = 1.0 - f64::from(c.beta1).powi(self.step);
            let bc2 = 1.0 - f64::from(c.beta2).powi(self.step);
            let params = self.weights.iter().zip(&self.biases).flat_map(|(w, b)| [w, b]);
            for (var, (m, v)) in params.zip(&mut self.moments) {
                let Some(g) = grads.get(var.as_tensor()) else { continue };
                *m = ((&*m * f64::from(c.beta1))? + (g * (1.0 - f64::from(c.beta1)))?)?;
                *v = ((&*v * f64::from(c.beta2))? + (g.sqr()? * (1.0 - f64::from(c.beta2)))?)?;
                let decayed = (var.as_tensor() * (1.0 - f64::from(c.lr * c.weight_decay)))?;
                let upd = ((&*m / bc1)? / ((&*v / bc2)?.sqrt()? + f64::from(c.eps))?)?;
                var.set(&(decayed - (upd * f64::from(c.lr))?)?)?;
            }
            loss.to_scalar::<f32>()
        };
        run().map_err(CatmapError::from)
    }
}
