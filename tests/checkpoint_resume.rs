//! Checkpoints: a mapper saved, dropped and restored four times — after the first frame, mid-stream,
//! during the training after the stream, during the category phase — ends with the same final
//! meshes, categories and map as a run that was never interrupted (bit for bit).

use std::ops::ControlFlow;
use std::sync::Arc;

use catmap::config::FieldConfig;
use catmap::dataset::FrameSource;
use catmap::dataset::stream::StreamMessage;
use catmap::meshing::MapMeshes;
use catmap::synth::{Preset, SyntheticScene};
use catmap::{MapperConfig, RgbdFrame};
use catmap_systems::Mapper;
use crossbeam_channel::{Sender, bounded};

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
            final_steps: 100,
            ..FieldConfig::default()
        },
        ..MapperConfig::default()
    };
    config.categories.min_field_steps = 20;
    config.category_fields.enabled = true;
    config.category_fields.iterations = 100;
    config.meshes.object.voxel_size_m = 0.04;
    config.meshes.background_voxel_m = 0.1;
    config
}

/// A mapper fed through a channel the test holds (like a reader thread's).
fn fed(mapper: &mut Mapper) -> Sender<StreamMessage> {
    let (sender, receiver) = bounded(4);
    mapper.attach_inbox(receiver);
    sender
}

fn push(mapper: &mut Mapper, sender: &Sender<StreamMessage>, frame: RgbdFrame) {
    sender.send(StreamMessage::Frame(Arc::new(frame))).expect("inbox open");
    mapper.step();
}

/// Saves `mapper` to a fresh folder and returns the mapper restored from it.
fn save_and_restore(mut mapper: Mapper) -> Mapper {
    let dir = tempfile::tempdir().expect("temp dir");
    mapper
        .save_checkpoint(dir.path(), "test", "{\"caller\": 1}".to_owned())
        .expect("checkpoint written");
    drop(mapper);
    let (restored, extra) = Mapper::resume(dir.path(), None).expect("checkpoint restores");
    assert_eq!(extra, "{\"caller\": 1}");
    restored
}

/// Maps every other frame of `scene`, stopping (save, drop, restore) at each of `stops`.
fn run(scene: &SyntheticScene, stops: &[Stop]) -> (MapMeshes, String, String) {
    let mut mapper = Mapper::with_inbox(config(), crossbeam_channel::never()).expect("valid config");
    let mut sender = fed(&mut mapper);
    for (mapped, position) in (0..scene.len()).step_by(2).enumerate() {
        push(&mut mapper, &sender, scene.read_frame(position).expect("frame renders"));
        if stops.contains(&Stop::Frame(mapped + 1)) {
            mapper = save_and_restore(mapper);
            assert_eq!(mapper.positions_consumed(), mapped + 1, "stream position restored");
            sender = fed(&mut mapper);
        }
    }
    sender.send(StreamMessage::End(Default::default())).expect("inbox open");
    mapper.step();
    assert!(mapper.stream_ended());
    let stop_once = |flag: bool| {
        move |_, _| {
            if flag {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        }
    };
    if !mapper.train_after_stream_until(stop_once(stops.contains(&Stop::AfterStream))) {
        mapper = save_and_restore(mapper);
        assert!(mapper.train_after_stream_until(stop_once(false)));
    }
    if !mapper.train_categories_until(stop_once(stops.contains(&Stop::Categories))) {
        mapper = save_and_restore(mapper);
        assert!(mapper.train_categories_until(stop_once(false)));
    }
    assert_eq!(mapper.category_field_count(), 1, "the three chairs share a field");
    let categories = serde_json::to_string(&mapper.category_records()).expect("serialises");
    let meshes = mapper.extract_final_meshes();
    let map = serde_json::to_string(&mapper.snapshot()).expect("serialises");
    (meshes, categories, map)
}

#[test]
fn a_restored_mapper_continues_to_the_same_map_as_an_uninterrupted_one() {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let (meshes, categories, map) = run(&scene, &[]);
    assert!(
        meshes.objects.len() >= 5,
        "meshes for the objects: {}",
        meshes.objects.len()
    );
    let stops = [Stop::Frame(1), Stop::Frame(8), Stop::AfterStream, Stop::Categories];
    let (resumed, resumed_categories, resumed_map) = run(&scene, &stops);
    assert_eq!(resumed_map, map, "map snapshot");
    assert_eq!(resumed_categories, categories, "categories");
    assert_eq!(
        resumed.objects.keys().collect::<Vec<_>>(),
        meshes.objects.keys().collect::<Vec<_>>()
    );
    for (id, mesh) in &meshes.objects {
        assert!(resumed.objects[id] == *mesh, "object {id}'s mesh differs");
    }
    assert!(resumed.background == meshes.background, "background mesh differs");
}

#[test]
fn a_damaged_checkpoint_is_refused_with_the_file_named() {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let mut mapper = Mapper::with_inbox(config(), crossbeam_channel::never()).expect("valid config");
    let sender = fed(&mut mapper);
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
    let err = Mapper::resume(dir.path(), None).err().expect("refused").to_string();
    assert!(err.contains(&manifest.state.name) && err.contains("CRC-32"), "{err}");
}
