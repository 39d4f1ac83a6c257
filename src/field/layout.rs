//! Flat parameter layout of a field: named tensors packed one after the other in a `Vec<f32>`.
//!
//! Names follow vMAP's module names (PyTorch `state_dict` style) so that checkpoints read
//! naturally: `encoding.B` (21 × 3, the trainable direction matrix), `in_layer.weight` (H × 87),
//! `mid1.*`, `cat_layer.*` (H × (H + 87), columns `[h2 ‖ emb_geo]`), `mid2.*`, `out_alpha.*`
//! (1 × H), `color_linear.*` (H × (H + 42), columns `[h4 ‖ emb_col]`), `out_color.*` (3 × H).
//! Weights are row-major `[out, in]` like `torch.nn.Linear`. A plain MLP uses `layers.{l}.*`.
//!
//! Initialisation (vMAP's `init_weights` + PyTorch defaults): weights Xavier-normal,
//! std = √(2 / (fan_in + fan_out)); biases U(−1/√fan_in, 1/√fan_in) (PyTorch's `Linear`
//! default, which vMAP keeps); `encoding.B` = the 21 fixed directions.

use rand::{Rng, RngExt};

use super::directions::{NUM_DIRECTIONS, icosphere_directions};
use super::encoding::{COL_DIMS, GEO_DIMS};

/// How a tensor is initialised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitKind {
    /// The fixed encoding directions.
    Directions,
    /// Xavier-normal weight of a linear layer.
    XavierNormal,
    /// PyTorch's default bias: uniform in ±1/√fan_in.
    BiasUniform,
}

/// One named tensor of a layout.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TensorSpec {
    /// Name, e.g. `cat_layer.weight`.
    pub name: String,
    /// Shape `[rows, cols]` (biases are `[out, 1]`).
    pub shape: [usize; 2],
    /// Offset of the first element in the flat vector.
    pub offset: usize,
    /// Fan-in used by the initialiser (the `cols` of the layer's weight).
    pub fan_in: usize,
    /// How the tensor is initialised.
    pub init: InitKind,
}

impl TensorSpec {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.shape[0] * self.shape[1]
    }

    /// Whether the tensor has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The element range in the flat vector.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.len()
    }
}

/// The named tensors of one field, in storage order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamLayout {
    tensors: Vec<TensorSpec>,
    len: usize,
}

impl ParamLayout {
    /// Layout of the vMAP occupancy field with `hidden` units.
    pub fn occupancy(hidden: usize) -> Self {
        let mut layout = Self {
            tensors: Vec::new(),
            len: 0,
        };
        layout.push("encoding.B", [NUM_DIRECTIONS, 3], 3, InitKind::Directions);
        layout.push_linear("in_layer", hidden, GEO_DIMS);
        layout.push_linear("mid1", hidden, hidden);
        layout.push_linear("cat_layer", hidden, hidden + GEO_DIMS);
        layout.push_linear("mid2", hidden, hidden);
        layout.push_linear("out_alpha", 1, hidden);
        layout.push_linear("color_linear", hidden, hidden + COL_DIMS);
        layout.push_linear("out_color", 3, hidden);
        layout
    }

    /// Layout of the CodeNeRF-style category field (width `hidden`, code dimension `code_dim`),
    /// with the module names of CodeNeRF's `model.py` (see [`super::category`]): `encoding.B`,
    /// `encoding_xyz`, `shape_latent_layer_1`, `shape_layer_1`, `cat_latent_layer`, `cat_layer`
    /// (columns `[y ‖ emb_geo]`), `shape_latent_layer_2`, `shape_layer_2`, `encoding_shape`,
    /// `sigma`, `encoding_viewdir` (columns `[y ‖ emb_col]`), `texture_latent_layer_1`,
    /// `texture_layer_1`, `rgb.0` (W/2 × W) and `rgb.2` (3 × W/2). The codes are not in it.
    pub fn category(hidden: usize, code_dim: usize) -> Self {
        let mut layout = Self {
            tensors: Vec::new(),
            len: 0,
        };
        layout.push("encoding.B", [NUM_DIRECTIONS, 3], 3, InitKind::Directions);
        layout.push_linear("encoding_xyz", hidden, GEO_DIMS);
        layout.push_linear("shape_latent_layer_1", hidden, code_dim);
        layout.push_linear("shape_layer_1", hidden, hidden);
        layout.push_linear("cat_latent_layer", hidden, code_dim);
        layout.push_linear("cat_layer", hidden, hidden + GEO_DIMS);
        layout.push_linear("shape_latent_layer_2", hidden, code_dim);
        layout.push_linear("shape_layer_2", hidden, hidden);
        layout.push_linear("encoding_shape", hidden, hidden);
        layout.push_linear("sigma", 1, hidden);
        layout.push_linear("encoding_viewdir", hidden, hidden + COL_DIMS);
        layout.push_linear("texture_latent_layer_1", hidden, code_dim);
        layout.push_linear("texture_layer_1", hidden, hidden);
        layout.push_linear("rgb.0", hidden / 2, hidden);
        layout.push_linear("rgb.2", 3, hidden / 2);
        layout
    }

    /// Layout of a plain MLP with layer widths `dims` (`dims[0]` inputs, `dims.last()` outputs).
    pub fn mlp(dims: &[usize]) -> Self {
        let mut layout = Self {
            tensors: Vec::new(),
            len: 0,
        };
        for (l, w) in dims.windows(2).enumerate() {
            layout.push_linear(&format!("layers.{l}"), w[1], w[0]);
        }
        layout
    }

    fn push(&mut self, name: &str, shape: [usize; 2], fan_in: usize, init: InitKind) {
        let spec = TensorSpec {
            name: name.to_owned(),
            shape,
            offset: self.len,
            fan_in,
            init,
        };
        self.len += spec.len();
        self.tensors.push(spec);
    }

    fn push_linear(&mut self, name: &str, out: usize, inp: usize) {
        self.push(&format!("{name}.weight"), [out, inp], inp, InitKind::XavierNormal);
        self.push(&format!("{name}.bias"), [out, 1], inp, InitKind::BiasUniform);
    }

    /// Total number of parameters.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the layout is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The tensors in storage order.
    pub fn tensors(&self) -> &[TensorSpec] {
        &self.tensors
    }

    /// The tensor called `name`.
    pub fn get(&self, name: &str) -> Option<&TensorSpec> {
        self.tensors.iter().find(|t| t.name == name)
    }

    /// Offset of tensor `name`; the layouts built here always contain the names they use.
    pub(crate) fn offset(&self, name: &str) -> usize {
        self.get(name).map_or(usize::MAX, |t| t.offset)
    }

    /// Fresh parameters drawn from `rng` (see the module doc for the initialisers).
    pub fn init(&self, rng: &mut impl Rng) -> Vec<f32> {
        let mut params = vec![0.0f32; self.len];
        let dirs = icosphere_directions();
        for t in &self.tensors {
            let dst = &mut params[t.range()];
            match t.init {
                InitKind::Directions => {
                    for (d, v) in dst.iter_mut().zip(dirs.iter().flatten()) {
                        *d = *v as f32;
                    }
                }
                InitKind::XavierNormal => {
                    let std = (2.0 / (t.shape[0] + t.shape[1]) as f64).sqrt();
                    for d in dst.iter_mut() {
                        *d = (std * standard_normal(rng)) as f32;
                    }
                }
                InitKind::BiasUniform => {
                    let bound = 1.0 / (t.fan_in as f64).sqrt();
                    for d in dst.iter_mut() {
                        *d = rng.random_range(-bound..bound) as f32;
                    }
                }
            }
        }
        params
    }
}

use crate::rng::standard_normal_f64 as standard_normal;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{RngStream, seeded_rng};

    #[test]
    fn the_object_field_has_about_11k_parameters() {
        let layout = ParamLayout::occupancy(32);
        // 63 + (87·32+32) + (32·32+32) + (119·32+32) + (32·32+32) + 33 + (74·32+32) + 99
        assert_eq!(layout.len(), 11_363, "METHOD.md: ≈11.3k parameters at H = 32");
        let last = layout.tensors().last().expect("non-empty");
        assert_eq!(
            last.offset + last.len(),
            layout.len(),
            "tensors are packed without gaps"
        );
    }

    #[test]
    fn the_category_field_has_the_papers_18_179_parameters() {
        // 18 116 weights and biases (four 32 → 32 code layers among them) + the 63 of B.
        assert_eq!(ParamLayout::category(32, 32).len(), 18_179, "METHOD.md §5 / paper");
    }

    #[test]
    fn initialisation_is_seeded_and_has_xavier_spread() {
        let layout = ParamLayout::occupancy(128);
        let a = layout.init(&mut seeded_rng(1, RngStream::Background));
        let b = layout.init(&mut seeded_rng(1, RngStream::Background));
        assert_eq!(a, b, "same seed, same weights");
        let w = layout.get("mid1.weight").expect("exists");
        let vals = &a[w.range()];
        let var = vals.iter().map(|v| f64::from(*v).powi(2)).sum::<f64>() / vals.len() as f64;
        let expected = 2.0 / 256.0;
        assert!(
            (var / expected - 1.0).abs() < 0.05,
            "variance {var} vs Xavier {expected}"
        );
        let bias = layout.get("mid1.bias").expect("exists");
        let bound = 1.0 / 128f32.sqrt();
        assert!(
            a[bias.range()].iter().all(|v| v.abs() <= bound),
            "bias within ±1/√fan_in"
        );
        let dirs = layout.get("encoding.B").expect("exists");
        assert_eq!(a[dirs.range()][..3], [1.0, 0.0, 0.0], "first direction is +x");
    }

    #[test]
    fn mlp_layout_names_layers_in_order() {
        let layout = ParamLayout::mlp(&[39, 32, 32, 32, 4]);
        let names: Vec<&str> = layout.tensors().iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names[..3], ["layers.0.weight", "layers.0.bias", "layers.1.weight"]);
        assert_eq!(layout.len(), 39 * 32 + 32 + 2 * (32 * 32 + 32) + 32 * 4 + 4);
    }
}
