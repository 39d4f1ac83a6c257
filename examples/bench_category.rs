//! Benchmark of the fused category-field training step (METHOD.md §5):
//!
//! 1. C categories (W = 32, D = 32) × M members, each member 120 rays × 10 samples per step
//!    (the default: 4 × 3 × 120 rays, i.e. 360 rays of 3 600 samples per category): fused
//!    steps/s and GFLOP/s (3 × the forward FLOPs per sample);
//! 2. the same rays through C·M instance-level vMAP fields (H = 32) for comparison;
//! 3. the candle autograd reference (f32 forward + backward, no optimiser) on the same batch.
//!
//! ```text
//! cargo run --release -p catmap --features bench --example bench_category
//! cargo run --release -p catmap --features bench --example bench_category -- --categories 8 --members 2
//! ```

use std::time::{Duration, Instant};

use anyhow::Context;
use candle_core::DType;
use catmap::field::category::reference::category_reference;
use catmap::field::{
    AdamWConfig, Backend, CategoryBatch, CategoryField, CategorySamples, FieldBatch, GEO_DIMS, OccupancyField,
    RaySamples,
};
use catmap::ids::ObjectId;
use catmap::rng::{RngStream, seeded_rng};
use clap::Parser;

/// Arguments.
#[derive(Parser, Debug)]
struct Args {
    /// Number of categories.
    #[arg(long, default_value_t = 4)]
    categories: usize,
    /// Members per category.
    #[arg(long, default_value_t = 3)]
    members: usize,
    /// Rays per member and step.
    #[arg(long, default_value_t = 120)]
    rays: usize,
    /// Seconds to time each configuration.
    #[arg(long, default_value_t = 3.0)]
    seconds: f64,
    /// Skip the (slow) candle reference.
    #[arg(long)]
    no_candle: bool,
    /// Seed of the random weights and samples.
    #[arg(long, default_value_t = 0)]
    seed: u64,
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

/// FLOPs of one training step of the category network (W = `w`) on `samples` samples.
fn category_step_flops(w: usize, samples: usize) -> f64 {
    let macs = GEO_DIMS * w + w * w + (w + GEO_DIMS) * w + 2 * w * w + w + (w + 42) * w + w * w + w * w / 2 + w / 2 * 3;
    3.0 * 2.0 * ((macs + 63) * samples) as f64
}

fn run(args: &Args) -> anyhow::Result<()> {
    let backend = Backend::detect();
    report(&format!(
        "backend: {} ({} f32 lanes), rayon threads: {}",
        backend.name(),
        backend.lanes(),
        rayon::current_num_threads()
    ));
    let (c, m, rays) = (args.categories, args.members, args.rays);
    let mut batch = CategoryBatch::new(AdamWConfig::default());
    let mut samples = Vec::new();
    for i in 0..c {
        let mut rng = seeded_rng(args.seed, RngStream::Object(ObjectId(i as u32)));
        batch.push(CategoryField::new(32, 32, 1.0, m, &mut rng));
        let rays = RaySamples::random(&mut rng, m * rays, 10, 0.8, 0.0);
        let members = (0..m * args.rays).map(|r| r / args.rays).collect();
        samples.push(CategorySamples { rays, members });
    }
    let field = &batch.fields()[0];
    report(&format!(
        "category network: {} parameters (W = {}, D = {}) + {} per member for the codes",
        field.param_count(),
        field.hidden(),
        field.code_dim(),
        field.code_param_count()
    ));
    let flops = c as f64 * category_step_flops(32, m * rays * 10);
    let fused = steps_per_second(args.seconds, || {
        batch.train_step(&samples).context("train step")?;
        Ok(())
    })?;
    report(&format!(
        "category: {c} × {m} members × {rays} rays × 10 samples, fused : {fused:8.1} steps/s  {:6.1} GFLOP/s  ({:.3} GFLOP/step)",
        fused * flops / 1e9,
        flops / 1e9
    ));

    let mut objects = FieldBatch::new(AdamWConfig::default());
    let mut object_samples = Vec::<RaySamples>::new();
    for i in 0..c * m {
        let mut rng = seeded_rng(args.seed, RngStream::ObjectField(ObjectId(i as u32)));
        objects.push(OccupancyField::new(32, 2.0, &mut rng));
        object_samples.push(RaySamples::random(&mut rng, rays, 10, 2.0, 0.0));
    }
    let instance = steps_per_second(args.seconds, || {
        objects.train_step(&object_samples).context("train step")?;
        Ok(())
    })?;
    report(&format!(
        "instance: {} vMAP fields × {rays} rays × 10 samples (H 32)     : {instance:8.1} steps/s",
        c * m
    ));

    if !args.no_candle {
        let reference = steps_per_second(args.seconds, || {
            for (field, s) in batch.fields().iter().zip(&samples) {
                category_reference(field, s, DType::F32)?;
            }
            Ok(())
        })?;
        report(&format!(
            "category, candle autograd f32 (forward + backward only)      : {reference:8.1} steps/s  (fused is {:.1}×)",
            fused / reference
        ));
    }
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    run(&args)
}
