//! Tests of the category field set: following memberships, fresh codes for moved frames, ended fields.

use super::*;
use crate::categories::class_registration::RegisteredMember;
use crate::categories::subcategories::Alignment;
use nalgebra::{Isometry3, Vector3};

fn member() -> RegisteredMember {
    RegisteredMember {
        alignment: Alignment {
            template_from_object: Isometry3::identity(),
            chamfer: 0.0,
            reverse_chamfer: None,
        },
        nocs: NocsFrame::of_box(Isometry3::identity(), Vector3::new(1.0, 2.0, 1.0)),
    }
}

fn subcategory(representative: u32, members: &[u32]) -> RegisteredSubcategory {
    RegisteredSubcategory {
        representative: ObjectId(representative),
        members: members.iter().map(|&id| (ObjectId(id), member())).collect(),
    }
}

#[test]
fn fields_follow_the_multi_member_subcategories_by_representative() {
    let mut set = CategoryFieldSet::new(AdamWConfig::default());
    let groups = [
        subcategory(7, &[7, 8]),
        subcategory(1, &[1, 2, 3]),
        subcategory(5, &[5]),
    ];
    let places = set.follow(&groups, 3, MemberCodes::per_member(8), &FrameHoldConfig::default());
    assert_eq!(
        set.members,
        vec![
            vec![ObjectId(1), ObjectId(2), ObjectId(3)],
            vec![ObjectId(7), ObjectId(8)]
        ]
    );
    assert_eq!(
        (set.batch.len(), set.ids.clone(), set.fields_created),
        (2, vec![0, 1], 2)
    );
    assert_eq!(places[&ObjectId(8)].field, 1);
    assert_eq!(places[&ObjectId(8)].member, 1);
    assert!(
        !places.contains_key(&ObjectId(5)),
        "a subcategory of one keeps its own field"
    );
    assert!(set.losses.iter().all(|l| l.is_nan()));
}

#[test]
fn an_unchanged_membership_keeps_the_fields_and_a_split_starts_one_more() {
    let mut set = CategoryFieldSet::new(AdamWConfig::default());
    set.follow(
        &[subcategory(1, &[1, 2, 3, 4])],
        3,
        MemberCodes::per_member(8),
        &FrameHoldConfig::default(),
    );
    set.losses[0] = 0.5;
    let before = set.batch.field(0).cloned();
    set.follow(
        &[subcategory(1, &[1, 2, 3, 4])],
        3,
        MemberCodes::per_member(8),
        &FrameHoldConfig::default(),
    );
    assert_eq!((set.remaps, set.losses[0]), (1, 0.5), "nothing to remap");
    assert_eq!(set.batch.field(0).cloned(), before);
    let places = set.follow(
        &[subcategory(1, &[1, 2, 3]), subcategory(4, &[4, 9])],
        3,
        MemberCodes::per_member(8),
        &FrameHoldConfig::default(),
    );
    assert_eq!(set.ids, vec![0, 1], "the larger part continues field 0");
    assert_eq!((set.remaps, set.fields_created), (2, 2));
    assert_eq!(places[&ObjectId(9)].field, 1);
}

#[test]
fn a_member_whose_frame_is_replaced_gets_a_fresh_code_and_the_others_keep_theirs() {
    let mut set = CategoryFieldSet::new(AdamWConfig::default());
    set.follow(
        &[subcategory(1, &[1, 2, 3])],
        3,
        MemberCodes::per_member(8),
        &FrameHoldConfig::default(),
    );
    let codes = |set: &CategoryFieldSet| -> Vec<Vec<f32>> {
        let field = set.batch.field(0).expect("one field");
        (0..3).map(|j| field.shape_code(j).expect("member").to_vec()).collect()
    };
    let before = codes(&set);
    // Object 2's frame is moved 0.5 m by a registration (its scale is 1); the others' boxes
    // only grew.
    let mut moved = subcategory(1, &[1, 2, 3]);
    for (id, m) in &mut moved.members {
        if *id == ObjectId(2) {
            m.nocs = NocsFrame::of_box(Isometry3::translation(0.5, 0.0, 0.0), Vector3::new(1.0, 2.0, 1.0));
        } else {
            m.nocs.extents *= 1.1;
        }
    }
    let places = set.follow(&[moved], 3, MemberCodes::per_member(8), &FrameHoldConfig::default());
    let after = codes(&set);
    assert_eq!(
        (after[0] == before[0], after[2] == before[2]),
        (true, true),
        "kept codes"
    );
    assert_ne!(after[1], before[1], "the moved member starts afresh");
    assert_eq!(set.frames_replaced, 1);
    assert_eq!(set.ids, vec![0], "the field continues");
    assert!(
        (places[&ObjectId(2)].nocs.world_from_nocs.isometry.translation.x - 0.5).abs() < 1e-6,
        "it trains in its new frame"
    );
}

#[test]
fn a_field_no_subcategory_continues_is_recorded_as_dropped() {
    let mut set = CategoryFieldSet::new(AdamWConfig::default());
    set.follow(
        &[subcategory(1, &[1, 2]), subcategory(5, &[5, 6])],
        3,
        MemberCodes::per_member(8),
        &FrameHoldConfig::default(),
    );
    set.follow(
        &[subcategory(1, &[1, 2, 5, 6])],
        3,
        MemberCodes::per_member(8),
        &FrameHoldConfig::default(),
    );
    assert_eq!(
        set.retired,
        vec![RetiredField {
            id: 1,
            members: vec![ObjectId(5), ObjectId(6)],
            remap: 2,
            cause: Retirement::Dropped,
        }]
    );
    assert_eq!(set.ids, vec![0]);
}
