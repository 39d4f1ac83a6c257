//! Benchmark-only code, compiled with the cargo feature `bench` (and in the crate's own tests):
//! the benchmark shape of FACTS.md — B plain MLPs trained by the same fused machinery as the
//! fields ([`MlpBatch`]) — and its candle autograd twin ([`CandleMlpBatch`], [`mlp_reference`]).
//! `cargo run --release --features bench --example bench_fields` compares them.

mod candle_mlp;
mod mlp;

pub use candle_mlp::{CandleMlpBatch, mlp_reference};
pub use mlp::{MlpBatch, random_rows};
