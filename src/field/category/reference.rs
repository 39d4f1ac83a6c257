//! The category model in candle autograd (`Var`, `backward`), built from the same weights and
//! codes: the reference the fused kernel is checked against.
//!
//! It follows CodeNeRF's literal formulation: every sample looks up its member's codes
//! (`index_select`, as `shape_codes(indices)` in the paper's code) and runs the code layers
//! itself; the fused kernel evaluates them once per member instead. Rendering (running product
//! for the transmittance, detached variance) and the masked-mean losses are written out as in
//! [`crate::field::reference`]. Slow; for checks only.

use candle_core::{DType, Device, Tensor, Var, backprop::GradStore};

use super::super::directions::NUM_DIRECTIONS;
use super::super::encoding::{GEO_DIMS, NUM_BANDS};
use super::super::heads::ALPHA_SCALE;
use super::super::loss::{COLOUR_WEIGHT, DEPTH_STD_EPS, OPACITY_WEIGHT};
use super::super::reference::{column, linear, sigmoid, vars};
use super::super::render::FREE_EPS;
use super::super::samples::RaySamples;
use super::{CODE_REG_WEIGHT, CategoryField, CategorySamples};
use crate::error::{CatmapError, Result};
use crate::objects::object_view::PixelState;

/// Losses and gradients of the reference category model on one category's rays.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CategoryReferenceOutput {
    /// Total loss: L_depth + 5 L_colour + 10 L_opacity + code regulariser.
    pub total: f64,
    /// L_depth.
    pub depth: f64,
    /// L_colour.
    pub colour: f64,
    /// L_opacity.
    pub opacity: f64,
    /// The code regulariser.
    pub code_reg: f64,
    /// Gradient of the total with respect to the network, flat in layout order.
    pub grad: Vec<f64>,
    /// Gradient of the total with respect to each member's `[z_s ‖ z_t]`.
    pub code_grads: Vec<Vec<f64>>,
}

type CResult<T> = candle_core::Result<T>;

/// The category model of `field` on `samples` with candle autograd, in `dtype`.
pub fn category_reference(
    field: &CategoryField,
    samples: &CategorySamples,
    dtype: DType,
) -> Result<CategoryReferenceOutput> {
    samples.validate(field.num_members())?;
    let layout = field.layout();
    let vars = vars(&layout, field.params(), dtype)?;
    let var = |name: &str| -> Result<&Var> {
        layout
            .tensors()
            .iter()
            .position(|t| t.name == name)
            .map(|i| &vars[i])
            .ok_or_else(|| CatmapError::missing(format!("tensor {name}")))
    };
    let (m, d) = (field.num_members(), field.code_dim());
    let codes: Vec<f32> = (0..m)
        .flat_map(|i| field.code(i).unwrap_or_default().to_vec())
        .collect();
    let all = Tensor::from_slice(&codes, (m, 2 * d), &Device::Cpu).and_then(|t| t.to_dtype(dtype))?;
    let z_shape = Var::from_tensor(&all.narrow(1, 0, d).and_then(|t| t.contiguous())?)?;
    let z_texture = Var::from_tensor(&all.narrow(1, d, d).and_then(|t| t.contiguous())?)?;

    let rays = &samples.rays;
    let (r, s) = (rays.num_rays(), rays.samples_per_ray);
    let n = r * s;
    let index: Vec<u32> = (0..n).map(|k| samples.members[k / s] as u32).collect();
    let index = Tensor::from_slice(&index, n, &Device::Cpu)?;
    let fc = |x: &Tensor, name: &str| -> Result<Tensor> {
        linear(x, var(&format!("{name}.weight"))?, var(&format!("{name}.bias"))?).map_err(CatmapError::from)
    };
    let relu_fc = |x: &Tensor, name: &str| fc(x, name)?.relu().map_err(CatmapError::from);
    let cat = |a: &Tensor, b: &Tensor| Tensor::cat(&[a, b], 1).map_err(CatmapError::from);
    let zs = z_shape.as_tensor().index_select(&index, 0)?;
    let zt = z_texture.as_tensor().index_select(&index, 0)?;

    // Encoding.
    let flat: Vec<f32> = rays.points.iter().flatten().copied().collect();
    let pts = Tensor::from_slice(&flat, (n, 3), &Device::Cpu).and_then(|p| p.to_dtype(dtype))?;
    let xs = (pts / f64::from(field.scale()))?;
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

    // The network (module doc of `category`).
    let add = |y: Tensor, z: &Tensor, name: &str| (y + relu_fc(z, name)?).map_err(CatmapError::from);
    let y = relu_fc(&geo, "encoding_xyz")?;
    let y = add(y, &zs, "shape_latent_layer_1")?;
    let y = relu_fc(&y, "shape_layer_1")?;
    let y = add(y, &zs, "cat_latent_layer")?;
    let y = relu_fc(&cat(&y, &geo)?, "cat_layer")?;
    let y = add(y, &zs, "shape_latent_layer_2")?;
    let y = relu_fc(&y, "shape_layer_2")?;
    let y = fc(&y, "encoding_shape")?;
    let alpha = (fc(&y, "sigma")? * f64::from(ALPHA_SCALE))?;
    let y = relu_fc(&cat(&y, &col)?, "encoding_viewdir")?;
    let y = add(y, &zt, "texture_latent_layer_1")?;
    let y = relu_fc(&y, "texture_layer_1")?;
    let y = relu_fc(&y, "rgb.0")?;
    let colour = sigmoid(&fc(&y, "rgb.2")?).and_then(|c| c.reshape((r, s, 3)))?;
    let occ = sigmoid(&alpha).and_then(|o| o.reshape((r, s)))?;

    let (l_depth, l_colour, l_opacity) = render_losses(&occ, &colour, rays, dtype)?;
    let norm = |z: &Var| z.as_tensor().sqr()?.sum(1)?.sqrt()?.sum_all();
    let reg = ((norm(&z_shape)? + norm(&z_texture)?)? * f64::from(CODE_REG_WEIGHT))?;
    let total = (|| -> CResult<Tensor> {
        let rendered =
            ((&l_depth + (&l_colour * f64::from(COLOUR_WEIGHT))?)? + (&l_opacity * f64::from(OPACITY_WEIGHT))?)?;
        rendered + &reg
    })()?;
    let grads = total.backward()?;
    let mut grad = vec![0.0; layout.len()];
    for (t, v) in layout.tensors().iter().zip(&vars) {
        if let Some(g) = flat_grad(&grads, v)? {
            grad[t.range()].copy_from_slice(&g);
        }
    }
    let gs = flat_grad(&grads, &z_shape)?.unwrap_or_else(|| vec![0.0; m * d]);
    let gt = flat_grad(&grads, &z_texture)?.unwrap_or_else(|| vec![0.0; m * d]);
    let code_grads = (0..m)
        .map(|i| [&gs[i * d..(i + 1) * d], &gt[i * d..(i + 1) * d]].concat())
        .collect();
    let scalar = |t: &Tensor| {
        t.to_dtype(DType::F64)
            .and_then(|t| t.to_scalar::<f64>())
            .map_err(CatmapError::from)
    };
    Ok(CategoryReferenceOutput {
        total: scalar(&total)?,
        depth: scalar(&l_depth)?,
        colour: scalar(&l_colour)?,
        opacity: scalar(&l_opacity)?,
        code_reg: scalar(&reg)?,
        grad,
        code_grads,
    })
}

fn flat_grad(grads: &GradStore, v: &Var) -> Result<Option<Vec<f64>>> {
    grads
        .get(v.as_tensor())
        .map(|g| {
            g.flatten_all()
                .and_then(|g| g.to_dtype(DType::F64))
                .and_then(|g| g.to_vec1::<f64>())
                .map_err(CatmapError::from)
        })
        .transpose()
}

/// Renders `occ` (`[R, S]`) and `colour` (`[R, S, 3]`) and returns vMAP's three masked means.
fn render_losses(occ: &Tensor, colour: &Tensor, rays: &RaySamples, dtype: DType) -> CResult<(Tensor, Tensor, Tensor)> {
    let (r, s) = (rays.num_rays(), rays.samples_per_ray);
    let free = ((occ.neg()? + 1.0)? + f64::from(FREE_EPS))?;
    let mut t_cols = vec![Tensor::ones((r, 1), dtype, &Device::Cpu)?];
    for i in 1..s {
        let prev = t_cols[i - 1].mul(&free.narrow(1, i - 1, 1)?)?;
        t_cols.push(prev);
    }
    let w = occ.mul(&Tensor::cat(&t_cols, 1)?)?;
    let zf: Vec<f64> = rays.z.iter().map(|v| f64::from(*v)).collect();
    let z = column(&zf, dtype)?.reshape((r, s))?;
    let depth = w.mul(&z)?.sum(1)?;
    let rgb = w.unsqueeze(2)?.broadcast_mul(colour)?.sum(1)?;
    let opacity = w.sum(1)?;
    let diff = z.broadcast_sub(&depth.unsqueeze(1)?)?;
    let var_z = w.mul(&diff.sqr()?)?.sum(1)?.detach();

    let mask = |f: &dyn Fn(PixelState, f32) -> bool| -> Vec<f64> {
        rays.states
            .iter()
            .zip(&rays.depth_m)
            .map(|(st, d)| f64::from(u8::from(f(*st, *d))))
            .collect()
    };
    let obj = mask(&|st, _| st.reads_colour());
    let known = mask(&|st, _| st.opacity_target().is_some());
    let this = mask(&|st, _| st.opacity_target() == Some(1.0));
    let md = mask(&|st, d| st.reads_colour() && d > 0.0);
    let mean = |masked: Tensor, mask: &[f64]| -> CResult<Tensor> {
        let count: f64 = mask.iter().sum();
        let factor = if count == 0.0 { 0.0 } else { 1.0 / (count + 1e-10) };
        masked.sum_all()? * factor
    };
    let gt_d: Vec<f64> = rays.depth_m.iter().map(|v| f64::from(*v)).collect();
    let gt_c: Vec<f64> = rays.rgb.iter().flatten().map(|v| f64::from(*v)).collect();
    let info = (var_z.sqrt()? + f64::from(DEPTH_STD_EPS))?.recip()?;
    let res_d = depth.sub(&column(&gt_d, dtype)?)?.abs()?;
    let l_depth = mean(res_d.mul(&info)?.mul(&column(&md, dtype)?)?, &md)?;
    let gt = column(&gt_c, dtype)?.reshape((r, 3))?;
    let res_c = rgb.sub(&gt)?.abs()?.sum(1)?;
    let l_colour = mean(res_c.mul(&column(&obj, dtype)?)?, &obj)?;
    let res_o = opacity.sub(&column(&this, dtype)?)?.abs()?;
    let l_opacity = mean(res_o.mul(&column(&known, dtype)?)?, &known)?;
    Ok((l_depth, l_colour, l_opacity))
}
