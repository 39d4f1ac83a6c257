//! vMAP's occupancy MLP (`model.py::OccupancyMap`) on a chunk of samples: fused forward,
//! rendering, loss and backward.
//!
//! ```text
//! emb = encode(x)                          (129; geo = emb[..87], col = emb[87..])
//! h1 = relu(fc(87 → H)(geo))               in_layer
//! h2 = relu(fc(H → H)(h1))                 mid1
//! h3 = relu(fc(H + 87 → H)(h2 ‖ geo))      cat_layer
//! h4 = relu(fc(H → H)(h3))                 mid2
//! α  = 10 · fc(H → 1)(h4)                  out_alpha (no activation)
//! h5 = relu(fc(H + 42 → H)(h4 ‖ col))      color_linear
//! c  = sigmoid(fc(H → 3)(h5))              out_color
//! ```
//!
//! A chunk is a run of whole rays of one field (`n` samples); all activations are sample-major
//! `[n × 16k]` buffers, small enough to stay in L2. The backward pass walks the graph in
//! reverse, reusing two gradient buffers, and accumulates packed gradients (see
//! [`super::dense`]) plus the gradient of the encoding matrix B.

mod train;

use super::dense::{Activation, Dense, PackingPlan, Rows};
use super::encoding::{self, COL_DIMS, EMB_LD, GEO_DIMS, TRIG_LD};
use super::gemm::padded;
use super::heads::HeadBuffers;
use super::layout::ParamLayout;
use super::simd::Backend;

/// The packed occupancy network of one hidden width.
#[derive(Debug, Clone)]
pub struct OccupancyNet {
    /// Hidden width H.
    pub hidden: usize,
    layers: [Dense; 7],
    b_param: usize,
    b_grad: usize,
    /// Floats of packed weights.
    pub packed_len: usize,
    /// Floats of packed gradient.
    pub grad_len: usize,
}

/// Scratch buffers of one chunk (reused across chunks and steps).
#[derive(Debug, Default)]
pub struct OccupancyScratch {
    emb: Vec<f32>,
    dsin: Vec<f32>,
    h: [Vec<f32>; 5],
    heads: HeadBuffers,
    p: Vec<f32>,
    q: Vec<f32>,
    d_geo: Vec<f32>,
    d_col: Vec<f32>,
}

fn ensure(buf: &mut Vec<f32>, len: usize) {
    if buf.len() < len {
        buf.resize(len, 0.0);
    }
}

impl OccupancyNet {
    /// The network with `hidden` units.
    pub(crate) fn new(hidden: usize) -> Self {
        let layout = ParamLayout::occupancy(hidden);
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
            dense("in_layer", hidden, &[GEO_DIMS]),
            dense("mid1", hidden, &[hidden]),
            dense("cat_layer", hidden, &[hidden, GEO_DIMS]),
            dense("mid2", hidden, &[hidden]),
            dense("out_alpha", 1, &[hidden]),
            dense("color_linear", hidden, &[hidden, COL_DIMS]),
            dense("out_color", 3, &[hidden]),
        ];
        let b_grad = plan.extra_grad(3 * encoding_rows());
        let b_param = layout.offset("encoding.B");
        Self {
            hidden,
            layers,
            b_param,
            b_grad,
            packed_len: plan.packed_len,
            grad_len: plan.grad_len,
        }
    }

    /// Packs the canonical `params` into `packed`.
    pub(crate) fn pack(&self, params: &[f32], packed: &mut [f32]) {
        for layer in &self.layers {
            layer.pack(params, packed);
        }
    }

    /// Adds the packed gradient `grad` into the canonical gradient `out`.
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

    fn hp(&self) -> usize {
        padded(self.hidden)
    }

    fn reserve(&self, s: &mut OccupancyScratch, n: usize) {
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

    /// Forward pass of `points` into the scratch; the colour head only when `colour` is true.
    pub(crate) fn forward(
        &self,
        backend: Backend,
        params: &[f32],
        packed: &[f32],
        scale: f32,
        points: &[[f32; 3]],
        s: &mut OccupancyScratch,
        heads: Heads,
    ) {
        let n = points.len();
        let hp = self.hp();
        self.reserve(s, n);
        let b = &params[self.b_param..self.b_param + 3 * encoding_rows()];
        encoding::encode_chunk(backend, points, scale, b, &mut s.emb, &mut s.dsin);
        let geo = Rows {
            data: &s.emb,
            ld: EMB_LD,
        };
        let [h1, h2, h3, h4, h5] = &mut s.h;
        let [l1, l2, l3, l4, la, l5, lc] = &self.layers;
        l1.forward(backend, packed, n, &[geo], h1, Activation::Relu);
        l2.forward(backend, packed, n, &[Rows { data: h1, ld: hp }], h2, Activation::Relu);
        l3.forward(
            backend,
            packed,
            n,
            &[Rows { data: h2, ld: hp }, geo],
            h3,
            Activation::Relu,
        );
        l4.forward(backend, packed, n, &[Rows { data: h3, ld: hp }], h4, Activation::Relu);
        la.forward(
            backend,
            packed,
            n,
            &[Rows { data: h4, ld: hp }],
            &mut s.heads.alpha_raw,
            Activation::Linear,
        );
        s.heads.occupancy_from_raw(n);
        let nc = heads.colour_rows(n);
        if heads == Heads::OccupancyOnly {
            return;
        }
        let col = Rows {
            data: &s.emb[GEO_DIMS..],
            ld: EMB_LD,
        };
        l5.forward(
            backend,
            packed,
            nc,
            &[Rows { data: h4, ld: hp }, col],
            h5,
            Activation::Relu,
        );
        lc.forward(
            backend,
            packed,
            nc,
            &[Rows { data: h5, ld: hp }],
            &mut s.heads.colour_raw,
            Activation::Linear,
        );
        s.heads.colour_from_raw(nc, n);
    }

    /// Occupancy of the last forward pass (n values).
    pub(crate) fn occupancy<'a>(&self, s: &'a OccupancyScratch, n: usize) -> &'a [f32] {
        s.heads.occupancy(n)
    }

    /// Raw α (= 10·raw) of the last forward pass.
    pub(crate) fn alpha(&self, s: &OccupancyScratch, n: usize) -> Vec<f32> {
        s.heads.alpha(n)
    }

    /// Colours of the last forward pass with [`Heads::All`].
    pub(crate) fn colour<'a>(&self, s: &'a OccupancyScratch, n: usize) -> &'a [[f32; 3]] {
        s.heads.colour(n)
    }
}

/// Which heads a forward pass evaluates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Heads {
    /// Occupancy only (meshing, uncertainty).
    OccupancyOnly,
    /// Occupancy and colour.
    All,
    /// Occupancy of every sample, colour of the first this many (training: the samples of rays
    /// whose colour the loss reads; the others' colours are 0).
    ColourOfFirst(usize),
}

impl Heads {
    /// How many of `n` samples get a colour.
    pub(crate) fn colour_rows(self, n: usize) -> usize {
        match self {
            Self::OccupancyOnly => 0,
            Self::All => n,
            Self::ColourOfFirst(k) => k.min(n),
        }
    }
}

const fn encoding_rows() -> usize {
    super::directions::NUM_DIRECTIONS
}
