//! Mapping a synthetic scene frame by frame, as the pipeline tests do.

use catmap::MapperConfig;
use catmap::dataset::FrameSource;
use catmap::synth::SyntheticScene;
use catmap_systems::Mapper;

/// A mapper with `config` fed the frames of `scene` at `positions` one tick each; the stream is
/// then ended and the training due after it (`FieldConfig::steps_after_stream`) is run.
pub fn map_scene(scene: &SyntheticScene, positions: impl IntoIterator<Item = usize>, config: MapperConfig) -> Mapper {
    let mut mapper = Mapper::new(config).expect("valid config");
    for position in positions {
        mapper
            .push(scene.read_frame(position).expect("frame renders"))
            .expect("valid frame");
        mapper.step();
    }
    mapper.end_stream();
    mapper.step();
    mapper.train_after_stream(|_, _| {});
    mapper
}
