use nalgebra::{Isometry3, Point3};

use super::*;
use crate::objects::config::ObjectConfig;
use crate::objects::frame_observation::observe_objects;
use crate::objects::mask_footprint::voxel_keys;
use crate::objects::segment::{associate_frame, relabel_instances};
use crate::sensor::frame::CameraIntrinsics;
use crate::sensor::frame::{InstanceLabel, InstanceMask, RgbdFrame};

pub(super) const CHAIR: ClassId = ClassId(20);
const TABLE: ClassId = ClassId(80);

/// Points 2 cm apart on the faces of the box `[lo, hi]` that face −y (what a camera at −y sees),
/// shifted by `jitter_m` along x (a frame's view differs a little).
pub(super) fn seen_face(lo: [f32; 3], hi: [f32; 3], jitter_m: f32) -> Vec<Point3<f32>> {
    let mut points = Vec::new();
    let steps = |a: f32, b: f32| ((b - a) / 0.02).round() as usize;
    for i in 0..=steps(lo[0], hi[0]) {
        for k in 0..=steps(lo[2], hi[2]) {
            points.push(Point3::new(
                lo[0] + 0.02 * i as f32 + jitter_m,
                lo[1],
                lo[2] + 0.02 * k as f32,
            ));
        }
    }
    points
}

pub(super) fn mask(local: u32, class: ClassId, points: Vec<Point3<f32>>) -> MaskEvidence {
    MaskEvidence {
        local: ObjectId(local),
        class,
        points,
    }
}

pub(super) fn chair_at(x: f32) -> ([f32; 3], [f32; 3]) {
    ([x - 0.25, 0.0, 0.0], [x + 0.25, 0.5, 0.9])
}

/// Chairs at x = 0 and x = 1.5 and a table at x = 3, masks numbered by `ids` in frame `t`.
fn three_objects(t: u64, ids: [u32; 3]) -> Vec<MaskEvidence> {
    let jitter = 0.01 * (t % 3) as f32;
    let (a, b) = (chair_at(0.0), chair_at(1.5));
    vec![
        mask(ids[0], CHAIR, seen_face(a.0, a.1, jitter)),
        mask(ids[1], CHAIR, seen_face(b.0, b.1, jitter)),
        mask(ids[2], TABLE, seen_face([2.4, 0.0, 0.0], [3.6, 0.8, 0.75], jitter)),
    ]
}

pub(super) fn object_of(fates: &BTreeMap<ObjectId, MaskFate>, local: u32) -> Option<ObjectId> {
    match fates.get(&ObjectId(local)) {
        Some(MaskFate::Object(id)) => Some(*id),
        _ => None,
    }
}

#[test]
fn shuffled_ids_give_every_object_one_stable_id_after_min_frames() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let orders = [[7, 3, 9], [1, 2, 3], [42, 5, 17], [3, 9, 7], [8, 6, 4], [2, 1, 99]];
    let mut ids: Vec<[Option<ObjectId>; 3]> = Vec::new();
    for (t, order) in orders.iter().enumerate() {
        let fates = tracker.associate(FrameIndex(t as u64), &three_objects(t as u64, *order), &cfg);
        ids.push(order.map(|local| object_of(&fates, local)));
    }
    assert_eq!(ids[0], [None; 3], "a first sighting is only a candidate");
    assert_eq!(ids[1], [None; 3]);
    let stable = ids[2].map(|id| id.expect("the third sighting makes the objects"));
    assert_eq!(stable.iter().collect::<BTreeSet<_>>().len(), 3, "{stable:?}");
    for later in &ids[3..] {
        assert_eq!(
            later.map(Option::unwrap),
            stable,
            "the same objects, whatever their masks' ids"
        );
    }
    assert_eq!((tracker.object_count(), tracker.candidate_count()), (3, 0));
}

#[test]
fn a_dropped_mask_does_not_lose_or_duplicate_its_object() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let mut chair_b = Vec::new();
    for t in 0..9u64 {
        let mut masks = three_objects(t, [1, 2, 3]);
        if (4..7).contains(&t) {
            masks.remove(1); // the segmenter misses chair B in frames 4-6
        }
        let fates = tracker.associate(FrameIndex(t), &masks, &cfg);
        if t >= 2 && !(4..7).contains(&t) {
            chair_b.push(object_of(&fates, 2).expect("chair B"));
        }
    }
    assert!(chair_b.windows(2).all(|w| w[0] == w[1]), "{chair_b:?}");
    assert_eq!(tracker.object_count(), 3);
}

#[test]
fn a_spurious_one_frame_mask_never_becomes_an_object_and_is_forgotten() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    for t in 0..40u64 {
        let mut masks = three_objects(t, [1, 2, 3]);
        if t == 5 {
            masks.push(mask(4, CHAIR, seen_face([5.0, 2.0, 0.0], [5.4, 2.3, 0.8], 0.0)));
        }
        let fates = tracker.associate(FrameIndex(t), &masks, &cfg);
        if t == 5 {
            assert_eq!(fates[&ObjectId(4)], MaskFate::Held(HoldReason::Candidate));
            assert_eq!(tracker.candidate_count(), 1);
        }
    }
    assert_eq!(tracker.object_count(), 3);
    assert_eq!(tracker.candidate_count(), 0, "forgotten after the window");
}

#[test]
fn two_touching_chairs_stay_two_objects_and_a_mask_spanning_both_is_held() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let (a, b) = (chair_at(0.0), chair_at(0.5)); // A's right side touches B's left side
    let mut seen = Vec::new();
    for t in 0..6u64 {
        let j = 0.01 * (t % 2) as f32;
        let masks = [
            mask(10 + t as u32, CHAIR, seen_face(a.0, a.1, j)),
            mask(20, CHAIR, seen_face(b.0, b.1, j)),
        ];
        let fates = tracker.associate(FrameIndex(t), &masks, &cfg);
        seen.push((object_of(&fates, 10 + t as u32), object_of(&fates, 20)));
    }
    let (first_a, first_b) = (seen[2].0.expect("A"), seen[2].1.expect("B"));
    assert_ne!(first_a, first_b);
    assert!(
        seen[3..].iter().all(|&(x, y)| (x, y) == (Some(first_a), Some(first_b))),
        "{seen:?}"
    );
    let merged = mask(5, CHAIR, [seen_face(a.0, a.1, 0.0), seen_face(b.0, b.1, 0.0)].concat());
    let fates = tracker.associate(FrameIndex(6), &[merged], &cfg);
    assert_eq!(fates[&ObjectId(5)], MaskFate::Held(HoldReason::Ambiguous));
    assert_eq!(tracker.object_count(), 2);
}

/// Masks of frame `t` for chairs `a` and `b` side by side: each alone, or one mask over both.
pub(super) fn side_by_side(
    t: u64,
    a: ([f32; 3], [f32; 3]),
    b: ([f32; 3], [f32; 3]),
    merged: bool,
) -> Vec<MaskEvidence> {
    let j = 0.01 * (t % 2) as f32;
    let (fa, fb) = (seen_face(a.0, a.1, j), seen_face(b.0, b.1, j));
    match merged {
        true => vec![mask(30, CHAIR, [fa, fb].concat())],
        false => vec![mask(10, CHAIR, fa), mask(20, CHAIR, fb)],
    }
}

#[test]
fn a_neighbour_merged_into_an_objects_masks_still_becomes_an_object_of_its_own() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let (a, b) = (chair_at(0.0), chair_at(0.55));
    for t in 0..3 {
        tracker.associate(FrameIndex(t), &side_by_side(t, a, b, false)[..1], &cfg);
    }
    let a_id = ObjectId(1);
    assert_eq!(tracker.object_count(), 1);
    // B is seen once alone, then twice in one mask with A (a segmenter's merges), then apart.
    let fates = tracker.associate(FrameIndex(3), &side_by_side(3, a, b, false), &cfg);
    assert_eq!(fates[&ObjectId(20)], MaskFate::Held(HoldReason::Candidate));
    for t in 4..6 {
        let merged = side_by_side(t, a, b, true);
        let frame = tracker.associate_frame(FrameIndex(t), &merged, &cfg);
        assert_eq!(object_of(&frame.fates, 30), Some(a_id), "mostly A: A takes it");
        // The voxels of B's face the merged mask covered are B's, whose pixels become unsure.
        let apart = side_by_side(t, a, b, false);
        let (a_keys, b_keys) = (voxel_keys(&apart[0].points, 0.05), voxel_keys(&apart[1].points, 0.05));
        let theirs = &frame.foreign[&a_id];
        assert!(theirs.iter().all(|k| b_keys.contains(k) && !a_keys.contains(k)), "{t}");
        assert!(
            theirs.len() * 2 > b_keys.len(),
            "most of B's face: {} of {}",
            theirs.len(),
            b_keys.len()
        );
    }
    let mut seen = Vec::new();
    for t in 6..10 {
        let fates = tracker.associate(FrameIndex(t), &side_by_side(t, a, b, false), &cfg);
        seen.push((object_of(&fates, 10), object_of(&fates, 20)));
    }
    let b_id = ObjectId(2);
    assert_eq!(
        seen[0],
        (Some(a_id), None),
        "B's mask is not A's: A did not grow into B"
    );
    assert_eq!(seen[1..], [(Some(a_id), Some(b_id)); 3], "B made after its third frame");
}

#[test]
fn a_candidate_that_two_masks_of_one_frame_show_is_split_into_two() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let (a, b) = (chair_at(0.0), chair_at(0.5));
    // First seen as one mask over both chairs, then always apart.
    tracker.associate(FrameIndex(0), &side_by_side(0, a, b, true), &cfg);
    let mut seen = Vec::new();
    for t in 1..5 {
        let fates = tracker.associate(FrameIndex(t), &side_by_side(t, a, b, false), &cfg);
        seen.push((object_of(&fates, 10), object_of(&fates, 20)));
    }
    assert_eq!(seen[..2], [(None, None); 2], "two new candidates, seen once and twice");
    let (first_a, first_b) = seen[2];
    assert!(first_a.is_some() && first_b.is_some() && first_a != first_b, "{seen:?}");
    assert_eq!(seen[3], seen[2]);
    assert_eq!(tracker.object_count(), 2);
}

#[test]
fn a_split_object_keeps_one_id_and_another_class_is_not_taken() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    for t in 0..3u64 {
        tracker.associate(FrameIndex(t), &three_objects(t, [1, 2, 3]), &cfg);
    }
    let (a, _) = (chair_at(0.0), ());
    let left = seen_face(a.0, [0.0, 0.5, 0.9], 0.0);
    let right = seen_face([0.02, 0.0, 0.0], a.1, 0.0);
    let confused = mask(9, TABLE, seen_face(chair_at(1.5).0, chair_at(1.5).1, 0.0));
    let fates = tracker.associate(
        FrameIndex(3),
        &[mask(4, CHAIR, left), mask(5, CHAIR, right), confused],
        &cfg,
    );
    let chair = object_of(&fates, 4).expect("the left half is chair A");
    assert_eq!(object_of(&fates, 5), Some(chair), "the right half too");
    assert_eq!(
        fates[&ObjectId(9)],
        MaskFate::Held(HoldReason::ConfusedClass),
        "a table mask never joins a chair: it is chair B under a confused class"
    );
    assert_eq!(tracker.candidate_count(), 0, "and starts no candidate");
}

#[test]
fn a_chair_confused_for_a_table_in_several_frames_makes_no_table_on_it() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    for t in 0..3u64 {
        tracker.associate(FrameIndex(t), &three_objects(t, [1, 2, 3]), &cfg);
    }
    let (b_lo, b_hi) = chair_at(1.5);
    for t in 3..8u64 {
        let mut masks = three_objects(t, [4, 5, 6]);
        masks[1] = mask(5, TABLE, seen_face(b_lo, b_hi, 0.01 * (t % 3) as f32));
        let fates = tracker.associate(FrameIndex(t), &masks, &cfg);
        assert_eq!(
            fates[&ObjectId(5)],
            MaskFate::Held(HoldReason::ConfusedClass),
            "frame {t}"
        );
    }
    assert_eq!(tracker.object_count(), 3, "the three objects, no table on chair B");
    // Off (a share above 1), the confused masks make a table on chair B after three frames.
    let off = AssociationConfig {
        confused_class_overlap: 1.1,
        ..cfg.clone()
    };
    let mut tracker = InstanceTracker::default();
    for t in 0..3u64 {
        tracker.associate(FrameIndex(t), &three_objects(t, [1, 2, 3]), &off);
    }
    for t in 3..6u64 {
        let mut masks = three_objects(t, [4, 5, 6]);
        masks[1] = mask(5, TABLE, seen_face(b_lo, b_hi, 0.0));
        tracker.associate(FrameIndex(t), &masks, &off);
    }
    assert_eq!(tracker.object_count(), 4);
    // A table's mask beside the chairs, far from every object, is a new object's as before.
    let mut tracker = InstanceTracker::default();
    for t in 0..3u64 {
        tracker.associate(
            FrameIndex(t),
            &[mask(1, TABLE, seen_face([6.0, 0.0, 0.0], [7.0, 0.8, 0.75], 0.0))],
            &cfg,
        );
    }
    assert_eq!(tracker.object_count(), 1);
}

#[test]
fn a_mask_without_depth_is_held_and_relabelling_names_objects_and_unknowns() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let fates = tracker.associate(FrameIndex(0), &[mask(3, CHAIR, vec![Point3::origin(); 5])], &cfg);
    assert_eq!(fates[&ObjectId(3)], MaskFate::Held(HoldReason::TooFewPoints));

    let labels = [0u32, 3, 4, 5].map(|id| match id {
        0 => InstanceLabel::Background,
        id => InstanceLabel::Object(ObjectId(id)),
    });
    let frame = RgbdFrame {
        index: FrameIndex(0),
        world_from_camera: Isometry3::identity(),
        intrinsics: CameraIntrinsics {
            width: 4,
            height: 1,
            fx: 1.0,
            fy: 1.0,
            cx: 1.5,
            cy: 0.0,
        },
        rgb: vec![[0; 3]; 4],
        depth_m: vec![1.0; 4],
        instances: InstanceMask::from_labels(labels),
        classes: vec![CHAIR; 4],
    };
    let fates = BTreeMap::from([
        (ObjectId(3), MaskFate::Object(ObjectId(1))),
        (ObjectId(4), MaskFate::Held(HoldReason::Candidate)),
    ]);
    let relabelled = relabel_instances(&frame, &fates);
    let got: Vec<InstanceLabel> = (0..4).map(|i| relabelled.instances.label(i)).collect();
    assert_eq!(
        got,
        [
            InstanceLabel::Background,
            InstanceLabel::Object(ObjectId(1)),
            InstanceLabel::Unsure,
            InstanceLabel::Unsure
        ]
    );
}

/// Associates every frame of the small scene of `seed` seen through `sensor` (per-frame ids) and
/// tallies the result against the exact render.
fn associate_small_scene(
    seed: u64,
    sensor: crate::synth::SensorSettings,
) -> Vec<crate::metrics::association_purity::AssociatedObject> {
    use crate::dataset::FrameSource;
    use crate::synth::{Preset, SyntheticScene};
    let exact = SyntheticScene::generate(seed, Preset::Small).expect("scene");
    let noisy = SyntheticScene::generate(seed, Preset::Small)
        .expect("scene")
        .with_sensor(sensor);
    let cfg = ObjectConfig::default();
    let mut tracker = InstanceTracker::default();
    let mut tally = crate::metrics::association_purity::AssociationTally::default();
    for i in 0..noisy.len() {
        let frame = noisy.read_frame(i).expect("frame");
        let (relabelled, _) = associate_frame(&mut tracker, &frame, &observe_objects(&frame, &cfg), &cfg);
        tally.add(&relabelled.instances, &exact.read_frame(i).expect("frame").instances);
    }
    tally.objects()
}

#[test]
fn per_frame_ids_of_a_small_scene_give_its_six_objects_each_pure() {
    use crate::synth::{InstanceIds, SensorModel, SensorSettings};
    let exact_masks = SensorSettings::new(SensorModel::None, InstanceIds::PerFrame);
    let objects = associate_small_scene(4, exact_masks);
    assert_eq!(objects.len(), 6, "{objects:?}");
    assert!(objects.iter().all(|o| o.purity == 1.0), "{objects:?}");
    let truths: BTreeSet<ObjectId> = objects.iter().map(|o| o.truth).collect();
    assert_eq!(truths.len(), 6, "one object per ground-truth object: {objects:?}");

    let kinect = SensorSettings::new(SensorModel::Kinect, InstanceIds::PerFrame);
    let objects = associate_small_scene(4, kinect);
    // Catmap's Kinect-like masks: every object pure, each of the six truths found, and one
    // extra object of 40 pixels over the whole scene (a fragment of object 2's, 6 761 pixels).
    assert!(objects.iter().all(|o| o.purity == 1.0), "{objects:?}");
    let truths: BTreeSet<ObjectId> = objects.iter().map(|o| o.truth).collect();
    assert_eq!(truths.len(), 6, "every ground-truth object: {objects:?}");
    assert_eq!(objects.len(), 7, "{objects:?}");
    let mut pixels: Vec<u64> = objects.iter().map(|o| o.pixels).collect();
    pixels.sort_unstable();
    assert!(
        pixels[0] <= 50 && pixels[1] > 1000,
        "one extra object, a small fragment: {objects:?}"
    );
}
