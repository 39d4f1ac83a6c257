//! Small dense matrix products with fused epilogues, vectorised with `pulp` (safe SIMD with
//! run-time dispatch: AVX-512, AVX2+FMA, or scalar).
//!
//! One routine covers the three products of a dense layer on a chunk of `n` samples stored
//! sample-major (`[n × ld]`, features contiguous):
//!
//! | product | C (M × N) | A (M × K) | B (K × N) |
//! |---|---|---|---|
//! | forward | `Y = act(X Wᵀ + b)` (n × out) | `X`, rows | `Wᵀ`, packed panels |
//! | input gradient | `dX = (dY W) ⊙ mask` (n × in) | `dY`, rows | `W`, packed panels |
//! | weight gradient | `dWᵀ += Xᵀ dY` (in × out) | `Xᵀ`, columns of `X` | `dY`, rows |
//!
//! `N` is always a multiple of [`PANEL`] = 16 floats (callers pad feature widths), so each row of
//! a B panel is 16 contiguous floats: one AVX-512 vector, two AVX2 vectors, 16 scalars.
//! The micro-kernel keeps an `MR × 16` block of C in registers (AVX2: 6 × 16, 12 accumulators
//! of its 16 registers; AVX-512: 8 × 32, or 12 × 16 for a last 16-wide panel) and streams K:
//! per step it loads one row of the B panels, broadcasts MR scalars of A and issues `MR · NR`
//! FMAs. C is written once per block, after the epilogue (bias or accumulate as the starting
//! value; ReLU or a ReLU-mask after).
//! Summation order is fixed by the shapes alone, so results are reproducible bit for bit.

use pulp::{Simd, WithSimd};

use super::simd::Backend;

/// Width of a B panel and the padding unit of every vectorised feature dimension.
pub(crate) const PANEL: usize = 16;

/// `n` rounded up to a multiple of [`PANEL`].
pub(crate) const fn padded(n: usize) -> usize {
    n.div_ceil(PANEL) * PANEL
}

/// How A is stored: element `(r, k)` at `data[r * ld + k]` (rows) or `data[k * ld + r]` (columns).
#[derive(Debug, Clone, Copy)]
pub(crate) enum ALayout {
    /// Sample-major rows.
    Rows,
    /// The transpose of a sample-major matrix.
    Cols,
}

/// Starting value of the C block.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Init<'a> {
    /// C = A B.
    Zero,
    /// C = A B + bias (one value per column, `N` long).
    Bias(&'a [f32]),
    /// C += A B.
    Accumulate,
}

/// What happens to the C block before it is stored.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Post<'a> {
    /// Nothing.
    Identity,
    /// ReLU.
    Relu,
    /// Zero where `mask` (same shape as C, row stride `ld`) is not positive: ReLU backward.
    Mask {
        /// The post-activation values of the layer whose gradient is being computed.
        data: &'a [f32],
        /// Row stride of `data`.
        ld: usize,
    },
}

/// One product `C = post(init + A B)`; see the module doc.
#[derive(Debug)]
pub(crate) struct Gemm<'a> {
    /// Rows of A and C.
    pub m: usize,
    /// Inner dimension.
    pub k: usize,
    /// Columns of B and C (a multiple of [`PANEL`]).
    pub n: usize,
    /// A's values, starting at element (0, 0).
    pub a: &'a [f32],
    /// A's layout.
    pub a_layout: ALayout,
    /// A's leading dimension.
    pub lda: usize,
    /// B's values: row `k` of panel `j` starts at `j * b_panel_stride + k * b_row_stride`.
    pub b: &'a [f32],
    /// Distance between panels of B.
    pub b_panel_stride: usize,
    /// Distance between rows of one panel of B.
    pub b_row_stride: usize,
    /// C's values, row-major with leading dimension `ldc`.
    pub c: &'a mut [f32],
    /// C's leading dimension.
    pub ldc: usize,
    /// Starting value of C.
    pub init: Init<'a>,
    /// Operation applied before storing.
    pub post: Post<'a>,
}

impl Gemm<'_> {
    /// Runs the product on `backend`.
    pub(crate) fn run(self, backend: Backend) {
        debug_assert!(self.n.is_multiple_of(PANEL), "C width is padded to panels");
        backend.dispatch(self);
    }
}

impl WithSimd for Gemm<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        // (MR, NR) of the 32-wide and of the 16-wide block: ≤ 24 accumulators with AVX-512's 32
        // registers. AVX2 has 16: 6 × 16 (12 accumulators, 2 B vectors, 1 broadcast) beats
        // 3 × 32, which needs 4 B vectors and spills, so AVX2 uses 16-wide blocks only.
        match S::F32_LANES {
            16 => gemm_blocks::<S, 8, 2, 12, 1>(simd, self),
            8 => gemm_blocks::<S, 6, 2, 6, 2>(simd, self),
            4 => gemm_blocks::<S, 2, 8, 3, 4>(simd, self),
            _ => gemm_blocks::<S, 1, 32, 1, 16>(simd, self),
        }
    }
}

/// Sweeps the C blocks: column blocks of 32 (then 16) outside, so that the B panels stay in L1,
/// row blocks inside.
#[inline(always)]
fn gemm_blocks<S: Simd, const MRW: usize, const NRW: usize, const MRN: usize, const NRN: usize>(simd: S, g: Gemm<'_>) {
    if NRN * S::F32_LANES != PANEL {
        return; // not this backend's arm
    }
    let use_wide = NRW * S::F32_LANES == 2 * PANEL;
    let Gemm {
        m,
        k,
        n,
        a,
        a_layout,
        lda,
        b,
        b_panel_stride,
        b_row_stride,
        c,
        ldc,
        init,
        post,
    } = g;
    let mut col = 0;
    while col < n {
        let wide = use_wide && col + 2 * PANEL <= n;
        let bp = &b[(col / PANEL) * b_panel_stride..];
        let mut r0 = 0;
        while r0 < m {
            let block = Block {
                simd,
                k,
                a,
                a_layout,
                lda,
                bp,
                b_row_stride,
                b_panel_stride,
                r0,
                col,
                init,
                post,
            };
            macro_rules! arm {
                ($max:ident, $nr:ident, $($mr:literal)*) => {{
                    let rows = (m - r0).min($max);
                    match rows {
                        $($mr if $mr < $max => block.run::<$mr, $nr>(c, ldc),)*
                        _ => block.run::<$max, $nr>(c, ldc),
                    }
                    rows
                }};
            }
            r0 += if wide {
                arm!(MRW, NRW, 1 2 3 4 5 6 7)
            } else {
                arm!(MRN, NRN, 1 2 3 4 5 6 7 8 9 10 11)
            };
        }
        col += if wide { 2 * PANEL } else { PANEL };
    }
}

/// One `MR × (NR · lanes)` block of C.
#[derive(Clone, Copy)]
struct Block<'a, S: Simd> {
    simd: S,
    k: usize,
    a: &'a [f32],
    a_layout: ALayout,
    lda: usize,
    bp: &'a [f32],
    b_row_stride: usize,
    b_panel_stride: usize,
    r0: usize,
    col: usize,
    init: Init<'a>,
    post: Post<'a>,
}

impl<S: Simd> Block<'_, S> {
    /// Computes the block. Every loop over `MR` and `NR` has a small constant trip count and a
    /// small body, so that it unrolls and the accumulators stay in registers.
    #[expect(
        clippy::needless_range_loop,
        reason = "indexing by constants keeps the block in registers"
    )]
    #[inline(always)]
    fn run<const MR: usize, const NR: usize>(self, c: &mut [f32], ldc: usize) {
        let simd = self.simd;
        let zero = simd.splat_f32s(0.0);
        let mut acc = [[zero; NR]; MR];
        match self.init {
            Init::Zero => {}
            Init::Bias(bias) => {
                let bv: [S::f32s; NR] = load::<S, NR>(&bias[self.col..]);
                for r in 0..MR {
                    acc[r] = bv;
                }
            }
            Init::Accumulate => {
                for r in 0..MR {
                    acc[r] = load::<S, NR>(&c[(self.r0 + r) * ldc + self.col..]);
                }
            }
        }
        let (k, lda, brs, bps) = (self.k, self.lda, self.b_row_stride, self.b_panel_stride);
        match self.a_layout {
            ALayout::Rows => {
                let base = &self.a[self.r0 * lda..];
                let mut rows: [&[f32]; MR] = [&[]; MR];
                for r in 0..MR {
                    rows[r] = &base[r * lda..r * lda + k];
                }
                for kk in 0..k {
                    let bv = load_b::<S, NR>(self.bp, kk * brs, bps);
                    for r in 0..MR {
                        let x = simd.splat_f32s(rows[r][kk]);
                        for v in 0..NR {
                            acc[r][v] = simd.mul_add_f32s(x, bv[v], acc[r][v]);
                        }
                    }
                }
            }
            ALayout::Cols => {
                for kk in 0..k {
                    let bv = load_b::<S, NR>(self.bp, kk * brs, bps);
                    let xs: &[f32] = &self.a[kk * lda + self.r0..][..MR];
                    for r in 0..MR {
                        let x = simd.splat_f32s(xs[r]);
                        for v in 0..NR {
                            acc[r][v] = simd.mul_add_f32s(x, bv[v], acc[r][v]);
                        }
                    }
                }
            }
        }
        match self.post {
            Post::Identity => {}
            Post::Relu => {
                for r in 0..MR {
                    for v in 0..NR {
                        acc[r][v] = simd.max_f32s(acc[r][v], zero);
                    }
                }
            }
            Post::Mask { data, ld } => {
                for r in 0..MR {
                    let m = load::<S, NR>(&data[(self.r0 + r) * ld + self.col..]);
                    for v in 0..NR {
                        acc[r][v] = simd.select_f32s(simd.greater_than_f32s(m[v], zero), acc[r][v], zero);
                    }
                }
            }
        }
        for r in 0..MR {
            store::<S, NR>(&mut c[(self.r0 + r) * ldc + self.col..], acc[r]);
        }
    }
}

/// Row `off` of the B panels starting at `b`: `NR` vectors, spread over `NR · lanes / 16` panels.
#[inline(always)]
fn load_b<S: Simd, const NR: usize>(b: &[f32], off: usize, panel_stride: usize) -> [S::f32s; NR] {
    let per_panel = PANEL / S::F32_LANES;
    let mut out: [S::f32s; NR] = [pulp::bytemuck::Zeroable::zeroed(); NR];
    for p in 0..NR / per_panel {
        let (v, _) = S::as_simd_f32s(&b[off + p * panel_stride..][..PANEL]);
        out[p * per_panel..(p + 1) * per_panel].copy_from_slice(&v[..per_panel]);
    }
    out
}

/// The first `NR · lanes` floats of `s` as `NR` vectors.
#[inline(always)]
pub(crate) fn load<S: Simd, const NR: usize>(s: &[f32]) -> [S::f32s; NR] {
    let (v, _) = S::as_simd_f32s(&s[..NR * S::F32_LANES]);
    let mut out: [S::f32s; NR] = [pulp::bytemuck::Zeroable::zeroed(); NR];
    out.copy_from_slice(&v[..NR]);
    out
}

/// Stores `NR` vectors into the first `NR · lanes` floats of `s`.
#[inline(always)]
pub(crate) fn store<S: Simd, const NR: usize>(s: &mut [f32], x: [S::f32s; NR]) {
    let (v, _) = S::as_mut_simd_f32s(&mut s[..NR * S::F32_LANES]);
    v[..NR].copy_from_slice(&x);
}

/// `out[c] += Σ_r data[r * ld + c]` for `c < width` (a multiple of [`PANEL`]): bias gradients.
pub(crate) fn add_column_sums(backend: Backend, data: &[f32], rows: usize, ld: usize, out: &mut [f32]) {
    struct ColumnSums<'a> {
        data: &'a [f32],
        rows: usize,
        ld: usize,
        out: &'a mut [f32],
    }
    impl WithSimd for ColumnSums<'_> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: Simd>(self, simd: S) {
            match S::F32_LANES {
                16 => self.panels::<S, 1>(simd),
                8 => self.panels::<S, 2>(simd),
                4 => self.panels::<S, 4>(simd),
                _ => self.panels::<S, 16>(simd),
            }
        }
    }
    impl ColumnSums<'_> {
        /// One 16-column panel at a time, its sums held in `NR` registers.
        #[inline(always)]
        fn panels<S: Simd, const NR: usize>(self, simd: S) {
            if NR * S::F32_LANES != PANEL {
                return;
            }
            for col in (0..self.out.len()).step_by(PANEL) {
                let mut acc = load::<S, NR>(&self.out[col..]);
                for r in 0..self.rows {
                    let x = load::<S, NR>(&self.data[r * self.ld + col..]);
                    for (a, x) in acc.iter_mut().zip(x) {
                        *a = simd.add_f32s(*a, x);
                    }
                }
                store::<S, NR>(&mut self.out[col..], acc);
            }
        }
    }
    debug_assert!(out.len().is_multiple_of(PANEL));
    backend.dispatch(ColumnSums { data, rows, ld, out });
}

#[cfg(test)]
#[path = "gemm_tests.rs"]
mod tests;
