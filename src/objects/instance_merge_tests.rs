//! Objects made twice merged: evidence per pair of frames apart and joined
//! ([`crate::objects::pair_evidence`]); and the reverse, an object made of two that frames show
//! apart (the masks an object takes in one frame: its own and the others).

use super::tests::{CHAIR, chair_at, mask, object_of, seen_face, side_by_side};
use super::*;

const SOFA: ClassId = ClassId(30);

/// The mask of a sofa's front between `x0` and `x1` (the sofa spans x = 0 … 2.2).
fn sofa_view(local: u32, x0: f32, x1: f32) -> MaskEvidence {
    mask(local, SOFA, seen_face([x0, 0.0, 0.0], [x1, 0.9, 0.8], 0.0))
}

#[test]
fn a_sofa_seen_end_to_end_in_three_partial_views_is_one_object_with_its_first_id() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let mut seen = Vec::new();
    // Its left end, then its right end (the views between them missed), then its middle.
    for t in 0..40u64 {
        let (x0, x1) = match t {
            0..4 => (0.0, 1.0),
            4..8 => (1.2, 2.2),
            _ => (0.4, 1.8),
        };
        let frame = tracker.associate_frame(FrameIndex(t), &[sofa_view(5, x0, x1)], &cfg);
        seen.push((object_of(&frame.fates, 5), frame.merges));
    }
    assert_eq!(seen[3].0, Some(ObjectId(1)), "the left end");
    assert_eq!(seen[7].0, Some(ObjectId(2)), "the right end, made an object of its own");
    // Views over both are held until the right end was first seen `candidate_window_frames`
    // ago (frame 4 + 30): then they are one.
    assert!(seen[8..34].iter().all(|s| *s == (None, vec![])), "{seen:?}");
    let merge = ObjectMerge {
        frame: FrameIndex(34),
        kept: ObjectId(1),
        absorbed: ObjectId(2),
    };
    assert_eq!(seen[34], (None, vec![merge]));
    assert!(seen[35..].iter().all(|s| *s == (Some(ObjectId(1)), vec![])), "{seen:?}");
    assert_eq!(tracker.object_count(), 1);
    assert_eq!(tracker.merges(), [merge]);
    // Either end alone is the one object now, and the next object's id is new.
    for (t, (x0, x1)) in [(40, (0.0, 1.0)), (41, (1.2, 2.2))] {
        let fates = tracker.associate(FrameIndex(t), &[sofa_view(5, x0, x1)], &cfg);
        assert_eq!(object_of(&fates, 5), Some(ObjectId(1)));
    }
    for t in 42..45u64 {
        let fates = tracker.associate(FrameIndex(t), &[sofa_view(6, 5.0, 6.0)], &cfg);
        assert_eq!(object_of(&fates, 6), (t == 44).then_some(ObjectId(3)), "{t}");
    }
}

#[test]
fn a_fragment_of_a_split_mask_rejoins_its_object_once_whole_masks_outnumber_split_ones() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let split = |t: u64| vec![sofa_view(1, 0.0, 1.6), sofa_view(2, 1.6, 2.2 + 0.01 * (t % 2) as f32)];
    for t in 0..3 {
        tracker.associate(FrameIndex(t), &[sofa_view(1, 0.0, 1.6)], &cfg);
    }
    for t in 3..6 {
        tracker.associate(FrameIndex(t), &split(t), &cfg);
    }
    assert_eq!(tracker.object_count(), 2, "the split end became an object");
    // Then whole in two frames of three, split in the third.
    let mut merges = Vec::new();
    for t in 6..36 {
        let masks = match t % 3 {
            1 => split(t),
            _ => vec![sofa_view(3, 0.0, 2.2)],
        };
        merges.extend(tracker.associate_frame(FrameIndex(t), &masks, &cfg).merges);
    }
    let merge = ObjectMerge {
        frame: FrameIndex(33),
        kept: ObjectId(1),
        absorbed: ObjectId(2),
    };
    assert_eq!(
        merges,
        [merge],
        "the first whole frame 30 after the fragment was first seen"
    );
    assert_eq!(tracker.object_count(), 1);
    let fates = tracker.associate(FrameIndex(36), &split(36), &cfg);
    assert_eq!(
        (object_of(&fates, 1), object_of(&fates, 2)),
        (Some(ObjectId(1)), Some(ObjectId(1)))
    );
}

#[test]
fn touching_chairs_a_segmenter_merges_in_a_run_of_frames_stay_two() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let (a, b) = (chair_at(0.0), chair_at(0.5));
    // Apart in frames 0–5, one mask over both in 6–9 (four joined for three apart: young
    // objects are not judged yet), apart again after.
    for t in 0..40 {
        let merged = (6..10).contains(&t);
        let frame = tracker.associate_frame(FrameIndex(t), &side_by_side(t, a, b, merged), &cfg);
        if merged {
            assert_eq!(frame.fates[&ObjectId(30)], MaskFate::Held(HoldReason::Ambiguous));
        }
        assert_eq!(frame.merges, [], "{t}");
    }
    assert_eq!(tracker.object_count(), 2);
}

#[test]
fn an_object_made_of_two_chairs_merged_in_its_first_frames_lets_the_second_go_once_seen_apart() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    // Two chairs 2 m apart that one mask covered in the first three frames (adjacent in the image,
    // one far behind the other): one object spans both.
    let (a, b) = (chair_at(0.0), chair_at(2.0));
    for t in 0..3 {
        tracker.associate(FrameIndex(t), &side_by_side(t, a, b, true), &cfg);
    }
    assert_eq!(tracker.object_count(), 1);
    let first = ObjectId(1);
    // Then always apart: A's mask (the one of most points on the object) keeps the object, and
    // every frame that gives it B's mask too counts against B's voxels, until B's mask is decided
    // without it and becomes an object of its own.
    let mut seen = Vec::new();
    for t in 3..12 {
        let fates = tracker.associate(FrameIndex(t), &side_by_side(t, a, b, false), &cfg);
        seen.push((object_of(&fates, 10), object_of(&fates, 20)));
    }
    assert!(seen.iter().all(|&(x, _)| x == Some(first)), "{seen:?}");
    let second = ObjectId(2);
    assert_eq!(seen[seen.len() - 3..], [(Some(first), Some(second)); 3], "{seen:?}");
    assert_eq!(tracker.object_count(), 2);
}

#[test]
fn an_object_its_segmenter_splits_in_one_frame_of_four_stays_one() {
    let cfg = AssociationConfig::default();
    let mut tracker = InstanceTracker::default();
    let (lo, hi) = chair_at(0.0);
    let mut ids = BTreeSet::new();
    for t in 0..24u64 {
        let j = 0.01 * (t % 3) as f32;
        let masks = match t % 4 == 3 {
            true => vec![
                mask(1, CHAIR, seen_face(lo, [0.0, 0.5, 0.9], j)),
                mask(2, CHAIR, seen_face([0.02, 0.0, 0.0], hi, j)),
            ],
            false => vec![mask(1, CHAIR, seen_face(lo, hi, j))],
        };
        let fates = tracker.associate(FrameIndex(t), &masks, &cfg);
        ids.extend(fates.values().filter_map(|f| match f {
            MaskFate::Object(id) => Some(*id),
            MaskFate::Held(_) => None,
        }));
    }
    assert_eq!(ids, BTreeSet::from([ObjectId(1)]));
    assert_eq!((tracker.object_count(), tracker.candidate_count()), (1, 0));
}
