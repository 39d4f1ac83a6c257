//! Benchmark of the streaming core (no training): read + ingest + masks + clouds + boxes.
//!
//! 1. Throughput: the default 640×480 synthetic scene, decoded from PNGs by the reader thread and
//!    mapped; prints frames/s and seconds per stage.
//! 2. Memory: a long stream (default 5 000 frames, the scene's frames replayed with new indices);
//!    prints resident memory every few hundred frames and the peak, and how long the reader was
//!    held back by the bounded channel.
//!
//! ```text
//! cargo run --release --features bench --example bench_ingest                 # writes the scene to target/bench-scene
//! cargo run --release --features bench --example bench_ingest -- --long-frames 10000
//! ```

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use catmap::dataset::FrameSource;
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::stream::{FrameStream, stream_positions};
use catmap::process_memory::{peak_resident_mib, resident_mib};
use catmap::synth::{Preset, SyntheticScene, write_replica_layout};
use catmap::{CameraIntrinsics, MapperConfig, RgbdFrame};
use catmap_systems::{Mapper, RunPhase};
use clap::Parser;

/// Arguments.
#[derive(Parser, Debug)]
struct Args {
    /// Dataset folder (Replica layout). Default: the default synthetic scene, written once to
    /// `target/bench-scene`.
    #[arg(long)]
    dataset: Option<PathBuf>,
    /// Frames of the long (memory) stream.
    #[arg(long, default_value_t = 5000)]
    long_frames: usize,
    /// Print memory every this many frames.
    #[arg(long, default_value_t = 500)]
    rss_every: u64,
}

/// Replays a source's frames cyclically, with increasing frame indices.
struct Replayed {
    inner: ReplicaSequence,
    len: usize,
}

impl FrameSource for Replayed {
    fn len(&self) -> usize {
        self.len
    }
    fn intrinsics(&self) -> CameraIntrinsics {
        self.inner.intrinsics()
    }
    fn read_frame(&self, position: usize) -> catmap::Result<RgbdFrame> {
        let mut frame = self.inner.read_frame(position % self.inner.len())?;
        frame.index = catmap::FrameIndex(position as u64);
        Ok(frame)
    }
    fn name(&self) -> String {
        format!("{} (replayed to {} frames)", self.inner.name(), self.len)
    }
}

fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt().with_env_filter("warn").init();
    let args = Args::parse();
    let dir = match &args.dataset {
        Some(dir) => dir.clone(),
        None => {
            let dir = PathBuf::from("target/bench-scene");
            if !dir.join("traj_w_c.txt").exists() {
                say("writing the default synthetic scene to target/bench-scene …");
                write_replica_layout(&SyntheticScene::generate(0, Preset::Default)?, &dir, |_, _| {})?;
            }
            dir
        }
    };
    let open = || ReplicaSequence::open(&dir, &ReplicaOptions::default());
    say(&format!(
        "machine: {} threads available",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    ));

    // 1. Throughput.
    let source: Arc<dyn FrameSource> = Arc::new(open()?);
    let frames = source.len();
    let (w, h) = (source.intrinsics().width, source.intrinsics().height);
    let mut config = MapperConfig {
        fields: catmap::config::FieldConfig::disabled(),
        ..MapperConfig::default()
    };
    config.category_fields.enabled = false; // ingest only
    let started = Instant::now();
    let stream = FrameStream::spawn(
        source,
        stream_positions(frames, 1, None),
        config.stream.channel_capacity,
    );
    let mut mapper = Mapper::with_inbox(config.clone(), stream.receiver.clone())?;
    mapper.run(|_| ControlFlow::Continue(()))?;
    stream.join();
    let seconds = started.elapsed().as_secs_f64();
    let stats = mapper.stream_stats().unwrap_or_default();
    let stages = mapper.stage_seconds();
    let map = mapper.finish();
    say(&format!(
        "\nthroughput: {frames} frames of {w}×{h} in {seconds:.2} s = {:.1} frames/s ({} objects)",
        frames as f64 / seconds,
        map.objects.len()
    ));
    say(&format!(
        "  reader thread: decode {:.2} s, blocked on the full channel {:.2} s",
        stats.decode_time.as_secs_f64(),
        stats.blocked_time.as_secs_f64()
    ));
    for (stage, secs) in &stages {
        say(&format!(
            "  {stage:<8} {secs:>7.2} s  ({:.2} ms/frame)",
            secs * 1000.0 / frames as f64
        ));
    }

    // 2. Memory over a long stream.
    let long = Replayed {
        inner: open()?,
        len: args.long_frames,
    };
    let long: Arc<dyn FrameSource> = Arc::new(long);
    let stream = FrameStream::spawn(
        long,
        stream_positions(args.long_frames, 1, None),
        config.stream.channel_capacity,
    );
    let mut mapper = Mapper::with_inbox(config, stream.receiver.clone())?;
    say(&format!(
        "\nlong stream: {} frames, RSS every {} frames",
        args.long_frames, args.rss_every
    ));
    say("  frames   RSS (MiB)");
    let started = Instant::now();
    let mut next_report = args.rss_every;
    let mut samples = Vec::new();
    mapper.run(|progress| {
        let n = progress.done;
        if progress.phase == RunPhase::Stream && n >= next_report {
            let rss = resident_mib().unwrap_or(f64::NAN);
            samples.push((n, rss));
            say(&format!("  {n:>6}   {rss:>8.1}"));
            next_report += args.rss_every;
        }
        ControlFlow::Continue(())
    })?;
    stream.join();
    let stats = mapper.stream_stats().unwrap_or_default();
    let seconds = started.elapsed().as_secs_f64();
    let warm: Vec<f64> = samples.iter().skip(samples.len() / 5).map(|s| s.1).collect();
    let (lo, hi) = warm
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &r| (lo.min(r), hi.max(r)));
    say(&format!(
        "  {:.1} frames/s; peak RSS {:.1} MiB",
        args.long_frames as f64 / seconds,
        peak_resident_mib().unwrap_or(f64::NAN)
    ));
    say(&format!(
        "  after warm-up (last 80 % of samples): RSS {lo:.1}–{hi:.1} MiB, spread {:.1} %",
        100.0 * (hi - lo) / lo.max(1e-9)
    ));
    say(&format!(
        "  reader blocked on the full channel for {:.1} s of {:.1} s (backpressure)",
        stats.blocked_time.as_secs_f64(),
        seconds
    ));
    Ok(())
}

#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn say(line: &str) {
    println!("{line}");
}
