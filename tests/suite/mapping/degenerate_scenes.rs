//! Issue 6 (resilience): degenerate scenes complete with sensible output and no panic — zero
//! objects, an object seen in one frame, a tiny object, a class with one object, identical
//! objects, frames without depth, a camera that never moves, a stream that stops early.

use catmap::dataset::FrameSource;
use std::ops::ControlFlow;
use std::sync::Arc;

use catmap::InstanceLabel;
use catmap::dataset::stream::FrameStream;
use catmap::synth::{Preset, SyntheticScene};
use catmap::{MapperConfig, ObjectId, RgbdFrame};
use catmap_systems::{Mapper, RunOutcome};

use crate::common::with_warnings;

/// Short training everywhere, category mode on.
fn quick_config() -> MapperConfig {
    let mut config = MapperConfig {
        seed: 5,
        ..MapperConfig::default()
    };
    config.fields.steps_per_frame = 2;
    config.fields.final_steps = 20;
    config.categories.min_field_steps = 4;
    config.category_fields.enabled = true;
    config.category_fields.iterations = 20;
    // The default (fast) schedule, capped: a short phase after the stream.
    config.schedule.max_steps_after_stream = 40;
    config.meshes.object.voxel_size_m = 0.03;
    config.meshes.object.max_samples_per_side = 48;
    config.meshes.background_voxel_m = 0.15;
    config
}

fn small_frames(positions: impl IntoIterator<Item = usize>) -> Vec<RgbdFrame> {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    positions
        .into_iter()
        .map(|p| scene.read_frame(p).expect("frame renders"))
        .collect()
}

/// Runs every phase of a category-mode run on `frames`; returns the mapper for inspection.
fn map_frames(frames: Vec<RgbdFrame>) -> Mapper {
    let mut mapper = Mapper::new(quick_config()).expect("valid config");
    for frame in frames {
        mapper.push(frame).expect("valid frame");
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

fn objects_in(frame: &RgbdFrame) -> Vec<ObjectId> {
    let ids: std::collections::BTreeSet<ObjectId> = (0..frame.instances.len())
        .filter_map(|i| frame.instances.object_at(i))
        .collect();
    ids.into_iter().collect()
}

fn erase_objects(frame: &mut RgbdFrame, keep: impl Fn(ObjectId) -> bool) {
    for i in 0..frame.instances.len() {
        if frame.instances.object_at(i).is_some_and(|id| !keep(id)) {
            frame.instances.set(i, InstanceLabel::Background);
        }
    }
}

#[test]
fn a_scene_without_objects_maps_only_the_background() {
    let mut frames = small_frames(0..4);
    frames.iter_mut().for_each(|f| erase_objects(f, |_| false));
    // The run ends with its meshing phase, which warns about what got no mesh.
    let (mut mapper, warnings) = with_warnings(|| map_frames(frames));
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert!(
        meshes.objects.is_empty(),
        "no object meshes: {:?}",
        meshes.objects.keys()
    );
    assert!(warnings.contains("the map has no objects"), "warned: {warnings}");
    assert!(mapper.category_records().is_empty(), "no classes");
    let map = mapper.finish();
    assert_eq!(map.frames_ingested, 4, "every frame ingested");
    assert!(map.objects.is_empty());
}

#[test]
fn an_object_seen_in_one_frame_still_gets_a_mesh() {
    let mut frames = small_frames(0..4);
    let only = objects_in(&frames[0])[0];
    for (k, frame) in frames.iter_mut().enumerate() {
        erase_objects(frame, |id| k == 0 && id == only);
    }
    let mut mapper = map_frames(frames);
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert_eq!(
        meshes.objects.keys().copied().collect::<Vec<_>>(),
        [only],
        "one object, one mesh"
    );
    let map = mapper.finish();
    assert_eq!(map.object(only).expect("mapped").visible_frames, 1);
}

#[test]
fn an_object_with_a_handful_of_pixels_gets_no_mesh_and_the_rest_map() {
    let mut frames = small_frames(0..4);
    let tiny = objects_in(&frames[0])[0];
    for frame in &mut frames {
        let mut kept = 0;
        for i in 0..frame.instances.len() {
            if frame.instances.object_at(i) == Some(tiny) {
                if kept < 5 {
                    kept += 1;
                } else {
                    frame.instances.set(i, InstanceLabel::Background);
                }
            }
        }
    }
    // The run ends with its meshing phase, which warns about what got no mesh.
    let (mut mapper, warnings) = with_warnings(|| map_frames(frames));
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert!(!meshes.objects.contains_key(&tiny), "5 pixels cannot make a mesh");
    assert!(!meshes.objects.is_empty(), "the other objects still get meshes");
    let map = mapper.finish();
    assert!(
        map.object(tiny).is_none(),
        "too small to become an object (box below min_box_side_px)"
    );
    assert!(
        warnings.contains(&format!("object={tiny}")) && warnings.contains("never mapped"),
        "the ignored instance is named: {warnings}"
    );
}

#[test]
fn frames_without_depth_are_ingested_and_map_nothing() {
    let mut frames = small_frames(0..4);
    frames.iter_mut().for_each(|f| f.depth_m.fill(0.0));
    // The run ends with its meshing phase, which warns about what got no mesh.
    let (mut mapper, warnings) = with_warnings(|| map_frames(frames));
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert!(meshes.objects.is_empty(), "no depth, no object meshes");
    let records = mapper.category_records();
    assert!(
        records.iter().all(|r| r.subcategories.is_empty()),
        "nothing to register: {records:?}"
    );
    let map = mapper.finish();
    assert_eq!(map.frames_ingested, 4);
    assert!(
        map.objects.iter().all(|o| o.cloud_points == 0),
        "no points from zero depth"
    );
    for object in &map.objects {
        assert!(
            warnings.contains(&format!("object={}", object.id)),
            "{} has no mesh: {warnings}",
            object.id
        );
    }
}

#[test]
fn some_frames_without_depth_do_not_spoil_the_others() {
    let mut frames = small_frames(0..6);
    frames.iter_mut().step_by(2).for_each(|f| f.depth_m.fill(0.0));
    let mut mapper = map_frames(frames);
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert!(!meshes.objects.is_empty(), "frames with depth still give meshes");
}

#[test]
fn a_camera_that_never_moves_maps_what_it_sees() {
    let frames: Vec<RgbdFrame> = (0..5u64)
        .map(|k| {
            let mut frame = small_frames([0]).remove(0);
            frame.index = catmap::FrameIndex(k);
            frame
        })
        .collect();
    let seen = objects_in(&frames[0]);
    let mut mapper = map_frames(frames);
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert!(!meshes.objects.is_empty(), "objects seen from one pose get meshes");
    let map = mapper.finish();
    assert_eq!(map.objects.len(), seen.len(), "no duplicates from repeated views");
}

#[test]
fn a_class_with_one_object_keeps_its_instance_field() {
    let mut frames = small_frames(0..6);
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let chairs: Vec<ObjectId> = scene
        .objects()
        .iter()
        .filter(|o| o.class() == scene.objects()[0].class())
        .map(|o| o.id)
        .collect();
    let lone = chairs[0];
    frames
        .iter_mut()
        .for_each(|f| erase_objects(f, |id| !chairs.contains(&id) || id == lone));
    let mut mapper = map_frames(frames);
    assert_eq!(
        mapper.category_field_count(),
        0,
        "one member per class needs no category field"
    );
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert!(
        meshes.objects.contains_key(&lone),
        "the lone chair is meshed from its own field"
    );
    for record in mapper.category_records() {
        let members: Vec<ObjectId> = record
            .subcategories
            .iter()
            .flat_map(|s| s.members.iter().map(|m| m.id))
            .collect();
        assert_eq!(members.len(), 1, "class {} has one object: {members:?}", record.class);
        assert_eq!(
            record.subcategories[0].representative, members[0],
            "it represents itself"
        );
    }
}

#[test]
fn identical_objects_are_one_class_and_all_get_meshes() {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let design = scene.objects()[0].design;
    let same: Vec<ObjectId> = scene
        .objects()
        .iter()
        .filter(|o| o.design == design)
        .map(|o| o.id)
        .collect();
    assert!(same.len() >= 3, "the small scene has identical chairs: {same:?}");
    let mut frames = small_frames(0..10);
    frames
        .iter_mut()
        .for_each(|f| erase_objects(f, |id| same.contains(&id)));
    let mut mapper = map_frames(frames);
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    let records = mapper.category_records();
    assert_eq!(records.len(), 1, "one class: {records:?}");
    let mut members: Vec<ObjectId> = records[0]
        .subcategories
        .iter()
        .flat_map(|s| s.members.iter().map(|m| m.id))
        .collect();
    members.sort();
    let mapped: Vec<ObjectId> = mapper.finish().objects.iter().map(|o| o.id).collect();
    assert_eq!(members, mapped, "every mapped chair is a member");
    assert!(
        mapped.iter().all(|id| meshes.objects.contains_key(id)),
        "every chair meshed: {:?}",
        meshes.objects.keys()
    );
}

/// The small scene's frames; reading any position from `broken_from` on fails like a truncated file.
struct BrokenSource {
    scene: SyntheticScene,
    len: usize,
    broken_from: usize,
}

impl FrameSource for BrokenSource {
    fn len(&self) -> usize {
        self.len
    }
    fn intrinsics(&self) -> catmap::CameraIntrinsics {
        Preset::Small.intrinsics()
    }
    fn read_frame(&self, position: usize) -> catmap::Result<RgbdFrame> {
        if position >= self.broken_from {
            return Err(catmap::CatmapError::io(
                std::path::Path::new("results/depth000003.png"),
                std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "truncated"),
            ));
        }
        self.scene.read_frame(position)
    }
    fn name(&self) -> String {
        "broken".to_owned()
    }
}

#[test]
fn a_stream_that_stops_mid_frame_keeps_what_was_mapped() {
    let source = BrokenSource {
        scene: SyntheticScene::generate(4, Preset::Small).expect("small scene"),
        len: 6,
        broken_from: 3,
    };
    let stream = FrameStream::spawn(Arc::new(source), (0..6).collect(), 2);
    let mut mapper = Mapper::with_inbox(quick_config(), stream.receiver.clone()).expect("valid config");
    let (outcome, warnings) = with_warnings(|| mapper.run(|_| ControlFlow::Continue(())).expect("the run"));
    stream.join();
    assert_eq!(outcome, RunOutcome::Complete);
    assert!(warnings.contains("truncated"), "the error is reported: {warnings}");
    assert!(
        !mapper.extract_final_meshes().expect("final meshes").objects.is_empty(),
        "the first frames are meshed"
    );
    let map = mapper.finish();
    assert_eq!(
        (map.frames_ingested, map.frames_skipped),
        (3, 3),
        "3 mapped, 3 reported"
    );
}

/// Reads three frames, then the reader dies (as when a decoder panics).
struct DyingSource(SyntheticScene);

impl FrameSource for DyingSource {
    fn len(&self) -> usize {
        6
    }
    fn intrinsics(&self) -> catmap::CameraIntrinsics {
        Preset::Small.intrinsics()
    }
    fn read_frame(&self, position: usize) -> catmap::Result<RgbdFrame> {
        assert!(position < 3, "reader dies at position {position}");
        self.0.read_frame(position)
    }
    fn name(&self) -> String {
        "dying".to_owned()
    }
}

#[test]
fn a_reader_that_dies_ends_the_stream_instead_of_hanging() {
    let source = DyingSource(SyntheticScene::generate(4, Preset::Small).expect("small scene"));
    let stream = FrameStream::spawn(Arc::new(source), (0..6).collect(), 2);
    // The stream alone: no fields to train after it.
    let mut config = MapperConfig {
        fields: catmap::config::FieldConfig::disabled(),
        ..quick_config()
    };
    config.category_fields.enabled = false;
    let mut mapper = Mapper::with_inbox(config, stream.receiver.clone()).expect("valid config");
    let (outcome, warnings) = with_warnings(|| mapper.run(|_| ControlFlow::Continue(())).expect("the run"));
    stream.join();
    assert_eq!(outcome, RunOutcome::Complete);
    assert!(warnings.contains("stopped without its end"), "warned: {warnings}");
    assert_eq!(mapper.finish().frames_ingested, 3, "the frames read before are kept");
}
