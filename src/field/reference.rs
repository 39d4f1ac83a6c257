//! The same models in candle autograd (`Var`, `backward`), built from the same flat weights:
//! the reference the fused kernels are checked against.
//!
//! Everything here follows the math of the fused modules literally (concatenations, a running
//! product for the transmittance, `detach` on the variance, masked means), in the dtype asked
//! for (f64 for gradient checks). It is slow and allocates freely; it is not used for training.

use candle_core::{DType, Device, Tensor, Var};

use super::directions::NUM_DIRECTIONS;
use super::encoding::{GEO_DIMS, NUM_BANDS};
use super::heads::ALPHA_SCALE;
use super::layout::ParamLayout;
use super::loss::{COLOUR_WEIGHT, DEPTH_STD_EPS, OPACITY_WEIGHT};
use super::render::FREE_EPS;
use super::samples::RaySamples;
use crate::error::{CatmapError, Result};

/// How far a gradient `got` (flat, in `layout` order) is from the reference `want`: the largest
/// error of one tensor relative to that tensor's norm in `want` (or to 1 % of the whole
/// gradient's norm, so that a tensor whose gradient nearly cancels — a one-element bias summed
/// over all samples — does not turn f32 rounding into a large error), and that tensor's name.
/// Typical errors are 1e-7 … 1e-6. With `FIELD_DEBUG` set, every tensor's error is logged.
pub fn worst_tensor_error(layout: &ParamLayout, got: &[f32], want: &[f64]) -> (f64, String) {
    let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|x| x * x).sum::<f64>().sqrt();
    let all = norm(&mut want.iter().copied());
    let mut worst = (0.0, String::new());
    for t in layout.tensors() {
        let diff = norm(&mut t.range().map(|i| f64::from(got[i]) - want[i]));
        let reference = norm(&mut t.range().map(|i| want[i])).max(1e-2 * all);
        let rel = diff / reference;
        if std::env::var_os("FIELD_DEBUG").is_some() {
            tracing::info!(
                "{:>22}: rel {rel:.2e}  |ref| {reference:.3e}  |diff| {diff:.3e}",
                t.name
            );
        }
        if rel > worst.0 {
            worst = (rel, t.name.clone());
        }
    }
    worst
}

/// Forward values and gradients of the reference occupancy model on one field's rays.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReferenceOutput {
    /// Total loss L_depth + 5 L_colour + 10 L_opacity + w L_solid.
    pub total: f64,
    /// L_depth.
    pub depth: f64,
    /// L_colour.
    pub colour: f64,
    /// L_opacity.
    pub opacity: f64,
    /// L_solid (prior samples, before its weight).
    pub solid: f64,
    /// Rendered depth per ray.
    pub rendered_depth: Vec<f64>,
    /// Rendered colour per ray.
    pub rendered_colour: Vec<[f64; 3]>,
    /// Rendered opacity per ray.
    pub rendered_opacity: Vec<f64>,
    /// Gradient of the total, flat in [`ParamLayout`] order.
    pub grad: Vec<f64>,
}

/// One Var per named tensor of `layout`, built from `params`.
pub(crate) fn vars(layout: &ParamLayout, params: &[f32], dtype: DType) -> Result<Vec<Var>> {
    layout
        .tensors()
        .iter()
        .map(|t| {
            let shape: Vec<usize> = if t.shape[1] == 1 && t.name.ends_with(".bias") {
                vec![t.shape[0]]
            } else {
                t.shape.to_vec()
            };
            let tensor = Tensor::from_slice(&params[t.range()], shape, &Device::Cpu).and_then(|x| x.to_dtype(dtype))?;
            Var::from_tensor(&tensor).map_err(CatmapError::from)
        })
        .collect()
}

/// Gradients of every Var, flat in layout order (zeros where a tensor got none).
pub(crate) fn flat_grads(layout: &ParamLayout, vars: &[Var], loss: &Tensor) -> Result<Vec<f64>> {
    let grads = loss.backward()?;
    let mut out = vec![0.0; layout.len()];
    for (t, v) in layout.tensors().iter().zip(vars) {
        if let Some(g) = grads.get(v.as_tensor()) {
            let g = g
                .flatten_all()
                .and_then(|g| g.to_dtype(DType::F64))
                .and_then(|g| g.to_vec1::<f64>())?;
            out[t.range()].copy_from_slice(&g);
        }
    }
    Ok(out)
}

pub(crate) fn linear(x: &Tensor, w: &Var, b: &Var) -> candle_core::Result<Tensor> {
    x.matmul(&w.as_tensor().t()?)?.broadcast_add(b.as_tensor())
}

pub(crate) fn sigmoid(x: &Tensor) -> candle_core::Result<Tensor> {
    (x.neg()?.exp()? + 1.0)?.recip()
}

pub(crate) fn column(values: &[f64], dtype: DType) -> candle_core::Result<Tensor> {
    Tensor::from_slice(values, values.len(), &Device::Cpu)?.to_dtype(dtype)
}

/// The occupancy model (H = `hidden`, encoding scale `scale`) on `rays` with candle autograd.
pub fn occupancy_reference(
    hidden: usize,
    scale: f32,
    params: &[f32],
    rays: &RaySamples,
    dtype: DType,
) -> Result<ReferenceOutput> {
    rays.validate()?;
    let layout = ParamLayout::occupancy(hidden);
    let vars = vars(&layout, params, dtype)?;
    let var = |name: &str| -> Result<&Var> {
        layout
            .tensors()
            .iter()
            .position(|t| t.name == name)
            .map(|i| &vars[i])
            .ok_or_else(|| CatmapError::missing(format!("tensor {name}")))
    };
    let (r, s) = (rays.num_rays(), rays.samples_per_ray);
    let n = r * s;
    let build = || -> Result<(Tensor, Tensor, Tensor, Tensor, Tensor, Tensor, Tensor)> {
        let flat: Vec<f32> = rays.points.iter().flatten().copied().collect();
        let pts = Tensor::from_slice(&flat, (n, 3), &Device::Cpu).and_then(|p| p.to_dtype(dtype))?;
        let xs = (pts / f64::from(scale))?;
        let proj = xs.matmul(&var("encoding.B")?.as_tensor().t()?)?;
        let mut parts = vec![xs.clone()];
        for k in 0..NUM_BANDS {
            let f = std::f64::consts::PI * f64::from(1u32 << k);
            parts.push((&proj * f).and_then(|x| x.sin())?);
        }
        let emb = Tensor::cat(&parts, 1)?;
        debug_assert_eq!(emb.dims(), [n, 3 + NUM_BANDS * NUM_DIRECTIONS]);
        let geo = emb.narrow(1, 0, GEO_DIMS)?;
        let col = emb.narrow(1, GEO_DIMS, emb.dim(1)? - GEO_DIMS)?;
        let fc = |x: &Tensor, name: &str| -> Result<Tensor> {
            linear(x, var(&format!("{name}.weight"))?, var(&format!("{name}.bias"))?).map_err(CatmapError::from)
        };
        let h1 = fc(&geo, "in_layer")?.relu()?;
        let h2 = fc(&h1, "mid1")?.relu()?;
        let h3 = fc(&Tensor::cat(&[&h2, &geo], 1)?, "cat_layer")?.relu()?;
        let h4 = fc(&h3, "mid2")?.relu()?;
        let alpha = (fc(&h4, "out_alpha")? * f64::from(ALPHA_SCALE))?;
        let h5 = fc(&Tensor::cat(&[&h4, &col], 1)?, "color_linear")?.relu()?;
        let colour = sigmoid(&fc(&h5, "out_color")?)?.reshape((r, s, 3))?;
        let occ = sigmoid(&alpha).and_then(|o| o.reshape((r, s)))?;
        // Transmittance by a running product over the samples of each ray.
        let free = ((occ.neg()? + 1.0)? + f64::from(FREE_EPS))?;
        let mut t_cols = vec![Tensor::ones((r, 1), dtype, &Device::Cpu)?];
        for i in 1..s {
            let prev = t_cols[i - 1].mul(&free.narrow(1, i - 1, 1)?)?;
            t_cols.push(prev);
        }
        let trans = Tensor::cat(&t_cols, 1)?;
        let w = occ.mul(&trans)?;
        let zf: Vec<f64> = rays.z.iter().map(|v| f64::from(*v)).collect();
        let z = column(&zf, dtype).and_then(|z| z.reshape((r, s)))?;
        let depth = w.mul(&z).and_then(|x| x.sum(1))?;
        let rgb = w
            .unsqueeze(2)
            .and_then(|w| w.broadcast_mul(&colour))
            .and_then(|x| x.sum(1))?;
        let opacity = w.sum(1)?;
        let diff = z.broadcast_sub(&depth.unsqueeze(1)?)?;
        let var_z = w.mul(&diff.sqr()?).and_then(|x| x.sum(1))?.detach();
        Ok((depth, rgb, opacity, var_z, w, trans, occ))
    };
    let (depth, rgb, opacity, var_z, _, _, occ) = build()?;

    // Masks and targets.
    let obj: Vec<f64> = rays
        .states
        .iter()
        .map(|s| f64::from(u8::from(s.reads_colour())))
        .collect();
    let known: Vec<f64> = rays
        .states
        .iter()
        .map(|s| f64::from(u8::from(s.opacity_target().is_some())))
        .collect();
    let this: Vec<f64> = rays
        .states
        .iter()
        .map(|s| f64::from(u8::from(s.opacity_target() == Some(1.0))))
        .collect();
    let md: Vec<f64> = obj
        .iter()
        .zip(&rays.depth_m)
        .map(|(o, d)| if *d > 0.0 { *o } else { 0.0 })
        .collect();
    let gt_d: Vec<f64> = rays.depth_m.iter().map(|v| f64::from(*v)).collect();
    let gt_c: Vec<f64> = rays.rgb.iter().flatten().map(|v| f64::from(*v)).collect();
    let mean = |masked: Tensor, mask: &[f64]| -> Result<Tensor> {
        let count: f64 = mask.iter().sum();
        let factor = if count == 0.0 { 0.0 } else { 1.0 / (count + 1e-10) };
        (masked.sum_all()? * factor).map_err(CatmapError::from)
    };
    let l_depth = {
        let res = depth.sub(&column(&gt_d, dtype)?).and_then(|x| x.abs())?;
        let info = (var_z.sqrt()? + f64::from(DEPTH_STD_EPS)).and_then(|x| x.recip())?;
        mean(res.mul(&info).and_then(|x| x.mul(&column(&md, dtype)?))?, &md)?
    };
    let l_colour = {
        let gt = column(&gt_c, dtype).and_then(|c| c.reshape((r, 3)))?;
        let res = rgb.sub(&gt).and_then(|x| x.abs()).and_then(|x| x.sum(1))?;
        mean(res.mul(&column(&obj, dtype)?)?, &obj)?
    };
    let l_opacity = {
        let res = opacity.sub(&column(&this, dtype)?).and_then(|x| x.abs())?;
        mean(res.mul(&column(&known, dtype)?)?, &known)?
    };
    let l_solid = {
        let mask_of = |target: f32| -> Vec<f64> {
            rays.states
                .iter()
                .flat_map(|st| std::iter::repeat_n(f64::from(u8::from(st.sample_target() == Some(target))), s))
                .collect()
        };
        let (solid, empty) = (mask_of(1.0), mask_of(0.0));
        let prior: Vec<f64> = solid.iter().zip(&empty).map(|(a, b)| a + b).collect();
        let tensor = |m: &[f64]| {
            column(m, dtype)
                .and_then(|m| m.reshape((r, s)))
                .map_err(CatmapError::from)
        };
        let (solid_mask, empty_mask) = (tensor(&solid)?, tensor(&empty)?);
        let neg_ln_solid = occ.log().and_then(|x| x.neg()).and_then(|x| x.mul(&solid_mask))?;
        let neg_ln_empty = (occ.neg()? + 1.0)
            .and_then(|x| x.log())
            .and_then(|x| x.neg())
            .and_then(|x| x.mul(&empty_mask))?;
        mean((neg_ln_solid + neg_ln_empty)?, &prior)?
    };
    let total = (((&l_depth + (&l_colour * f64::from(COLOUR_WEIGHT))?)? + (&l_opacity * f64::from(OPACITY_WEIGHT))?)?
        + (&l_solid * f64::from(rays.solid_weight))?)?;
    let scalar = |t: &Tensor| {
        t.to_dtype(DType::F64)
            .and_then(|t| t.to_scalar::<f64>())
            .map_err(CatmapError::from)
    };
    let vec1 = |t: &Tensor| {
        t.to_dtype(DType::F64)
            .and_then(|t| t.to_vec1::<f64>())
            .map_err(CatmapError::from)
    };
    let rgb2 = rgb.to_dtype(DType::F64).and_then(|t| t.to_vec2::<f64>())?;
    Ok(ReferenceOutput {
        total: scalar(&total)?,
        depth: scalar(&l_depth)?,
        colour: scalar(&l_colour)?,
        opacity: scalar(&l_opacity)?,
        solid: scalar(&l_solid)?,
        rendered_depth: vec1(&depth)?,
        rendered_colour: rgb2.iter().map(|c| [c[0], c[1], c[2]]).collect(),
        rendered_opacity: vec1(&opacity)?,
        grad: flat_grads(&layout, &vars, &total)?,
    })
}
