//! Benchmark of the fused field training step, in one run:
//!
//! 1. the machine's SGEMM rate: 1024³ f32 through candle's matmul (gemm), 2·n³/t;
//! 2. (a) the bench shape of FACTS.md: B = 16 plain MLPs 39→32→32→32→4 (ReLU), N = 1200 points
//!    each, L1 loss, Adam: fused steps/s and GFLOP/s (0.394 GFLOP per step, counting
//!    forward + backward as 3× the forward FLOPs), and the same with candle autograd;
//! 3. (b) the real vMAP model: B = 16 object fields (H = 32, 120 rays × 10 samples) plus the
//!    background field (H = 128, 120 rays × (5 + 9) samples), and the same with vMAP's
//!    1200 background rays.
//!
//! ```text
//! cargo run --release -p catmap --features bench --example bench_fields
//! cargo run --release -p catmap --features bench --example bench_fields -- --seconds 5
//! ```

use std::time::{Duration, Instant};

use anyhow::Context;
use candle_core::{Device, Tensor};
use catmap::field::bench::{CandleMlpBatch, MlpBatch, random_rows};
use catmap::field::{AdamWConfig, Backend, FieldBatch, GEO_DIMS, OccupancyField, RaySamples};
use catmap::ids::ObjectId;
use catmap::rng::{RngStream, seeded_rng};
use clap::Parser;

/// Arguments.
#[derive(Parser, Debug)]
struct Args {
    /// Seconds to time each configuration.
    #[arg(long, default_value_t = 3.0)]
    seconds: f64,
    /// Seconds to time the (slow) candle baseline.
    #[arg(long, default_value_t = 3.0)]
    candle_seconds: f64,
    /// Seed of the random weights and samples.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Which parts to run.
    #[arg(long, value_enum, default_value_t = Only::All)]
    only: Only,
}

/// Parts of the benchmark.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum Only {
    /// Everything.
    All,
    /// The fused plain-MLP step (a) only.
    Mlp,
    /// The fused vMAP step (b) only.
    Vmap,
}

#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn report(line: &str) {
    println!("{line}");
}

/// Runs `step` for at least `seconds` after a short warm-up; returns steps per second.
fn steps_per_second(seconds: f64, mut step: impl FnMut() -> anyhow::Result<()>) -> anyhow::Result<f64> {
    for _ in 0..3 {
        step()?;
    }
    let start = Instant::now();
    let mut steps = 0u32;
    while start.elapsed() < Duration::from_secs_f64(seconds) || steps < 3 {
        step()?;
        steps += 1;
    }
    Ok(f64::from(steps) / start.elapsed().as_secs_f64())
}

/// 1024³ SGEMM through candle; GFLOP/s.
fn sgemm_gflops(seconds: f64) -> anyhow::Result<f64> {
    let n = 1024;
    let a = Tensor::randn(0f32, 1.0, (n, n), &Device::Cpu)?;
    let b = Tensor::randn(0f32, 1.0, (n, n), &Device::Cpu)?;
    let rate = steps_per_second(seconds, || {
        let c = a.matmul(&b)?;
        std::hint::black_box(c);
        Ok(())
    })?;
    Ok(rate * 2.0 * (n as f64).powi(3) / 1e9)
}

/// FLOPs of one training step of a plain MLP batch (3 × forward).
fn mlp_step_flops(dims: &[usize], count: usize, points: usize) -> f64 {
    let macs: usize = dims.windows(2).map(|w| w[0] * w[1]).sum();
    3.0 * 2.0 * (macs * count * points) as f64
}

/// FLOPs of one training step of an occupancy field with `hidden` units on `samples` samples.
fn field_step_flops(hidden: usize, samples: usize) -> f64 {
    let h = hidden;
    let macs = GEO_DIMS * h + h * h + (h + GEO_DIMS) * h + h * h + h + (h + 42) * h + 3 * h + 63;
    3.0 * 2.0 * (macs * samples) as f64
}

fn bench_mlp(args: &Args) -> anyhow::Result<()> {
    let dims = [39, 32, 32, 32, 4];
    let (count, points) = (16, 1200);
    let mut rng = seeded_rng(args.seed, RngStream::Mapper);
    let mut mlps = MlpBatch::new(&dims, count, AdamWConfig::adam(1e-3), &mut rng)?;
    let inputs = random_rows(&mut rng, count, points * 39);
    let targets = random_rows(&mut rng, count, points * 4);
    let flops = mlp_step_flops(&dims, count, points);
    let xs: Vec<&[f32]> = inputs.iter().map(Vec::as_slice).collect();
    let ts: Vec<&[f32]> = targets.iter().map(Vec::as_slice).collect();
    let fused = steps_per_second(args.seconds, || {
        mlps.train_step(&xs, &ts)?;
        Ok(())
    })?;
    report(&format!(
        "(a) MLP 16×[39→32→32→32→4], N = 1200, fused     : {fused:8.1} steps/s  {:6.1} GFLOP/s  ({:.3} GFLOP/step)",
        fused * flops / 1e9,
        flops / 1e9
    ));
    if args.only == Only::Mlp {
        return Ok(());
    }

    let params: Vec<&[f32]> = (0..count).filter_map(|b| mlps.params(b)).collect();
    let mut candle = CandleMlpBatch::new(&dims, &params, AdamWConfig::adam(1e-3))?;
    let flat_x: Vec<f32> = inputs.concat();
    let flat_t: Vec<f32> = targets.concat();
    let x = Tensor::from_slice(&flat_x, (count, points, 39), &Device::Cpu)?;
    let t = Tensor::from_slice(&flat_t, (count, points, 4), &Device::Cpu)?;
    let baseline = steps_per_second(args.candle_seconds, || {
        candle.step(&x, &t)?;
        Ok(())
    })?;
    report(&format!(
        "(a) same, candle 0.11 autograd + AdamW           : {baseline:8.1} steps/s  {:6.1} GFLOP/s  (fused is {:.1}×)",
        baseline * flops / 1e9,
        fused / baseline
    ));
    Ok(())
}

fn bench_vmap(args: &Args, background_rays: usize) -> anyhow::Result<()> {
    let (objects, rays) = (16, 120);
    let mut batch = FieldBatch::new(AdamWConfig::default());
    let mut samples = Vec::<RaySamples>::new();
    for i in 0..objects {
        let mut rng = seeded_rng(args.seed, RngStream::Object(ObjectId(i)));
        batch.push(OccupancyField::new(32, 2.0, &mut rng));
        samples.push(RaySamples::random(&mut rng, rays, 10, 2.0, 0.0));
    }
    let mut rng = seeded_rng(args.seed, RngStream::Background);
    batch.push(OccupancyField::new(128, 5.0, &mut rng));
    samples.push(RaySamples::random(&mut rng, background_rays, 14, 2.0, 0.0));
    let flops = objects as f64 * field_step_flops(32, rays * 10) + field_step_flops(128, background_rays * 14);
    let rate = steps_per_second(args.seconds, || {
        batch.train_step(&samples).context("train step")?;
        Ok(())
    })?;
    report(&format!(
        "(b) vMAP 16 objects (120×10, H 32) + bg ({background_rays:4}×14, H 128): {rate:8.1} steps/s  {:6.1} GFLOP/s  ({:.3} GFLOP/step)",
        rate * flops / 1e9,
        flops / 1e9
    ));
    Ok(())
}

/// (c) Object fields alone, as the fast schedule trains them (a few at a time): field steps/s.
fn bench_subsets(args: &Args) -> anyhow::Result<()> {
    let rays = 120;
    for objects in [1usize, 2, 4, 8, 16] {
        let mut batch = FieldBatch::new(AdamWConfig::default());
        let mut samples = Vec::<RaySamples>::new();
        for i in 0..objects {
            let mut rng = seeded_rng(args.seed, RngStream::Object(ObjectId(i as u32)));
            batch.push(OccupancyField::new(32, 2.0, &mut rng));
            samples.push(RaySamples::random(&mut rng, rays, 10, 2.0, 0.0));
        }
        let flops = objects as f64 * field_step_flops(32, rays * 10);
        let rate = steps_per_second(args.seconds, || {
            batch.train_step(&samples).context("train step")?;
            Ok(())
        })?;
        report(&format!(
            "(c) {objects:2} object fields (120×10, H 32)       : {rate:8.1} steps/s  {:8.1} field steps/s  {:6.1} GFLOP/s",
            rate * objects as f64,
            rate * flops / 1e9
        ));
    }
    Ok(())
}

fn run(args: &Args) -> anyhow::Result<()> {
    let backend = Backend::detect();
    report(&format!(
        "backend: {} ({} f32 lanes), rayon threads: {}",
        backend.name(),
        backend.lanes(),
        rayon::current_num_threads()
    ));
    if args.only == Only::All {
        let sgemm = sgemm_gflops(args.seconds)?;
        report(&format!(
            "SGEMM 1024³ f32 (candle/gemm)                   : {sgemm:6.1} GFLOP/s"
        ));
    }
    if args.only != Only::Vmap {
        bench_mlp(args)?;
    }
    if args.only != Only::Mlp {
        bench_vmap(args, 120)?;
        bench_vmap(args, 1200)?;
        bench_subsets(args)?;
    }
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    run(&args)
}
