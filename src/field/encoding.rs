//! The positional encoding of vMAP's `UniDirsEmbed`, forward and backward on a chunk of points.
//!
//! ```text
//! x'   = x / scale                                   (3)
//! proj = B x'                                        (21; B is 21 × 3 and trainable)
//! emb  = [x', sin(π 2^0 proj), …, sin(π 2^5 proj)]   (3 + 6·21 = 129, band-major)
//! emb[..87] (x' and bands 0–3) feeds geometry, emb[87..] (bands 4–5) feeds colour.
//! ∂emb[3 + 21k + j] / ∂proj_j = π 2^k cos(π 2^k proj_j);   ∂L/∂B[j, c] = Σ_s ∂L/∂proj_j · x'_c
//! ```
//!
//! Storage per chunk of `n` points: `emb` is `[n × EMB_LD]` (x' in columns 0..3, sines in
//! 3..129, padding after) and `dsin` is `[n × TRIG_LD]` with the derivative factors above.
//! Sine and cosine are evaluated on the exactly reduced argument `t − round(t)` of `sin(π t)`
//! (`t = 2^k proj`), which is at least as accurate in f32 as rounding `π t` first.

use pulp::{Simd, WithSimd};

use super::directions::NUM_DIRECTIONS;
use super::simd::Backend;

/// Number of frequency bands (2^0 … 2^5).
pub const NUM_BANDS: usize = 6;
/// Number of sine features (bands × directions).
pub const SIN_DIMS: usize = NUM_BANDS * NUM_DIRECTIONS;
/// Width of the whole embedding: x' and the sines.
pub const EMB_DIMS: usize = 3 + SIN_DIMS;
/// Embedding columns that feed the geometry layers (x' and bands 0–3).
pub const GEO_DIMS: usize = 3 + 4 * NUM_DIRECTIONS;
/// Embedding columns that feed the colour layer (bands 4–5).
pub const COL_DIMS: usize = EMB_DIMS - GEO_DIMS;

/// Row stride of the trig buffers (the sines padded to whole vectors).
pub(crate) const TRIG_LD: usize = 128;
/// Row stride of the embedding buffer.
pub(crate) const EMB_LD: usize = 3 + TRIG_LD + 13;

/// 1.5 · 2^23: adding and subtracting it rounds an f32 of magnitude < 2^22 to the nearest integer.
const ROUND_MAGIC: f32 = 12_582_912.0;

/// Fills `emb` (`[n × EMB_LD]`) and `dsin` (`[n × TRIG_LD]`) for `points`.
pub(crate) fn encode_chunk(
    backend: Backend,
    points: &[[f32; 3]],
    scale: f32,
    b: &[f32],
    emb: &mut [f32],
    dsin: &mut [f32],
) {
    debug_assert_eq!(b.len(), NUM_DIRECTIONS * 3);
    backend.dispatch(EncodeChunk {
        points,
        scale,
        b,
        emb,
        dsin,
    });
}

struct EncodeChunk<'a> {
    points: &'a [[f32; 3]],
    scale: f32,
    b: &'a [f32],
    emb: &'a mut [f32],
    dsin: &'a mut [f32],
}

impl WithSimd for EncodeChunk<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let mut freq = [0.0f32; TRIG_LD];
        for (i, f) in freq.iter_mut().take(SIN_DIMS).enumerate() {
            *f = std::f32::consts::PI * (1u32 << (i / NUM_DIRECTIONS)) as f32;
        }
        let (freq_v, _) = S::as_simd_f32s(&freq);
        for (s, p) in self.points.iter().enumerate() {
            let xs = p.map(|c| c / self.scale);
            let mut t = [0.0f32; TRIG_LD];
            for j in 0..NUM_DIRECTIONS {
                let row = &self.b[3 * j..3 * j + 3];
                let proj = row[0] * xs[0] + row[1] * xs[1] + row[2] * xs[2];
                for k in 0..NUM_BANDS {
                    t[k * NUM_DIRECTIONS + j] = proj * (1u32 << k) as f32;
                }
            }
            let emb_row = &mut self.emb[s * EMB_LD..(s + 1) * EMB_LD];
            emb_row[..3].copy_from_slice(&xs);
            let (t_v, _) = S::as_simd_f32s(&t);
            let (sin_v, _) = S::as_mut_simd_f32s(&mut emb_row[3..3 + TRIG_LD]);
            let (dsin_v, _) = S::as_mut_simd_f32s(&mut self.dsin[s * TRIG_LD..(s + 1) * TRIG_LD]);
            for (((tv, sv), dv), fv) in t_v.iter().zip(sin_v).zip(dsin_v).zip(freq_v) {
                let (sin, cos) = sincos_pi(simd, *tv);
                *sv = sin;
                *dv = simd.mul_f32s(cos, *fv);
            }
        }
    }
}

/// `(sin(π t), cos(π t))` for |t| < 2^22, to about 1 ulp of the reduced argument.
#[inline(always)]
pub(crate) fn sincos_pi<S: Simd>(simd: S, t: S::f32s) -> (S::f32s, S::f32s) {
    let magic = simd.splat_f32s(ROUND_MAGIC);
    let nearest = simd.sub_f32s(simd.add_f32s(t, magic), magic);
    let f = simd.sub_f32s(t, nearest); // exact, in [−0.5, 0.5]
    let half = simd.mul_f32s(nearest, simd.splat_f32s(0.5));
    let half_rounded = simd.sub_f32s(simd.add_f32s(half, magic), magic);
    let odd = simd.abs_f32s(simd.sub_f32s(nearest, simd.add_f32s(half_rounded, half_rounded)));
    let sign = simd.sub_f32s(simd.splat_f32s(1.0), simd.add_f32s(odd, odd));
    let x = simd.mul_f32s(f, simd.splat_f32s(std::f32::consts::PI));
    let x2 = simd.mul_f32s(x, x);
    let c = |v: f64| simd.splat_f32s(v as f32);
    // Taylor series to x^11 / x^12: the first omitted terms are < 6e-8 for |x| ≤ π/2.
    let mut sp = c(-1.0 / 39_916_800.0);
    for coef in [1.0 / 362_880.0, -1.0 / 5040.0, 1.0 / 120.0, -1.0 / 6.0] {
        sp = simd.mul_add_f32s(sp, x2, c(coef));
    }
    let sin = simd.mul_add_f32s(simd.mul_f32s(sp, x2), x, x);
    let mut cp = c(1.0 / 479_001_600.0);
    for coef in [-1.0 / 3_628_800.0, 1.0 / 40_320.0, -1.0 / 720.0, 1.0 / 24.0, -0.5, 1.0] {
        cp = simd.mul_add_f32s(cp, x2, c(coef));
    }
    (simd.mul_f32s(sin, sign), simd.mul_f32s(cp, sign))
}

/// Adds this chunk's gradient of `B` to `grad_b` (21 × 3, row-major), with `backend`'s
/// instructions (no sum is reordered or fused, so every lane width gives the same bits).
///
/// `d_geo` (`[n × geo_ld]`) holds ∂L/∂emb[..87] and `d_col` (`[n × col_ld]`) ∂L/∂emb[87..].
pub(crate) fn backward_chunk(
    backend: Backend,
    emb: &[f32],
    dsin: &[f32],
    d_geo: &[f32],
    geo_ld: usize,
    d_col: &[f32],
    col_ld: usize,
    n: usize,
    grad_b: &mut [f32],
) {
    struct BackwardChunk<'a> {
        emb: &'a [f32],
        dsin: &'a [f32],
        d_geo: &'a [f32],
        geo_ld: usize,
        d_col: &'a [f32],
        col_ld: usize,
        n: usize,
        grad_b: &'a mut [f32],
    }
    impl WithSimd for BackwardChunk<'_> {
        type Output = ();
        #[inline(always)]
        fn with_simd<S: Simd>(self, _simd: S) {
            let geo_sines = GEO_DIMS - 3;
            let geo_bands = geo_sines / NUM_DIRECTIONS;
            for s in 0..self.n {
                let ds = &self.dsin[s * TRIG_LD..][..SIN_DIMS];
                let dg = &self.d_geo[s * self.geo_ld + 3..][..geo_sines];
                let dc = &self.d_col[s * self.col_ld..][..COL_DIMS];
                let xs = &self.emb[s * EMB_LD..][..3];
                // Sine i = band·21 + direction; the first bands feed geometry, the rest colour.
                // Band by band, so that the 21-wide products vectorise.
                let mut dproj = [0.0f32; NUM_DIRECTIONS];
                for (band, dsb) in ds.chunks_exact(NUM_DIRECTIONS).enumerate() {
                    let de = if band < geo_bands {
                        &dg[band * NUM_DIRECTIONS..][..NUM_DIRECTIONS]
                    } else {
                        &dc[(band - geo_bands) * NUM_DIRECTIONS..][..NUM_DIRECTIONS]
                    };
                    for ((acc, a), b) in dproj.iter_mut().zip(dsb).zip(de) {
                        *acc += a * b;
                    }
                }
                for (g, dp) in self.grad_b.chunks_exact_mut(3).zip(&dproj) {
                    g[0] += dp * xs[0];
                    g[1] += dp * xs[1];
                    g[2] += dp * xs[2];
                }
            }
        }
    }
    backend.dispatch(BackwardChunk {
        emb,
        dsin,
        d_geo,
        geo_ld,
        d_col,
        col_ld,
        n,
        grad_b,
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedding_widths_match_vmap() {
        // vMAP trainer.py: emb_size1 = 21·(3+1)+3 = 87, emb_size2 = 21·(5+1)+3 − 87 = 42.
        assert_eq!((GEO_DIMS, COL_DIMS, EMB_DIMS), (87, 42, 129));
    }

    #[test]
    fn the_encoding_gradient_has_the_same_bits_on_every_backend() {
        // Rows of pseudo-random values; the scalar arm is the reference.
        let n = 37;
        let value = |i: usize| ((i * 7919 % 1000) as f32 - 500.0) * 1e-3;
        let emb: Vec<f32> = (0..n * EMB_LD).map(value).collect();
        let dsin: Vec<f32> = (0..n * TRIG_LD).map(|i| value(i + 11)).collect();
        let (geo_ld, col_ld) = (GEO_DIMS + 5, COL_DIMS + 6);
        let d_geo: Vec<f32> = (0..n * geo_ld).map(|i| value(i + 23)).collect();
        let d_col: Vec<f32> = (0..n * col_ld).map(|i| value(i + 47)).collect();
        let run = |backend: Backend| {
            let mut grad_b = vec![0.25f32; NUM_DIRECTIONS * 3];
            backward_chunk(backend, &emb, &dsin, &d_geo, geo_ld, &d_col, col_ld, n, &mut grad_b);
            grad_b
        };
        let reference = run(Backend::Scalar);
        assert!(reference.iter().any(|&g| g != 0.25), "the gradient moved");
        for backend in Backend::all_available() {
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<u32>>();
            assert_eq!(bits(&run(backend)), bits(&reference), "{}", backend.name());
        }
    }

    #[test]
    fn sincos_matches_f64_on_every_backend() {
        let backends = Backend::all_available();
        println!("SIMD paths run: {}", Backend::describe_all(&backends));
        for backend in backends {
            struct Check;
            impl WithSimd for Check {
                type Output = f64;
                #[inline(always)]
                fn with_simd<S: Simd>(self, simd: S) -> f64 {
                    let mut worst = 0.0f64;
                    for i in 0..4000 {
                        let t0 = (i as f32 - 2000.0) * 0.0173;
                        let t = simd.splat_f32s(t0);
                        let (s, c) = sincos_pi(simd, t);
                        let s: &[f32] = bytemuck_slice::<S>(&s);
                        let c: &[f32] = bytemuck_slice::<S>(&c);
                        let arg = std::f64::consts::PI * f64::from(t0);
                        worst = worst.max((f64::from(s[0]) - arg.sin()).abs());
                        worst = worst.max((f64::from(c[0]) - arg.cos()).abs());
                    }
                    worst
                }
            }
            fn bytemuck_slice<S: Simd>(v: &S::f32s) -> &[f32] {
                pulp::bytemuck::cast_slice(std::slice::from_ref(v))
            }
            let worst = backend.dispatch(Check);
            assert!(worst < 3e-7, "{backend:?}: max error {worst}");
        }
    }

    #[test]
    fn encoding_matches_the_formula() {
        let b: Vec<f32> = crate::field::directions::icosphere_directions()
            .iter()
            .flatten()
            .map(|v| *v as f32)
            .collect();
        let points = [[0.3f32, -1.2, 0.7], [2.0, 0.1, -0.4]];
        let mut emb = vec![0.0; 2 * EMB_LD];
        let mut dsin = vec![0.0; 2 * TRIG_LD];
        encode_chunk(Backend::detect(), &points, 2.0, &b, &mut emb, &mut dsin);
        for (s, p) in points.iter().enumerate() {
            let xs: Vec<f64> = p.iter().map(|c| f64::from(*c) / 2.0).collect();
            for k in 0..NUM_BANDS {
                for j in 0..NUM_DIRECTIONS {
                    let proj: f64 = (0..3).map(|c| f64::from(b[3 * j + c]) * xs[c]).sum();
                    let arg = std::f64::consts::PI * 2f64.powi(k as i32) * proj;
                    let i = k * NUM_DIRECTIONS + j;
                    assert!(
                        (f64::from(emb[s * EMB_LD + 3 + i]) - arg.sin()).abs() < 2e-5,
                        "sin [{s}, {i}]"
                    );
                    let d = std::f64::consts::PI * 2f64.powi(k as i32) * arg.cos();
                    let tol = 2e-5 * std::f64::consts::PI * 2f64.powi(k as i32);
                    assert!((f64::from(dsin[s * TRIG_LD + i]) - d).abs() < tol, "dsin [{s}, {i}]");
                }
            }
            assert_eq!(emb[s * EMB_LD..s * EMB_LD + 3], [p[0] / 2.0, p[1] / 2.0, p[2] / 2.0]);
        }
    }
}
