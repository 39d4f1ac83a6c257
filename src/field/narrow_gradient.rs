//! The weight gradient of a narrow layer (a head with 1 or 3 outputs) as a sum of scaled input
//! rows, instead of a GEMM over outputs padded to a 16-wide panel.
//!
//! `dWᵀ[kk][o] += Σ_i x[i][kk] · dy[i][o]`: the GEMM computes it with the samples as its inner
//! dimension and 16 output columns, 15 of them padding, so a 1-wide head costs one vector
//! multiply-add per sample and input — as much as half a 32-wide hidden layer. Here each output
//! `o` keeps the inputs in the lanes (`k / lanes` vectors) and adds `dy[i][o] · x[i]` sample by
//! sample: one multiply-add per sample and 16 inputs.
//!
//! Each gradient entry is the same chain of fused multiply-adds, in the same sample order and
//! starting from the same value, as the GEMM's (a product's operands only change sides), so the
//! result is bit-identical to it on every backend.

use pulp::{Simd, WithSimd};

use super::dense::Rows;
use super::gemm::{PANEL, load, store};
use super::simd::Backend;

/// Layers at most this wide take the narrow weight gradient.
pub(crate) const NARROW_OUTPUTS: usize = 4;

/// `grad[kk · ldg + o] += Σ_{i < n} x[i][kk] · dy[i][o]` for `kk < k`, `o < out`, summed in
/// sample order.
pub(crate) fn add_narrow_weight_gradient(
    backend: Backend,
    n: usize,
    x: Rows<'_>,
    k: usize,
    dy: Rows<'_>,
    out: usize,
    grad: &mut [f32],
    ldg: usize,
) {
    backend.dispatch(NarrowGradient {
        n,
        x,
        k,
        dy,
        out,
        grad,
        ldg,
    });
}

struct NarrowGradient<'a> {
    n: usize,
    x: Rows<'a>,
    k: usize,
    dy: Rows<'a>,
    out: usize,
    grad: &'a mut [f32],
    ldg: usize,
}

impl WithSimd for NarrowGradient<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        match S::F32_LANES {
            16 => self.outputs::<S, 1>(simd),
            8 => self.outputs::<S, 2>(simd),
            4 => self.outputs::<S, 4>(simd),
            _ => self.outputs::<S, 16>(simd),
        }
    }
}

impl NarrowGradient<'_> {
    /// The output count as a constant, so that the loops over outputs unroll.
    #[inline(always)]
    fn outputs<S: Simd, const NR: usize>(self, simd: S) {
        match self.out {
            0 => {}
            1 => self.blocks::<S, NR, 1>(simd),
            2 => self.blocks::<S, NR, 2>(simd),
            3 => self.blocks::<S, NR, 3>(simd),
            _ => self.blocks::<S, NR, NARROW_OUTPUTS>(simd),
        }
    }

    /// 16 inputs of every output at a time, their sums held in `OUT × NR` registers.
    #[inline(always)]
    fn blocks<S: Simd, const NR: usize, const OUT: usize>(self, simd: S) {
        if NR * S::F32_LANES != PANEL {
            return; // not this backend's arm
        }
        let Self {
            n,
            x,
            k,
            dy,
            out,
            grad,
            ldg,
        } = self;
        debug_assert!(out == OUT);
        let zero = simd.splat_f32s(0.0);
        for kb in (0..k).step_by(PANEL) {
            let width = (k - kb).min(PANEL);
            let mut acc = [[zero; NR]; OUT];
            let mut sums = [0.0f32; PANEL];
            for o in 0..OUT {
                for (j, s) in sums[..width].iter_mut().enumerate() {
                    *s = grad[(kb + j) * ldg + o];
                }
                acc[o] = load::<S, NR>(&sums);
            }
            let mut tail = [0.0f32; PANEL];
            for i in 0..n {
                let start = i * x.ld + kb;
                // Lanes past `width` read the next row (or zeros) and are never stored.
                let xv = if start + PANEL <= x.data.len() {
                    load::<S, NR>(&x.data[start..])
                } else {
                    tail[..width].copy_from_slice(&x.data[start..start + width]);
                    load::<S, NR>(&tail)
                };
                let dy_row = &dy.data[i * dy.ld..][..OUT];
                for o in 0..OUT {
                    let d = simd.splat_f32s(dy_row[o]);
                    for v in 0..NR {
                        acc[o][v] = simd.mul_add_f32s(d, xv[v], acc[o][v]);
                    }
                }
            }
            for o in 0..OUT {
                store::<S, NR>(&mut sums, acc[o]);
                for (j, s) in sums[..width].iter().enumerate() {
                    grad[(kb + j) * ldg + o] = *s;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::gemm::{ALayout, Gemm, Init, Post};

    /// The GEMM the narrow gradient replaces: `dWᵀ += xᵀ dy` over 16 padded output columns.
    fn gemm_gradient(backend: Backend, n: usize, x: Rows<'_>, k: usize, dy: Rows<'_>, grad: &mut [f32]) {
        Gemm {
            m: k,
            k: n,
            n: PANEL,
            a: x.data,
            a_layout: ALayout::Cols,
            lda: x.ld,
            b: dy.data,
            b_panel_stride: PANEL,
            b_row_stride: dy.ld,
            c: grad,
            ldc: PANEL,
            init: Init::Accumulate,
            post: Post::Identity,
        }
        .run(backend);
    }

    #[test]
    fn narrow_weight_gradients_are_bit_identical_to_the_padded_gemm_on_every_backend() {
        let backends = Backend::all_available();
        println!("SIMD paths run: {}", Backend::describe_all(&backends));
        // A 32-wide input (whole blocks) and a 21-wide one of stride 21 (a tail that reaches
        // past the last row), 1- and 3-wide outputs, 37 samples.
        for (k, ld) in [(32, 32), (21, 21), (40, 48)] {
            for out in [1, 3] {
                let n = 37;
                let x: Vec<f32> = (0..n * ld).map(|i| ((i * 7919 % 113) as f32 - 56.0) / 17.0).collect();
                let dy: Vec<f32> = (0..n * PANEL)
                    .map(|i| {
                        if i % PANEL < out {
                            ((i * 31 % 29) as f32 - 14.0) / 9.0
                        } else {
                            0.0
                        }
                    })
                    .collect();
                let start: Vec<f32> = (0..k * PANEL).map(|i| (i as f32 * 0.37).sin()).collect();
                for &backend in &backends {
                    let (xr, dyr) = (Rows::new(&x, ld), Rows::new(&dy, PANEL));
                    let mut want = start.clone();
                    gemm_gradient(backend, n, xr, k, dyr, &mut want);
                    let mut got = start.clone();
                    add_narrow_weight_gradient(backend, n, xr, k, dyr, out, &mut got, PANEL);
                    for kk in 0..k {
                        for o in 0..out {
                            let (g, w) = (got[kk * PANEL + o], want[kk * PANEL + o]);
                            assert_eq!(
                                g.to_bits(),
                                w.to_bits(),
                                "{backend:?} k {k} out {out}: [{kk}][{o}] {g} vs {w}"
                            );
                        }
                        for o in out..PANEL {
                            assert_eq!(got[kk * PANEL + o], start[kk * PANEL + o], "padding untouched");
                        }
                    }
                }
            }
        }
    }
}
