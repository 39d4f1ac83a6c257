//! Mapping a synthetic scene frame by frame, as the pipeline tests do.

use catmap::MapperConfig;
use catmap::dataset::FrameSource;
use catmap::synth::SyntheticScene;
use std::ops::ControlFlow;

use catmap_systems::{Mapper, RunOutcome};

/// A mapper with `config` fed the frames of `scene` at `positions` one tick each; the stream is
/// then ended and the rest of the run (the training after it, the category phase) is run.
pub fn map_scene(scene: &SyntheticScene, positions: impl IntoIterator<Item = usize>, config: MapperConfig) -> Mapper {
    let mut mapper = Mapper::new(config).expect("valid config");
    for position in positions {
        mapper
            .push(scene.read_frame(position).expect("frame renders"))
            .expect("valid frame");
        mapper.step().expect("a tick");
    }
    mapper.end_stream().expect("a tick");
    mapper.step().expect("a tick");
    assert_eq!(
        mapper.run(|_| ControlFlow::Continue(())).expect("the run"),
        RunOutcome::Complete
    );
    mapper
}
