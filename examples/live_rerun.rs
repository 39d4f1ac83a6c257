//! Stream the default synthetic scene to a running Rerun viewer and watch frames, masks and
//! each object's observed cloud and box appear live.
//!
//! ```text
//! rerun &                                   # a viewer (pip install rerun-sdk==0.36.3)
//! cargo run --release --example live_rerun  # or: -- --addr rerun+http://127.0.0.1:9876/proxy
//! ```

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::Arc;

use anyhow::Context as _;
use catmap::MapperConfig;
use catmap::dataset::FrameSource;
use catmap::dataset::stream::{FrameStream, stream_positions};
use catmap::synth::{Preset, SyntheticScene};
use catmap_systems::Mapper;
use clap::Parser;

/// Arguments.
#[derive(Parser, Debug)]
struct Args {
    /// Address of the Rerun viewer's gRPC proxy.
    #[arg(long, default_value = "rerun+http://127.0.0.1:9876/proxy")]
    addr: String,
    /// Seed of the scene and the mapper.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Use the small scene (fast) instead of the default one.
    #[arg(long)]
    small: bool,
    /// Save the stream to this .rrd file instead of connecting to a viewer.
    #[arg(long)]
    save: Option<PathBuf>,
}

fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt().with_env_filter("info").init();
    let args = Args::parse();
    let builder = rerun::RecordingStreamBuilder::new("catmap_live");
    let rec = match &args.save {
        Some(path) => builder
            .save(path)
            .with_context(|| format!("cannot write {}", path.display()))?,
        None => builder
            .connect_grpc_opts(args.addr.clone())
            .with_context(|| format!("no Rerun viewer at {}", args.addr))?,
    };
    run(&rec, &args)
}

fn run(rec: &rerun::RecordingStream, args: &Args) -> anyhow::Result<()> {
    let preset = if args.small { Preset::Small } else { Preset::Default };
    let scene: Arc<dyn FrameSource> = Arc::new(SyntheticScene::generate(args.seed, preset)?);
    let config = MapperConfig {
        seed: args.seed,
        ..MapperConfig::default()
    };
    let positions = stream_positions(scene.len(), 1, None);
    let stream = FrameStream::spawn(scene, positions, config.stream.channel_capacity);
    let mut mapper = Mapper::with_inbox(config, stream.receiver.clone())?;
    mapper.set_recording(rec.clone());
    mapper.run(|progress| {
        tracing::debug!(phase = ?progress.phase, done = progress.done, "mapped");
        ControlFlow::Continue(())
    })?;
    stream.join();
    let map = mapper.finish();
    tracing::info!(
        objects = map.objects.len(),
        frames = map.frames_ingested,
        "streamed to Rerun"
    );
    Ok(())
}
