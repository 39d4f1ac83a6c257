//! A training step that breaks an invariant fails the run once, naming its step and object: the
//! mapper returns one error instead of warning at every later step, runs no more ticks, and
//! refuses to overwrite the checkpoint written before the failure.

use catmap::dataset::FrameSource;
use catmap::synth::{Preset, SyntheticScene};
use catmap::{MapperConfig, ObjectId};
use catmap_systems::components::{FieldSlot, Object};
use catmap_systems::failed_step::TrainingStep;
use catmap_systems::{Mapper, MapperError};

use crate::common::with_warnings;

#[test]
fn a_step_on_a_field_outside_its_batch_fails_the_run_once_naming_the_object() {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let mut mapper = Mapper::new(MapperConfig::default()).expect("valid config");
    let mut frames = 0..scene.len();
    // Stream until a field trains, and a few steps more.
    for position in frames.by_ref() {
        mapper
            .push(scene.read_frame(position).expect("frame renders"))
            .expect("valid frame");
        mapper.step().expect("a tick");
        if mapper.training_steps() >= 5 {
            break;
        }
    }
    let checkpoint = tempfile::tempdir().expect("temp dir");
    mapper
        .save_checkpoint(checkpoint.path(), "before the failure", "{}".into())
        .expect("a checkpoint before the failure");
    // Break the invariant "every field's slot lies in its batch" for the object of lowest id.
    let world = mapper.world_mut();
    let mut slots = world.query::<(&Object, &mut FieldSlot)>();
    let (object, mut slot) = slots
        .iter_mut(world)
        .min_by_key(|(o, _)| o.id)
        .expect("an object field");
    let broken: ObjectId = object.id;
    slot.index = 999;
    let steps_before = mapper.training_steps();

    let next = frames.next().expect("frames left");
    mapper
        .push(scene.read_frame(next).expect("frame renders"))
        .expect("valid frame");
    let (failed, warnings) = with_warnings(|| mapper.step());
    let Err(MapperError::StepFailed(failure)) = failed else {
        panic!("the tick fails: {failed:?}");
    };
    assert_eq!(failure.step, TrainingStep::ObjectFields);
    assert_eq!(failure.objects(), vec![broken], "the one object at fault: {failure}");
    assert_eq!(failure.steps_before, steps_before);
    let message = failure.to_string();
    assert!(
        message.contains(&format!("object {broken}")) && message.contains("slot"),
        "the error names the object and the broken invariant: {message}"
    );
    assert!(warnings.is_empty(), "one error, no warnings: {warnings}");
    assert_eq!(mapper.training_steps(), steps_before, "no step ran after the failure");

    // The run is over: no more ticks, and the checkpoint before the failure stays as it was.
    let manifest = catmap::checkpoint::read_manifest(checkpoint.path()).expect("the manifest");
    assert!(matches!(mapper.step(), Err(MapperError::Stopped)));
    assert!(matches!(
        mapper.save_checkpoint(checkpoint.path(), "after the failure", "{}".into()),
        Err(MapperError::Stopped)
    ));
    let kept = catmap::checkpoint::read_manifest(checkpoint.path()).expect("the manifest");
    assert_eq!(
        kept.generation, manifest.generation,
        "the checkpoint is not overwritten"
    );
}
