//! An object made twice with per-frame ids is merged in the map: the small scene's largest
//! object (the table) is first seen by its left half only, then split into two masks (its right half made an
//! object of its own), then whole; the mapper ends with one object of the first id holding both
//! halves' sightings.

use catmap::dataset::FrameSource;
use catmap::objects::instance_association::{InstanceSource, ObjectMerge};
use catmap::synth::{Preset, SyntheticScene};
use catmap::{FrameIndex, InstanceLabel, MapperConfig, ObjectId, RgbdFrame};
use catmap_systems::{Mapper, SavedMapper};

const SEED: u64 = 11;

/// The id with the most pixels over every frame of `scene` (the table, in view throughout).
fn largest_object(scene: &SyntheticScene) -> ObjectId {
    let mut counts = std::collections::BTreeMap::<ObjectId, usize>::new();
    for t in 0..scene.len() {
        let frame = scene.read_frame(t).expect("synthetic frames render");
        for i in 0..frame.instances.len() {
            if let Some(id) = frame.instances.object_at(i) {
                *counts.entry(id).or_default() += 1;
            }
        }
    }
    counts
        .into_iter()
        .max_by_key(|&(id, n)| (n, std::cmp::Reverse(id)))
        .expect("objects in view")
        .0
}

/// How frame `t` shows the object: its left half alone (the right half unknown), split into two
/// masks, or whole.
fn shown(t: usize, mut frame: RgbdFrame, object: ObjectId) -> RgbdFrame {
    let w = frame.intrinsics.width as usize;
    let mut columns: Vec<usize> = (0..frame.instances.len())
        .filter(|&i| frame.instances.object_at(i) == Some(object))
        .map(|i| i % w)
        .collect();
    columns.sort_unstable();
    let Some(&middle) = columns.get(columns.len() / 2) else {
        return frame;
    };
    let right = match t {
        0..3 => InstanceLabel::Unknown,
        3..6 => InstanceLabel::Object(ObjectId(900)),
        _ => return frame,
    };
    for i in 0..frame.instances.len() {
        if frame.instances.object_at(i) == Some(object) && i % w >= middle {
            frame.instances.set(i, right);
        }
    }
    frame
}

/// Per-frame ids; a pair is judged once the younger was first seen 4 frames ago (the scene is
/// short); `fields` as given.
fn config(fields: catmap::config::FieldConfig) -> MapperConfig {
    let mut config = MapperConfig {
        seed: SEED,
        fields,
        ..MapperConfig::default()
    };
    config.category_fields.enabled = false;
    config.objects.association.instances = InstanceSource::PerFrame;
    config.objects.association.candidate_window_frames = 4;
    config
}

#[test]
fn an_object_first_seen_by_halves_is_merged_into_one_with_its_first_id() {
    let scene = SyntheticScene::generate(SEED, Preset::Small).expect("the small scene generates");
    let mut mapper = Mapper::new(config(catmap::config::FieldConfig::disabled())).expect("valid config");
    let object = largest_object(&scene);
    let mut seen_in = 0;
    for t in 0..scene.len() {
        let frame = scene.read_frame(t).expect("synthetic frames render");
        seen_in += u64::from((0..frame.instances.len()).any(|i| frame.instances.object_at(i) == Some(object)));
        mapper.push(shown(t, frame, object)).expect("the frame is valid");
        mapper.step().expect("a tick");
    }
    mapper.end_stream().expect("a tick");
    mapper.step().expect("a tick");
    let map = mapper.finish();
    assert_eq!(map.merges.len(), 1, "{:?}", map.merges);
    let ObjectMerge { frame, kept, absorbed } = map.merges[0];
    assert!(kept < absorbed, "the first id is kept: {kept} absorbed {absorbed}");
    assert_eq!(
        frame,
        FrameIndex(7),
        "the second whole frame, 4 after the right half was first seen"
    );
    assert!(map.object(absorbed).is_none(), "object {absorbed} is gone");
    // Seen as an object in every frame but two as a candidate and the two held between the
    // halves before the merge.
    let merged = map.object(kept).expect("the kept object");
    assert!(
        merged.visible_frames + 4 >= seen_in,
        "{} of {seen_in}",
        merged.visible_frames
    );
    assert!(
        map.categories.iter().all(|c| !c.members.contains(&absorbed)),
        "{:?}",
        map.categories
    );
}

#[test]
fn a_map_whose_merged_object_had_a_field_is_checkpointed_and_restored() {
    let scene = SyntheticScene::generate(SEED, Preset::Small).expect("the small scene generates");
    let fields = catmap::config::FieldConfig {
        steps_per_frame: 2,
        ..catmap::config::FieldConfig::default()
    };
    let mut mapper = Mapper::new(config(fields)).expect("valid config");
    let object = largest_object(&scene);
    for t in 0..10 {
        let frame = scene.read_frame(t).expect("synthetic frames render");
        mapper.push(shown(t, frame, object)).expect("the frame is valid");
        mapper.step().expect("a tick");
    }
    let before = mapper.snapshot();
    assert_eq!(before.merges.len(), 1, "{:?}", before.merges);
    let dir = tempfile::tempdir().expect("temp dir");
    mapper
        .save_checkpoint(dir.path(), "merged", String::new())
        .expect("a field without an owner is saved");
    let saved = SavedMapper::load(dir.path()).expect("checkpoint reads");
    let mut restored = Mapper::from_checkpoint(saved, crossbeam_channel::never()).expect("checkpoint restores");
    let after = restored.snapshot();
    assert_eq!(after.merges, before.merges);
    let ids = |map: &catmap_systems::MapSnapshot| map.objects.iter().map(|o| o.id).collect::<Vec<_>>();
    assert_eq!(ids(&after), ids(&before));
    assert!(after.object(before.merges[0].absorbed).is_none());
}
