//! The category network on a chunk of samples: packed layers, the per-member code activations,
//! and the forward pass (the fused training pass is in `train`).
//!
//! A chunk is a run of whole rays of one category; the rays may belong to different members.
//! The four code layers do not depend on the sample, so they are evaluated once per member and
//! step into a *code table* (`[member][slot][padded(W)]`, `c = ReLU(W z + b)`), and the forward
//! pass adds the member's row to every sample's activations. In the backward pass the chunk sums
//! each member's ∂L/∂c per slot (the `dc` tail of a task's gradient buffer); after the
//! deterministic reduction, [`CategoryNet::code_backward`] turns those sums into gradients of
//! the code layers and of the codes, once per member.

use super::super::dense::{Activation, Dense, PackingPlan, Rows};
use super::super::encoding::{self, COL_DIMS, EMB_LD, GEO_DIMS, TRIG_LD};
use super::super::gemm::padded;
use super::super::heads::HeadBuffers;
use super::super::layout::ParamLayout;
use super::super::occupancy::Heads;
use super::super::simd::Backend;

/// Code layers, in table-slot order: three take the shape code, the last the texture code.
pub(crate) const CODE_LAYERS: [&str; 4] = [
    "shape_latent_layer_1",
    "cat_latent_layer",
    "shape_latent_layer_2",
    "texture_latent_layer_1",
];
/// Table slot of `shape_latent_layer_1` (added to y0).
pub(crate) const SHAPE_1: usize = 0;
/// Table slot of `cat_latent_layer` (added to y1).
pub(crate) const CAT: usize = 1;
/// Table slot of `shape_latent_layer_2` (added to y2).
pub(crate) const SHAPE_2: usize = 2;
/// Table slot of `texture_latent_layer_1` (added to y5).
pub(crate) const TEXTURE: usize = 3;

/// Canonical offsets of one code layer (`[W, D]` weight, `[W]` bias).
#[derive(Debug, Clone, Copy)]
struct CodeLayer {
    weight: usize,
    bias: usize,
}

/// The packed category network of one (width, code dimension).
#[derive(Debug, Clone)]
pub struct CategoryNet {
    /// Hidden width W.
    pub hidden: usize,
    /// Code dimension D (of z_s and of z_t each).
    pub code_dim: usize,
    pub(super) layers: [Dense; 10],
    code_layers: [CodeLayer; 4],
    b_param: usize,
    pub(super) b_grad: usize,
    /// Floats of packed weights.
    pub packed_len: usize,
    /// Floats of packed gradient (dense layers and B; the `dc` tail is extra, see the module doc).
    pub grad_len: usize,
}

/// Scratch buffers of one chunk (reused across chunks and steps).
#[derive(Debug, Default)]
pub struct CategoryScratch {
    pub(super) emb: Vec<f32>,
    pub(super) dsin: Vec<f32>,
    /// y0, y0+c, y1, y1+c, y2, y2+c, y3, y4, y5, y5+c, y6, y7 (see the module doc of `category`).
    pub(super) h: [Vec<f32>; 12],
    pub(super) heads: HeadBuffers,
    pub(super) p: Vec<f32>,
    pub(super) q: Vec<f32>,
    pub(super) d_geo: Vec<f32>,
    pub(super) d_col: Vec<f32>,
}

fn ensure(buf: &mut Vec<f32>, len: usize) {
    if buf.len() < len {
        buf.resize(len, 0.0);
    }
}

/// Which member each sample of a chunk belongs to: sample `s` is in ray `s / samples_per_ray`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Membership<'a> {
    /// Member index of each ray of the chunk.
    pub rays: &'a [usize],
    /// Samples per ray.
    pub samples_per_ray: usize,
}

impl Membership<'_> {
    /// The member of sample `s`.
    #[inline]
    pub(crate) fn of(&self, s: usize) -> usize {
        self.rays[s / self.samples_per_ray]
    }
}

impl CategoryNet {
    /// The network of width `hidden` and code dimension `code_dim`.
    pub(crate) fn new(hidden: usize, code_dim: usize) -> Self {
        let layout = ParamLayout::category(hidden, code_dim);
        let mut plan = PackingPlan::default();
        let mut dense = |name: &str, out: usize, segments: &[usize]| {
            plan.dense(
                layout.offset(&format!("{name}.weight")),
                layout.offset(&format!("{name}.bias")),
                out,
                segments,
            )
        };
        let layers = [
            dense("encoding_xyz", hidden, &[GEO_DIMS]),
            dense("shape_layer_1", hidden, &[hidden]),
            dense("cat_layer", hidden, &[hidden, GEO_DIMS]),
            dense("shape_layer_2", hidden, &[hidden]),
            dense("encoding_shape", hidden, &[hidden]),
            dense("sigma", 1, &[hidden]),
            dense("encoding_viewdir", hidden, &[hidden, COL_DIMS]),
            dense("texture_layer_1", hidden, &[hidden]),
            dense("rgb.0", hidden / 2, &[hidden]),
            dense("rgb.2", 3, &[hidden / 2]),
        ];
        let b_grad = plan.extra_grad(3 * encoding_rows());
        let code_layers = CODE_LAYERS.map(|name| CodeLayer {
            weight: layout.offset(&format!("{name}.weight")),
            bias: layout.offset(&format!("{name}.bias")),
        });
        Self {
            hidden,
            code_dim,
            layers,
            code_layers,
            b_param: layout.offset("encoding.B"),
            b_grad,
            packed_len: plan.packed_len,
            grad_len: plan.grad_len,
        }
    }

    /// Row stride of the hidden activations.
    pub(crate) fn hp(&self) -> usize {
        padded(self.hidden)
    }

    /// Floats of one member's row of the code table (and of its `dc` sums).
    pub(crate) fn table_row(&self) -> usize {
        CODE_LAYERS.len() * self.hp()
    }

    /// Packs the canonical `params` into `packed`.
    pub(crate) fn pack(&self, params: &[f32], packed: &mut [f32]) {
        for layer in &self.layers {
            layer.pack(params, packed);
        }
    }

    /// Adds the packed gradient `grad` (dense layers and B) into the canonical gradient `out`.
    pub(crate) fn unpack_grad(&self, grad: &[f32], out: &mut [f32]) {
        for layer in &self.layers {
            layer.unpack_grad(grad, out);
        }
        let n = 3 * encoding_rows();
        for (d, g) in out[self.b_param..self.b_param + n]
            .iter_mut()
            .zip(&grad[self.b_grad..self.b_grad + n])
        {
            *d += g;
        }
    }

    /// The code table of `codes` (one `[z_s ‖ z_t]` per member): `ReLU(W_k z + b_k)` per slot.
    pub(crate) fn code_table(&self, params: &[f32], codes: &[Vec<f32>], table: &mut Vec<f32>) {
        let (hp, d) = (self.hp(), self.code_dim);
        table.clear();
        table.resize(codes.len() * self.table_row(), 0.0);
        for (code, row) in codes.iter().zip(table.chunks_exact_mut(self.table_row())) {
            for (slot, layer) in self.code_layers.iter().enumerate() {
                let z = &code[if slot == TEXTURE { d..2 * d } else { 0..d }];
                for (o, c) in row[slot * hp..slot * hp + self.hidden].iter_mut().enumerate() {
                    let w = &params[layer.weight + o * d..layer.weight + (o + 1) * d];
                    let pre = params[layer.bias + o] + w.iter().zip(z).map(|(w, z)| w * z).sum::<f32>();
                    *c = pre.max(0.0);
                }
            }
        }
    }

    /// Backward of [`CategoryNet::code_table`]: from the summed ∂L/∂c of every member (`dc`,
    /// laid out like the table), adds the code layers' gradients to `grad` and each member's
    /// ∂L/∂[z_s ‖ z_t] to `code_grads`.
    pub(crate) fn code_backward(
        &self,
        params: &[f32],
        codes: &[Vec<f32>],
        table: &[f32],
        dc: &[f32],
        grad: &mut [f32],
        code_grads: &mut [Vec<f32>],
    ) {
        let (hp, d, row) = (self.hp(), self.code_dim, self.table_row());
        for (m, (code, dz)) in codes.iter().zip(code_grads.iter_mut()).enumerate() {
            for (slot, layer) in self.code_layers.iter().enumerate() {
                let zr = if slot == TEXTURE { d..2 * d } else { 0..d };
                for o in 0..self.hidden {
                    let k = m * row + slot * hp + o;
                    if table[k] <= 0.0 {
                        continue; // ReLU backward
                    }
                    let g = dc[k];
                    grad[layer.bias + o] += g;
                    let wg = &mut grad[layer.weight + o * d..layer.weight + (o + 1) * d];
                    for (w, z) in wg.iter_mut().zip(&code[zr.clone()]) {
                        *w += g * z;
                    }
                    let w = &params[layer.weight + o * d..layer.weight + (o + 1) * d];
                    for (dz, w) in dz[zr.clone()].iter_mut().zip(w) {
                        *dz += g * w;
                    }
                }
            }
        }
    }

    fn reserve(&self, s: &mut CategoryScratch, n: usize) {
        let hp = self.hp();
        ensure(&mut s.emb, n * EMB_LD);
        ensure(&mut s.dsin, n * TRIG_LD);
        for h in &mut s.h {
            ensure(h, n * hp);
        }
        s.heads.reserve(n);
        ensure(&mut s.p, n * hp);
        ensure(&mut s.q, n * hp);
        ensure(&mut s.d_geo, n * padded(GEO_DIMS));
        ensure(&mut s.d_col, n * padded(COL_DIMS));
    }

    /// Forward pass of `points` (in the category's NOCS frame) into the scratch; the colour head
    /// only with [`Heads::All`]. `table` is the code table of the step.
    pub(crate) fn forward(
        &self,
        backend: Backend,
        params: &[f32],
        packed: &[f32],
        table: &[f32],
        scale: f32,
        points: &[[f32; 3]],
        members: Membership<'_>,
        s: &mut CategoryScratch,
        heads: Heads,
    ) {
        let n = points.len();
        let (hp, hh) = (self.hp(), padded(self.hidden / 2));
        self.reserve(s, n);
        let b = &params[self.b_param..self.b_param + 3 * encoding_rows()];
        encoding::encode_chunk(backend, points, scale, b, &mut s.emb, &mut s.dsin);
        let geo = Rows::new(&s.emb, EMB_LD);
        let [y0, y0c, y1, y1c, y2, y2c, y3, y4, y5, y5c, y6, y7] = &mut s.h;
        let [l_xyz, l_s1, l_cat, l_s2, l_enc, l_sigma, l_view, l_t1, l_rgb0, l_rgb2] = &self.layers;
        let add = |src: &[f32], dst: &mut [f32], slot: usize, rows: usize| {
            self.add_code(table, src, dst, slot, rows, members);
        };
        l_xyz.forward(backend, packed, n, &[geo], y0, Activation::Relu);
        add(y0, y0c, SHAPE_1, n);
        l_s1.forward(backend, packed, n, &[Rows::new(y0c, hp)], y1, Activation::Relu);
        add(y1, y1c, CAT, n);
        l_cat.forward(backend, packed, n, &[Rows::new(y1c, hp), geo], y2, Activation::Relu);
        add(y2, y2c, SHAPE_2, n);
        l_s2.forward(backend, packed, n, &[Rows::new(y2c, hp)], y3, Activation::Relu);
        l_enc.forward(backend, packed, n, &[Rows::new(y3, hp)], y4, Activation::Linear);
        let a = &mut s.heads.alpha_raw;
        l_sigma.forward(backend, packed, n, &[Rows::new(y4, hp)], a, Activation::Linear);
        s.heads.occupancy_from_raw(n);
        if heads == Heads::OccupancyOnly {
            return;
        }
        let nc = heads.colour_rows(n);
        let col = Rows::new(&s.emb[GEO_DIMS..], EMB_LD);
        l_view.forward(backend, packed, nc, &[Rows::new(y4, hp), col], y5, Activation::Relu);
        add(y5, y5c, TEXTURE, nc);
        l_t1.forward(backend, packed, nc, &[Rows::new(y5c, hp)], y6, Activation::Relu);
        l_rgb0.forward(backend, packed, nc, &[Rows::new(y6, hp)], y7, Activation::Relu);
        let c = &mut s.heads.colour_raw;
        l_rgb2.forward(backend, packed, nc, &[Rows::new(y7, hh)], c, Activation::Linear);
        s.heads.colour_from_raw(nc, n);
    }

    /// `dst = src + table[member(s), slot]`, row by row.
    fn add_code(&self, table: &[f32], src: &[f32], dst: &mut [f32], slot: usize, n: usize, members: Membership<'_>) {
        let hp = self.hp();
        for s in 0..n {
            let c = &table[members.of(s) * self.table_row() + slot * hp..][..hp];
            for ((d, x), c) in dst[s * hp..(s + 1) * hp].iter_mut().zip(&src[s * hp..]).zip(c) {
                *d = x + c;
            }
        }
    }

    /// Occupancy of the last forward pass (n values).
    pub(crate) fn occupancy<'a>(&self, s: &'a CategoryScratch, n: usize) -> &'a [f32] {
        s.heads.occupancy(n)
    }

    /// α (= 10·raw) of the last forward pass.
    pub(crate) fn alpha(&self, s: &CategoryScratch, n: usize) -> Vec<f32> {
        s.heads.alpha(n)
    }

    /// Colours of the last forward pass with [`Heads::All`].
    pub(crate) fn colour<'a>(&self, s: &'a CategoryScratch, n: usize) -> &'a [[f32; 3]] {
        s.heads.colour(n)
    }
}

pub(crate) const fn encoding_rows() -> usize {
    super::super::directions::NUM_DIRECTIONS
}
