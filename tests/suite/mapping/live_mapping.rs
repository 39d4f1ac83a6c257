//! Live replay (`catmap run --live`): the small scene replayed far faster than a deliberately
//! slow mapper can map it. The mapper takes the newest frames, the reader counts what it
//! dropped, nothing blocks, and the run ends — finishing time, final meshes — with a whole map.

use std::ops::ControlFlow;
use std::sync::Arc;
use std::time::Duration;

use catmap::dataset::FrameSource;
use catmap::dataset::stream::FrameStream;
use catmap::synth::{Preset, SyntheticScene};
use catmap::{CameraIntrinsics, FrameIndex, MapperConfig, RgbdFrame};
use catmap_systems::resources::StreamProgress;
use catmap_systems::run_state::PhaseProgress;
use catmap_systems::{Mapper, RunOutcome, RunPhase};

/// Frames rendered beforehand, so that the reader keeps its rate.
struct Rendered {
    frames: Vec<RgbdFrame>,
    intrinsics: CameraIntrinsics,
}

impl FrameSource for Rendered {
    fn len(&self) -> usize {
        self.frames.len()
    }
    fn intrinsics(&self) -> CameraIntrinsics {
        self.intrinsics
    }
    fn read_frame(&self, position: usize) -> catmap::Result<RgbdFrame> {
        Ok(self.frames[position].clone())
    }
    fn name(&self) -> String {
        "rendered small scene".to_owned()
    }
}

/// A live mapper on the small scene at 200 frames/s, with a short finishing time.
fn live_config() -> MapperConfig {
    let mut config = MapperConfig {
        seed: 2,
        ..MapperConfig::default()
    };
    config.stream.live.enabled = true;
    config.stream.live.fps = Some(200.0);
    config.stream.live.finish_seconds = 1.0;
    config.categories.min_field_steps = 4;
    config.meshes.object.voxel_size_m = 0.04;
    config.meshes.background_voxel_m = 0.15;
    config
}

#[test]
fn a_slow_mapper_takes_the_newest_frames_counts_the_drops_and_ends_with_a_whole_map() {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let frames: Vec<RgbdFrame> = (0..scene.len())
        .map(|p| scene.read_frame(p).expect("frame renders"))
        .collect();
    let last = FrameIndex(frames.len() as u64 - 1);
    let source = Arc::new(Rendered {
        frames,
        intrinsics: scene.intrinsics(),
    });
    let positions: Vec<usize> = (0..source.len()).collect();
    let total = positions.len() as u64;
    let (done, finished) = crossbeam_channel::bounded(1);
    // The run goes on a thread so that a blocked mapper fails the test instead of hanging it.
    std::thread::spawn(move || {
        let stream = FrameStream::spawn_live(source, positions, 200.0);
        let mut mapper = Mapper::with_inbox(live_config(), stream.receiver.clone()).expect("valid config");
        mapper.count_drops_from(Arc::clone(&stream.dropped));
        // Deliberately slow: every tick takes at least 40 ms more (5 frames' time at 200 fps).
        let outcome = mapper
            .run(|_| {
                std::thread::sleep(Duration::from_millis(40));
                ControlFlow::Continue(())
            })
            .expect("the run");
        stream.join();
        let meshes = mapper.extract_final_meshes().expect("final meshes");
        let _ = done.send((mapper, outcome, meshes));
    });
    let (mapper, outcome, meshes) = finished
        .recv_timeout(Duration::from_secs(300))
        .expect("the live run ends: nothing blocks");
    assert_eq!(outcome, RunOutcome::Complete);
    assert_eq!(mapper.phase(), RunPhase::Done);
    let stats = mapper.stream_stats().expect("the stream ended with its statistics");
    let progress = mapper.world().resource::<StreamProgress>().clone();
    assert_eq!(
        progress.frames_ingested, stats.frames_sent,
        "the mapper took what was sent"
    );
    assert_eq!(
        stats.frames_sent + stats.frames_dropped + stats.frames_skipped,
        total,
        "every frame is taken, dropped or skipped: {stats:?}"
    );
    assert!(stats.frames_dropped > 0, "a slow mapper drops frames: {stats:?}");
    assert!(stats.frames_sent >= 2, "it still maps some: {stats:?}");
    assert_eq!(progress.last_frame, Some(last), "the newest frame is taken");
    let phases = *mapper.world().resource::<PhaseProgress>();
    assert!(
        phases.after_stream_end.is_some(),
        "the finishing phase ended: {phases:?}"
    );
    assert!(mapper.training_steps() > 0, "the fields trained in the time there was");
    assert!(!meshes.objects.is_empty(), "objects meshed");
    let map = mapper.finish();
    assert_eq!(map.frames_ingested, stats.frames_sent);
}
