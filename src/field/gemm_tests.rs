//! Tests of [`super`]: every backend against a naive product, and a timing harness.

use super::*;

/// Naive reference of one product.
fn naive(m: usize, k: usize, n: usize, a: impl Fn(usize, usize) -> f32, b: impl Fn(usize, usize) -> f32) -> Vec<f64> {
    let mut c = vec![0.0; m * n];
    for r in 0..m {
        for j in 0..n {
            c[r * n + j] = (0..k).map(|kk| f64::from(a(r, kk)) * f64::from(b(kk, j))).sum();
        }
    }
    c
}

fn value(i: usize) -> f32 {
    ((i * 7919 % 113) as f32 - 56.0) / 37.0
}

fn check_backend(backend: Backend) {
    // m = 13 exercises every tail, k = 9, n = 32 (two panels); A stored as rows and as columns.
    let (m, k, n) = (13, 9, 32);
    let a: Vec<f32> = (0..m * k).map(value).collect();
    let at: Vec<f32> = (0..k * m).map(|i| a[(i % m) * k + i / m]).collect();
    // B packed as panels: row kk of panel j at j*k*16 + kk*16.
    let b_full = |kk: usize, j: usize| value(1000 + kk * n + j);
    let mut bp = vec![0.0; k * n];
    for j in 0..n {
        for kk in 0..k {
            bp[(j / PANEL) * k * PANEL + kk * PANEL + j % PANEL] = b_full(kk, j);
        }
    }
    let bias: Vec<f32> = (0..n).map(|j| value(5000 + j)).collect();
    let expected = naive(m, k, n, |r, kk| a[r * k + kk], b_full);
    for (layout, data, lda) in [(ALayout::Rows, &a, k), (ALayout::Cols, &at, m)] {
        let mut c = vec![0.5; m * n];
        Gemm {
            m,
            k,
            n,
            a: data,
            a_layout: layout,
            lda,
            b: &bp,
            b_panel_stride: k * PANEL,
            b_row_stride: PANEL,
            c: &mut c,
            ldc: n,
            init: Init::Bias(&bias),
            post: Post::Relu,
        }
        .run(backend);
        for (i, (got, want)) in c.iter().zip(&expected).enumerate() {
            let want = (want + f64::from(bias[i % n])).max(0.0);
            assert!(
                (f64::from(*got) - want).abs() < 1e-5,
                "{backend:?} {layout:?} [{i}]: {got} vs {want}"
            );
        }
        let mut acc = vec![1.0; m * n];
        let mask: Vec<f32> = (0..m * n).map(|i| if i % 3 == 0 { 0.0 } else { 1.0 }).collect();
        Gemm {
            m,
            k,
            n,
            a: data,
            a_layout: layout,
            lda,
            b: &bp,
            b_panel_stride: k * PANEL,
            b_row_stride: PANEL,
            c: &mut acc,
            ldc: n,
            init: Init::Accumulate,
            post: Post::Mask { data: &mask, ld: n },
        }
        .run(backend);
        for (i, (got, want)) in acc.iter().zip(&expected).enumerate() {
            let want = if i % 3 == 0 { 0.0 } else { want + 1.0 };
            assert!(
                (f64::from(*got) - want).abs() < 1e-5,
                "{backend:?} {layout:?} masked [{i}]"
            );
        }
    }
}

#[test]
fn every_backend_matches_a_naive_product() {
    let backends = Backend::all_available();
    println!("SIMD paths run: {}", Backend::describe_all(&backends));
    for backend in backends {
        check_backend(backend);
    }
}

#[test]
fn column_sums_add_every_row() {
    let data: Vec<f32> = (0..5 * 20).map(value).collect();
    let backends = Backend::all_available();
    println!("SIMD paths run: {}", Backend::describe_all(&backends));
    for backend in backends {
        let mut out = vec![1.0; 16];
        add_column_sums(backend, &data, 5, 20, &mut out);
        for (c, o) in out.iter().enumerate() {
            let want: f32 = 1.0 + (0..5).map(|r| data[r * 20 + c]).sum::<f32>();
            assert!((o - want).abs() < 1e-5, "{backend:?} column {c}");
        }
    }
}
