//! Checkpoints: a mapper saved, dropped and restored four times — after the first frame, mid-stream,
//! during the training after the stream, during the category phase — ends with the same final
//! meshes, categories and map as a run that was never interrupted (bit for bit), the solid and
//! support priors on, the category members' too; and a run with per-frame instance ids, whose association memory is part of
//! the checkpoint, restored mid-stream, with the masks' borders decided by the last frames' labels
//! (border votes; the labels are in the checkpoint too).

use std::ops::ControlFlow;
use std::sync::Arc;

use catmap::config::FieldConfig;
use catmap::dataset::FrameSource;
use catmap::dataset::stream::StreamMessage;
use catmap::meshing::MapMeshes;
use catmap::objects::instance_association::InstanceSource;
use catmap::synth::{InstanceIds, Preset, SensorModel, SensorSettings, SyntheticScene};
use catmap::training::SchedulePolicy;
use catmap::{MapperConfig, RgbdFrame};
use catmap_systems::{Mapper, RunOutcome, RunPhase, SavedMapper};
use crossbeam_channel::{Receiver, Sender, bounded};

/// Where a run is interrupted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stop {
    /// After this many frames were mapped.
    Frame(usize),
    /// After the first chunk of the training after the stream.
    AfterStream,
    /// After the first chunk of the category phase.
    Categories,
}

fn config() -> MapperConfig {
    let mut config = MapperConfig {
        seed: 11,
        fields: FieldConfig {
            steps_per_frame: 3,
            final_steps: 60,
            ..FieldConfig::default()
        },
        ..MapperConfig::default()
    };
    // The paper's schedule has a category phase of its own (the fast one trains the category
    // fields in the phase before), so that the run can stop in each phase; 60 steps per phase
    // leave a step after its first chunk (`CHUNK_STEPS`, 50).
    config.schedule.policy = SchedulePolicy::Paper;
    config.categories.min_field_steps = 20;
    config.category_fields.enabled = true;
    config.category_fields.iterations = 60;
    config.meshes.object.voxel_size_m = 0.04;
    config.meshes.background_voxel_m = 0.1;
    // The priors of objects without a twin, whose hidden cells are not checkpointed but
    // recomputed from the restored keyframes and boxes.
    config.fields.object_rays.hidden_solid_rays = 4;
    config.fields.object_rays.below_support_rays = 2;
    config.fields.object_rays.seen_free_rays = 2;
    // The members' solid prior (off under `paper` unless set), for every member with a cell no
    // member saw into: its cells are not checkpointed either.
    config.category_fields.hidden_solid_rays = 4;
    config.category_fields.min_hidden_share = 0.0;
    config
}

fn push(mapper: &mut Mapper, sender: &Sender<StreamMessage>, frame: RgbdFrame) {
    sender.send(StreamMessage::Frame(Arc::new(frame))).expect("inbox open");
    mapper.step().expect("a tick");
}

/// Saves `mapper` to a fresh folder and returns the mapper restored from it, fed by `inbox`.
fn save_and_restore(mut mapper: Mapper, inbox: Receiver<StreamMessage>) -> Mapper {
    let dir = tempfile::tempdir().expect("temp dir");
    mapper
        .save_checkpoint(dir.path(), "test", "{\"caller\": 1}".to_owned())
        .expect("checkpoint written");
    drop(mapper);
    let saved = SavedMapper::load(dir.path()).expect("checkpoint reads");
    assert_eq!(saved.extra(), "{\"caller\": 1}");
    Mapper::from_checkpoint(saved, inbox).expect("checkpoint restores")
}

/// The stop in `phase` after its first chunk, if any.
fn stop_in(phase: RunPhase) -> Option<Stop> {
    match phase {
        RunPhase::AfterStream => Some(Stop::AfterStream),
        RunPhase::Categories => Some(Stop::Categories),
        _ => None,
    }
}

/// Maps every other frame of `scene` through a channel the test holds (like a reader thread's),
/// stopping (save, drop, restore) at each of `stops`.
fn run(scene: &SyntheticScene, config: &MapperConfig, stops: &[Stop]) -> (MapMeshes, String, String) {
    let (mut sender, receiver) = bounded(4);
    let mut mapper = Mapper::with_inbox(config.clone(), receiver).expect("valid config");
    for (mapped, position) in (0..scene.len()).step_by(2).enumerate() {
        push(&mut mapper, &sender, scene.read_frame(position).expect("frame renders"));
        if stops.contains(&Stop::Frame(mapped + 1)) {
            let (new_sender, receiver) = bounded(4);
            mapper = save_and_restore(mapper, receiver);
            sender = new_sender;
            assert_eq!(mapper.positions_consumed(), mapped + 1, "stream position restored");
        }
    }
    sender.send(StreamMessage::End(Default::default())).expect("inbox open");
    mapper.step().expect("a tick");
    assert!(mapper.stream_ended());
    let mut stopped: Vec<Stop> = Vec::new();
    while let RunOutcome::Paused(at) = mapper
        .run(|progress| match stop_in(progress.phase) {
            Some(stop) if stops.contains(&stop) && !stopped.contains(&stop) => ControlFlow::Break(()),
            _ => ControlFlow::Continue(()),
        })
        .expect("the run")
    {
        stopped.extend(stop_in(at.phase));
        mapper = save_and_restore(mapper, crossbeam_channel::never());
    }
    let wanted: Vec<Stop> = stops.iter().copied().filter(|s| !matches!(s, Stop::Frame(_))).collect();
    assert_eq!(stopped, wanted, "the run paused where asked, once each");
    assert_eq!(mapper.category_field_count(), 1, "the three chairs share a field");
    let categories = serde_json::to_string(&mapper.category_records()).expect("serialises");
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    let map = serde_json::to_string(&mapper.snapshot()).expect("serialises");
    (meshes, categories, map)
}

/// The resumed run's map snapshot, categories and object meshes equal the uninterrupted one's.
fn assert_same_run(resumed: (&MapMeshes, &String, &String), reference: (&MapMeshes, &String, &String)) {
    let ((resumed, resumed_categories, resumed_map), (meshes, categories, map)) = (resumed, reference);
    assert_eq!(resumed_map, map, "map snapshot");
    assert_eq!(resumed_categories, categories, "categories");
    assert_eq!(
        resumed.objects.keys().collect::<Vec<_>>(),
        meshes.objects.keys().collect::<Vec<_>>()
    );
    for (id, mesh) in &meshes.objects {
        assert!(resumed.objects[id] == *mesh, "object {id}'s mesh differs");
    }
}

#[test]
fn a_restored_mapper_continues_to_the_same_map_as_an_uninterrupted_one() {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let (meshes, categories, map) = run(&scene, &config(), &[]);
    assert!(
        meshes.objects.len() >= 5,
        "meshes for the objects: {}",
        meshes.objects.len()
    );
    let stops = [Stop::Frame(1), Stop::Frame(8), Stop::AfterStream, Stop::Categories];
    let (resumed, resumed_categories, resumed_map) = run(&scene, &config(), &stops);
    assert_same_run(
        (&resumed, &resumed_categories, &resumed_map),
        (&meshes, &categories, &map),
    );
    assert!(resumed.background == meshes.background, "background mesh differs");
}

#[test]
fn a_damaged_checkpoint_is_refused_with_the_file_named() {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let (sender, receiver) = bounded(4);
    let mut mapper = Mapper::with_inbox(config(), receiver).expect("valid config");
    for position in 0..6 {
        push(&mut mapper, &sender, scene.read_frame(position).expect("frame renders"));
    }
    let dir = tempfile::tempdir().expect("temp dir");
    mapper
        .save_checkpoint(dir.path(), "six frames", String::new())
        .expect("written");
    let manifest = catmap::checkpoint::read_manifest(dir.path()).expect("manifest");
    let state = dir.path().join(&manifest.state.name);
    let mut bytes = std::fs::read(&state).expect("reads");
    let middle = bytes.len() / 2;
    bytes[middle] ^= 0x40;
    std::fs::write(&state, bytes).expect("damages");
    let err = SavedMapper::load(dir.path()).err().expect("refused").to_string();
    assert!(err.contains(&manifest.state.name) && err.contains("CRC-32"), "{err}");
}

#[test]
fn a_run_with_per_frame_ids_and_border_votes_restored_mid_stream_continues_to_the_same_map() {
    let scene = SyntheticScene::generate(4, Preset::Small)
        .expect("small scene")
        .with_sensor(SensorSettings::new(SensorModel::None, InstanceIds::PerFrame));
    let mut config = config();
    config.objects.association.instances = InstanceSource::PerFrame;
    // A 1 px band whose pixels the last 4 frames decide (the 2 px band of `--masks segmenter`
    // leaves the small scene's chairs too thin to share a field).
    config.objects.mask_border_px = 1;
    config.objects.border_votes.frames = 4;
    let (meshes, categories, map) = run(&scene, &config, &[]);
    assert!(
        meshes.objects.len() >= 5,
        "the masks make objects: {}",
        meshes.objects.len()
    );
    // Frame 2 holds only candidates (seen in 3 frames they become objects), frame 9 objects.
    let (resumed, resumed_categories, resumed_map) = run(&scene, &config, &[Stop::Frame(2), Stop::Frame(9)]);
    assert_same_run(
        (&resumed, &resumed_categories, &resumed_map),
        (&meshes, &categories, &map),
    );
}
