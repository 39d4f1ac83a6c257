//! Long-stream benchmark with training on: memory stays flat and the reader never runs ahead.
//!
//! The stream is the default synthetic scene (14 objects, seed 0) rendered on demand at a low
//! resolution by the reader thread, from a camera that keeps sweeping along the free side of the
//! room with pan, tilt, height and distance oscillating at incommensurate periods, so no two frames
//! show the same view and keyframe windows keep turning over. The mapper is the online instance-mode
//! mapper (clouds, boxes, keyframes, `--steps-per-frame` training steps per frame, previews, class
//! registration with `categories.enabled`).
//!
//! Every `--rss-every` frames it prints the frames ingested, resident memory, elapsed time, and
//! how many frames the reader has produced; at the end the memory after warm-up (spread as ± % of
//! its mean) and the reader's largest lead over the mapper against the channel capacity (the
//! reader can hold at most `capacity` frames in the channel plus one in hand).
//!
//! ```text
//! cargo run --release --features bench --example bench_long_stream
//! cargo run --release --features bench --example bench_long_stream -- --frames 2000 --steps-per-frame 4 --rss-every 100
//! ```

use std::f32::consts::TAU;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use catmap::dataset::FrameSource;
use catmap::dataset::stream::{FrameStream, stream_positions};
use catmap::process_memory::{peak_resident_mib, resident_mib};
use catmap::synth::geometry::SceneGeometry;
use catmap::synth::render::render_view;
use catmap::synth::trajectory::look_rotation;
use catmap::synth::{Preset, Room, SurfaceLabel, SyntheticScene};
use catmap::{CameraIntrinsics, FrameIndex, MapperConfig, RgbdFrame};
use catmap_systems::Mapper;
use catmap_systems::components::{Keyframes, ObjectCloud};
use catmap_systems::resources::StreamProgress;
use catmap_systems::rrd_file::{RrdFooter, save_rrd};
use clap::{Parser, ValueEnum};
use nalgebra::{Isometry3, Translation3};

/// Arguments.
#[derive(Parser, Debug)]
struct Args {
    /// Frames in the stream.
    #[arg(long, default_value_t = 10_000)]
    frames: usize,
    /// Image width × height, pixels.
    #[arg(long, default_value = "160x120", value_parser = parse_size)]
    size: (u32, u32),
    /// Training steps per incoming frame (`fields.steps_per_frame`; one step of 14 object fields
    /// plus every 10th background step costs ≈ 48 ms on 2 cores, so 1 keeps 10 000 frames ≲ 15 min).
    #[arg(long, default_value_t = 1)]
    steps_per_frame: usize,
    /// Class registration while streaming (`categories.enabled`).
    #[arg(long, value_enum, default_value_t = Switch::On)]
    categories: Switch,
    /// Print a row every this many frames.
    #[arg(long, default_value_t = 500)]
    rss_every: u64,
    /// Frames of warm-up, excluded from the flatness check (default: the first 10 %).
    #[arg(long)]
    warm_up: Option<u64>,
    /// Scene seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Also log to Rerun, saving the recording here (e.g. /dev/null to exercise logging only);
    /// the file gets Rerun's chunk index only if `--frames` ≤ `rerun.rrd_footer_max_frames`.
    #[arg(long)]
    rerun_save: Option<std::path::PathBuf>,
}

/// On or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Switch {
    On,
    Off,
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once('x').ok_or("expected WxH, e.g. 160x120")?;
    let parse = |v: &str| v.parse::<u32>().map_err(|e| format!("{v:?}: {e}"));
    Ok((parse(w)?, parse(h)?))
}

/// The default scene's geometry seen by a camera sweeping along its free (−y) side, rendered on
/// demand; counts the frames it has produced.
struct SweepingCamera {
    geometry: SceneGeometry,
    room: Room,
    intrinsics: CameraIntrinsics,
    len: usize,
    /// Frames read so far (the highest position read + 1).
    produced: Arc<AtomicUsize>,
}

impl SweepingCamera {
    fn new(scene: &SyntheticScene, size: (u32, u32), len: usize) -> Self {
        let background = scene.room().surfaces();
        let labels: Vec<SurfaceLabel> = scene
            .objects()
            .iter()
            .map(|o| SurfaceLabel {
                instance_id: u16::try_from(o.id.0).expect("scenes hold fewer than 100 objects"),
                class: o.class(),
            })
            .collect();
        let geometry = SceneGeometry::build(
            background.iter().map(|(label, mesh)| (*label, mesh)),
            labels.into_iter().zip(scene.objects().iter().map(|o| &o.mesh_in_world)),
        );
        let f = 0.8 * size.0 as f32; // the presets' ≈ 64° horizontal field of view
        let intrinsics = CameraIntrinsics {
            width: size.0,
            height: size.1,
            fx: f,
            fy: f,
            cx: (size.0 as f32 - 1.0) / 2.0,
            cy: (size.1 as f32 - 1.0) / 2.0,
        };
        Self {
            geometry,
            room: *scene.room(),
            intrinsics,
            len,
            produced: Arc::new(AtomicUsize::new(0)),
        }
    }

    /// Camera pose of frame `position`: a back-and-forth walk along the −y wall (600 frames per
    /// round trip, ≤ 3 cm per frame) with distance, height, pan and tilt oscillating at periods
    /// that share no factor with it, looking into the room like the scene's own trajectory.
    fn world_from_camera(&self, position: usize) -> Isometry3<f32> {
        let wave = |period: f32| (TAU * position as f32 / period).sin();
        let room = &self.room;
        let x = (room.half_x_m - 0.7) * wave(600.0);
        let y = -room.half_y_m + 0.45 + 0.12 * wave(377.0);
        let z = 1.4 + 0.1 * wave(251.0);
        let yaw = -0.35 * x / room.half_x_m + 0.45 * wave(233.0);
        let pitch = -0.36 + 0.08 * wave(419.0);
        Isometry3::from_parts(Translation3::new(x, y, z), look_rotation(yaw, pitch))
    }
}

impl FrameSource for SweepingCamera {
    fn len(&self) -> usize {
        self.len
    }
    fn intrinsics(&self) -> CameraIntrinsics {
        self.intrinsics
    }
    fn read_frame(&self, position: usize) -> catmap::Result<RgbdFrame> {
        let view = render_view(&self.geometry, &self.intrinsics, &self.world_from_camera(position));
        self.produced.fetch_max(position + 1, Ordering::SeqCst);
        Ok(view.into_rgbd_frame(FrameIndex(position as u64)))
    }
    fn name(&self) -> String {
        format!("synthetic sweep ({} frames)", self.len)
    }
}

/// One printed row.
#[derive(Debug, Clone, Copy)]
struct Sample {
    frames: u64,
    rss_mib: f64,
}

fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt().with_env_filter("warn").init();
    let args = Args::parse();
    run(&args)
}

fn run(args: &Args) -> anyhow::Result<()> {
    let scene = SyntheticScene::generate(args.seed, Preset::Default)?;
    let source = SweepingCamera::new(&scene, args.size, args.frames);
    let produced = Arc::clone(&source.produced);
    drop(scene);
    let mut config = MapperConfig::default();
    config.fields.steps_per_frame = args.steps_per_frame;
    config.categories.enabled = args.categories == Switch::On;
    config.category_fields.enabled = config.categories.enabled;
    let capacity = config.stream.channel_capacity.max(1);
    say(&format!(
        "long stream: {} frames of {}×{}, {} training steps per frame, categories {:?}, channel capacity {capacity}, {} threads",
        args.frames,
        args.size.0,
        args.size.1,
        args.steps_per_frame,
        args.categories,
        std::thread::available_parallelism().map_or(1, |n| n.get()),
    ));
    let started = Instant::now();
    let stream = FrameStream::spawn(Arc::new(source), stream_positions(args.frames, 1, None), capacity);
    let footer = RrdFooter::for_stream(Some(args.frames as u64), &config.rerun);
    let mut mapper = Mapper::with_inbox(config, stream.receiver.clone())?;
    if let Some(path) = &args.rerun_save {
        let builder = rerun::RecordingStreamBuilder::new("catmap_long_stream");
        mapper.set_recording(save_rrd(builder, path, footer)?);
        say(&format!(
            "  logging to Rerun, saved to {} ({footer:?} chunk index)",
            path.display()
        ));
    }
    say(&format!(
        "  rss before streaming: {:.1} MiB",
        resident_mib().unwrap_or(f64::NAN)
    ));
    say("  frames  RSS [MiB]  elapsed [s]  read by reader  lead  training steps  cloud voxels  keyframes [KiB]");
    let mut samples = Vec::new();
    let mut max_lead = 0;
    let mut next_row = args.rss_every.max(1);
    while !mapper.stream_ended() {
        if stream.receiver.is_empty() {
            let mut select = crossbeam_channel::Select::new();
            select.recv(&stream.receiver);
            let _ = select.ready_timeout(Duration::from_millis(100));
            continue;
        }
        mapper.step()?;
        let ingested = mapper.world().resource::<StreamProgress>().frames_ingested;
        // The mapper does not ingest while we look, so this is the reader's lead right now.
        let lead = produced.load(Ordering::SeqCst).saturating_sub(ingested as usize);
        max_lead = max_lead.max(lead);
        if ingested >= next_row {
            let rss_mib = resident_mib().unwrap_or(f64::NAN);
            samples.push(Sample {
                frames: ingested,
                rss_mib,
            });
            let (voxels, keyframe_bytes) = map_size(mapper.world_mut());
            say(&format!(
                "  {ingested:>6}  {rss_mib:>9.1}  {:>11.1}  {:>14}  {lead:>4}  {:>14}  {voxels:>12}  {:>15.0}",
                started.elapsed().as_secs_f64(),
                produced.load(Ordering::SeqCst),
                mapper.training_steps(),
                keyframe_bytes as f64 / 1024.0,
            ));
            next_row += args.rss_every.max(1);
        }
    }
    let seconds = started.elapsed().as_secs_f64();
    let stats = mapper.stream_stats().unwrap_or_default();
    let steps = mapper.training_steps();
    let stages = mapper.stage_seconds();
    let map = mapper.finish();
    stream.join();
    say(&format!(
        "\n{} frames in {seconds:.1} s ({:.1} frames/s), {steps} training steps, {} objects; peak RSS {:.1} MiB",
        stats.frames_sent,
        stats.frames_sent as f64 / seconds,
        map.objects.len(),
        peak_resident_mib().unwrap_or(f64::NAN)
    ));
    let stage_list: Vec<String> = stages.iter().map(|(k, v)| format!("{k} {v:.1}")).collect();
    say(&format!("  seconds per stage: {}", stage_list.join(", ")));
    let warm_up = args.warm_up.unwrap_or(args.frames as u64 / 10);
    say_flatness(&samples, warm_up);
    say(&format!(
        "  reader: max lead {max_lead} frames (channel capacity {capacity} + 1 in hand = bound {}) → {}; \
         blocked on the full channel {:.1} s of {seconds:.1} s, rendering {:.1} s",
        capacity + 1,
        if max_lead <= capacity + 1 {
            "held back"
        } else {
            "RAN AHEAD"
        },
        stats.blocked_time.as_secs_f64(),
        stats.decode_time.as_secs_f64(),
    ));
    anyhow::ensure!(max_lead <= capacity + 1, "the reader ran {max_lead} frames ahead");
    Ok(())
}

/// What the map holds that may grow with the stream: cloud voxels (objects and background) and
/// the bytes of every keyframe crop.
fn map_size(world: &mut bevy_ecs::world::World) -> (usize, usize) {
    let voxels = world.query::<&ObjectCloud>().iter(world).map(|c| c.0.len()).sum();
    let keyframe_bytes = world
        .query::<&Keyframes>()
        .iter(world)
        .flat_map(|k| k.0.slots())
        .map(|slot| slot.data.byte_size())
        .sum();
    (voxels, keyframe_bytes)
}

/// Prints the memory at the end of warm-up and the spread of every later sample.
fn say_flatness(samples: &[Sample], warm_up: u64) {
    let at_warm_up = samples.iter().find(|s| s.frames >= warm_up);
    let after: Vec<Sample> = samples.iter().copied().filter(|s| s.frames > warm_up).collect();
    let (Some(at_warm_up), false) = (at_warm_up, after.is_empty()) else {
        say("  too few samples after warm-up to judge flatness");
        return;
    };
    let rss: Vec<f64> = after.iter().map(|s| s.rss_mib).collect();
    let (lo, hi) = rss.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &r| {
        (lo.min(r), hi.max(r))
    });
    let mean = rss.iter().sum::<f64>() / rss.len() as f64;
    let spread = 100.0 * (hi - mean).max(mean - lo) / mean;
    say(&format!(
        "  warm-up: first {warm_up} frames, RSS {:.1} MiB at frame {}",
        at_warm_up.rss_mib, at_warm_up.frames
    ));
    say(&format!(
        "  after warm-up ({} samples): RSS min {lo:.1}, max {hi:.1}, mean {mean:.1} MiB → spread ±{spread:.1} % ({}); \
         trend {:+.2} MiB per 1000 frames",
        rss.len(),
        if spread <= 10.0 {
            "flat within ±10 %"
        } else {
            "NOT flat within ±10 %"
        },
        slope_per_frame(&after) * 1000.0,
    ));
}

/// Least-squares slope of RSS over frames, MiB per frame.
fn slope_per_frame(samples: &[Sample]) -> f64 {
    let n = samples.len() as f64;
    let mx = samples.iter().map(|s| s.frames as f64).sum::<f64>() / n;
    let my = samples.iter().map(|s| s.rss_mib).sum::<f64>() / n;
    let (sxy, sxx) = samples.iter().fold((0.0, 0.0), |(sxy, sxx), s| {
        let dx = s.frames as f64 - mx;
        (sxy + dx * (s.rss_mib - my), sxx + dx * dx)
    });
    if sxx > 0.0 { sxy / sxx } else { 0.0 }
}

#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn say(line: &str) {
    println!("{line}");
}
