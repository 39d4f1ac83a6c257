//! Tests of one class's registration: warm starts, the pair cache, frames that hold still.

use nalgebra::Isometry3;

use super::*;
use crate::categories::held_frames::{FrameHoldConfig, FramePolicy, FrameSymmetry, frame_change};

#[test]
fn a_class_is_due_when_new_when_its_members_change_or_a_cloud_grows() {
    let (a, b, c) = (ObjectId(1), ObjectId(2), ObjectId(3));
    let then = BTreeMap::from([(a, 1_000), (b, 500)]);
    assert!(class_is_due(None, &[(a, 10)], 0.2), "never registered");
    assert!(
        !class_is_due(Some(&then), &[(a, 1_200), (b, 500)], 0.2),
        "20 % is not more than 20 %"
    );
    assert!(class_is_due(Some(&then), &[(a, 1_000), (b, 601)], 0.2), "a cloud grew");
    assert!(
        class_is_due(Some(&then), &[(a, 1_000), (b, 500), (c, 10)], 0.2),
        "a member joined"
    );
    assert!(
        class_is_due(Some(&then), &[(a, 1_000), (c, 500)], 0.2),
        "a member was replaced"
    );
}

/// Members drawn as partial, noisy views of `(id, design, seed)`, ranked by id (the lowest
/// first).
fn members_of(drawn: &[(u32, crate::synth::Design, u64)]) -> Vec<MemberInput> {
    use crate::geometry::oriented_box::fit_minimum_volume_box;
    use crate::synth::{RegistrationTrial, RegistrationTrialSpec};
    let spec = RegistrationTrialSpec {
        outlier_fraction: 0.0,
        visible: (0.7, 0.8),
        ..RegistrationTrialSpec::default()
    };
    drawn
        .iter()
        .map(|&(id, design, seed)| {
            let trial = RegistrationTrial::draw(design, &spec, seed).unwrap();
            MemberInput {
                id: ObjectId(id),
                bounds: fit_minimum_volume_box(&trial.source).unwrap(),
                cloud: trial.source,
                cloud_version: 1,
                reliable_rays: 10 - id as usize,
            }
        })
        .collect()
}

/// Two copies of one chair design and a table, each a partial, noisy view.
fn three_members() -> Vec<MemberInput> {
    use crate::synth::Design;
    members_of(&[
        (1, Design::LadderBackChair, 1),
        (2, Design::LadderBackChair, 2),
        (3, Design::DiningTable, 3),
    ])
}

/// The same members after their clouds changed (new versions of the same points), so that no
/// pair is answered from the cache.
fn touched(members: &[MemberInput]) -> Vec<MemberInput> {
    members
        .iter()
        .map(|m| MemberInput {
            cloud_version: m.cloud_version + 1,
            ..m.clone()
        })
        .collect()
}

fn first_time() -> ClassRegistration {
    ClassRegistration::default()
}

fn groups(registered: &ClassRegistration) -> Vec<(ObjectId, Vec<ObjectId>)> {
    registered
        .groups
        .iter()
        .map(|g| (g.representative, g.members.keys().copied().collect()))
        .collect()
}

fn starting(registration_start: RegistrationStart) -> CategoryConfig {
    CategoryConfig {
        registration_start,
        ..CategoryConfig::default()
    }
}

#[test]
fn a_warm_re_registration_keeps_the_full_searchs_groups_and_scores() {
    let members = three_members();
    let first = register_class(&members, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
    assert_eq!(
        groups(&first),
        vec![
            (ObjectId(1), vec![ObjectId(1), ObjectId(2)]),
            (ObjectId(3), vec![ObjectId(3)])
        ],
        "the chair copies share a subcategory, the table does not"
    );
    let again = register_class(&touched(&members), &first, &starting(RegistrationStart::Warm), 7).unwrap();
    assert_eq!(groups(&again), groups(&first));
    let (cold, warm) = (
        first.groups[0].members[&ObjectId(2)].alignment.chamfer,
        again.groups[0].members[&ObjectId(2)].alignment.chamfer,
    );
    assert!(
        warm_start_holds(warm, cold, CategoryConfig::default().warm_start_tolerance),
        "refining the stored pose on the same clouds: {warm} vs {cold}"
    );
}

#[test]
fn a_warm_start_that_scores_worse_falls_back_to_the_full_search() {
    let members = three_members();
    let first = register_class(&members, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
    // A stored alignment half a turn off, with the good score: the warm start cannot reach it.
    let mut wrong = first.clone();
    let pair = wrong.pairs.0.get_mut(&(ObjectId(2), ObjectId(1))).unwrap();
    pair.template_from_source =
        Isometry3::rotation(nalgebra::Vector3::new(0.0, 0.0, std::f32::consts::PI)) * pair.template_from_source;
    let again = register_class(&touched(&members), &wrong, &starting(RegistrationStart::Warm), 7).unwrap();
    assert_eq!(groups(&again), groups(&first));
    assert_eq!(
        again.groups[0].members[&ObjectId(2)].alignment.chamfer,
        first.groups[0].members[&ObjectId(2)].alignment.chamfer,
        "the full search's result"
    );
}

#[test]
fn frames_hold_still_across_a_re_registration_that_keeps_the_membership() {
    // Issue 31: a member's NOCS frame must not move under its category field when only the
    // representative's box was refitted.
    let members = three_members();
    let search = starting(RegistrationStart::Search);
    let first = register_class(&members, &first_time(), &search, 7).unwrap();
    let mut later = touched(&members);
    // The representative's box refitted (on a grown cloud): 1 cm away and a quarter turn off
    // (a near-square seat's longer edge changed sides).
    let refit = &mut later[0].bounds;
    refit.world_from_box *= Isometry3::new(
        nalgebra::Vector3::new(0.01, 0.0, 0.0),
        nalgebra::Vector3::z() * std::f32::consts::FRAC_PI_2,
    );
    refit.half_extents = nalgebra::Vector3::new(refit.half_extents.y, refit.half_extents.x, refit.half_extents.z);
    let with = |policy| CategoryConfig {
        frames: FrameHoldConfig {
            policy,
            ..FrameHoldConfig::default()
        },
        ..search.clone()
    };
    let before = first.frames();
    let turn = |after: &BTreeMap<ObjectId, NocsFrame>, id| frame_change(&before[&id], &after[&id], FrameSymmetry::None);
    let again = register_class(&later, &first, &with(FramePolicy::Hold), 7).unwrap();
    assert_eq!(groups(&again), groups(&first), "the membership is kept");
    let held = again.frames();
    for id in [ObjectId(1), ObjectId(2), ObjectId(3)] {
        assert_eq!(
            held[&id].world_from_nocs, before[&id].world_from_nocs,
            "hold: object {id}'s frame held still"
        );
        assert!(
            held[&id]
                .extents
                .iter()
                .zip(before[&id].extents.iter())
                .all(|(a, b)| a >= b),
            "boxes only grow"
        );
    }
    let refitted = register_class(&later, &first, &with(FramePolicy::KeepAxes), 7)
        .unwrap()
        .frames();
    for id in [ObjectId(1), ObjectId(2)] {
        let change = turn(&refitted, id);
        assert!(change.turn_rad < 1e-5, "keep_axes: no turn of object {id}: {change:?}");
        assert!(change.shift > 0.0, "keep_axes: the centre follows the refit");
    }
    let rebuilt = register_class(&later, &first, &with(FramePolicy::Rebuild), 7)
        .unwrap()
        .frames();
    assert!(
        (turn(&rebuilt, ObjectId(1)).turn_rad - std::f32::consts::FRAC_PI_2).abs() < 1e-4,
        "rebuilding turns every frame with the refitted box"
    );
}

#[test]
fn pairs_on_unchanged_clouds_are_answered_as_before_and_only_they() {
    let members = three_members();
    let search = starting(RegistrationStart::Search);
    let first = register_class(&members, &first_time(), &search, 7).expect("registered");
    // Table → chair representative (rejected) and chair → chair (joined): both answered.
    assert_eq!(first.pairs.len(), 2, "{:?}", first.pairs.0.keys());
    // An impossible answer planted in the cache shows whether a pair was searched again.
    let mut planted = first.clone();
    for cached in planted.pairs.0.values_mut() {
        cached.chamfer = 1e-6;
    }
    let again = register_class(&members, &planted, &search, 7).expect("registered");
    assert_eq!(
        again.pairs, planted.pairs,
        "no cloud changed: every pair from the cache"
    );
    assert_eq!(
        groups(&again),
        vec![(ObjectId(1), members.iter().map(|m| m.id).collect())]
    );

    let mut table_moved = members.clone();
    table_moved[2].cloud_version += 1;
    let after = register_class(&table_moved, &planted, &search, 7).expect("registered");
    assert_eq!(groups(&after), groups(&first), "the table's pair searched again");
    let chair_pair = (ObjectId(2), ObjectId(1));
    assert_eq!(
        after.pairs.0[&chair_pair], planted.pairs.0[&chair_pair],
        "the chairs' pair kept"
    );
    assert_eq!(
        after.pairs.0[&(ObjectId(3), ObjectId(1))],
        CachedPair {
            versions: PairVersions { source: 2, template: 1 },
            ..first.pairs.0[&(ObjectId(3), ObjectId(1))]
        },
        "searched anew: exactly the first search's answer"
    );
}

#[test]
fn a_reused_pair_keeps_its_alignment_until_a_cloud_grows() {
    let members = three_members();
    let first = register_class(&members, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
    let chair = |registered: &ClassRegistration| registered.groups[0].members[&ObjectId(2)];
    let found_at = |registered: &ClassRegistration| registered.pairs.0[&(ObjectId(2), ObjectId(1))].found_at;
    assert_eq!(
        found_at(&first),
        PairPoints {
            source: members[1].cloud.len(),
            template: members[0].cloud.len()
        },
        "a searched pair records its cloud sizes"
    );
    let reuse = starting(RegistrationStart::Reuse);
    let again = register_class(&touched(&members), &first, &reuse, 7).unwrap();
    assert_eq!(groups(&again), groups(&first));
    let (kept, searched) = (chair(&again), chair(&first));
    assert_eq!(
        (kept.alignment.template_from_object, kept.nocs, found_at(&again)),
        (searched.alignment.template_from_object, searched.nocs, found_at(&first)),
        "same clouds: the alignment is kept as it was"
    );
    assert!(
        (kept.alignment.chamfer - searched.alignment.chamfer).abs() < 1e-6,
        "rescored on the same clouds (in f32 rather than the search's f64 pose)"
    );

    // The member's cloud grows by half (its points again, shifted by 1 mm): searched anew.
    let mut grown = members.clone();
    let extra: Vec<Point3<f32>> = grown[1]
        .cloud
        .iter()
        .step_by(2)
        .map(|p| p + nalgebra::Vector3::new(0.001, 0.0, 0.0))
        .collect();
    grown[1].cloud.extend(extra);
    grown[1].cloud_version += 1;
    let after = register_class(&grown, &again, &reuse, 7).unwrap();
    assert_eq!(groups(&after), groups(&first));
    assert_eq!(
        found_at(&after).source,
        grown[1].cloud.len(),
        "searched at the grown size"
    );
    let searched = register_class(&grown, &first_time(), &starting(RegistrationStart::Search), 7).unwrap();
    assert_eq!(chair(&after), chair(&searched), "exactly the full search's result");
}

#[test]
fn the_best_explanation_pass_keeps_its_own_pairs_until_a_cloud_grows_by_the_growth() {
    use crate::categories::subcategories::SubcategoryAssignment;
    use crate::synth::Design;
    // Two chairs and two tables, the chairs ranked first: the greedy pass groups the chairs
    // under chair 1 and the tables under table 3; the best pass asks chair 2 about table 3,
    // which the greedy pass never did.
    let members = members_of(&[
        (1, Design::LadderBackChair, 1),
        (2, Design::LadderBackChair, 2),
        (3, Design::DiningTable, 3),
        (4, Design::DiningTable, 4),
    ]);
    let mut cfg = starting(RegistrationStart::Search);
    cfg.subcategories.assignment = SubcategoryAssignment::Best;
    let first = register_class(&members, &first_time(), &cfg, 7).unwrap();
    assert_eq!(
        groups(&first),
        vec![
            (ObjectId(1), vec![ObjectId(1), ObjectId(2)]),
            (ObjectId(3), vec![ObjectId(3), ObjectId(4)])
        ]
    );
    let (greedy_pair, best_pair) = ((ObjectId(2), ObjectId(1)), (ObjectId(2), ObjectId(3)));
    assert!(
        first.pairs.0.contains_key(&best_pair),
        "the best pass asked chair 2 about table 3"
    );
    let found_at = |registered: &ClassRegistration, pair| registered.pairs.0[&pair].found_at.source;

    // Chair 2's cloud grows by a tenth (its points again, shifted by 1 mm): the greedy pass
    // searches its pair anew, the best pass keeps its own.
    let grow = |members: &[MemberInput], share: usize| {
        let mut grown = members.to_vec();
        let extra: Vec<Point3<f32>> = grown[1]
            .cloud
            .iter()
            .step_by(share)
            .map(|p| p + nalgebra::Vector3::new(0.001, 0.0, 0.0))
            .collect();
        grown[1].cloud.extend(extra);
        grown[1].cloud_version += 1;
        grown
    };
    let tenth = grow(&members, 10);
    let again = register_class(&tenth, &first, &cfg, 7).unwrap();
    assert_eq!(groups(&again), groups(&first));
    assert_eq!(found_at(&again, greedy_pair), tenth[1].cloud.len(), "searched anew");
    assert_eq!(found_at(&again, best_pair), members[1].cloud.len(), "kept");
    // Grown by half: searched anew too.
    let half = grow(&members, 2);
    let after = register_class(&half, &first, &cfg, 7).unwrap();
    assert_eq!(found_at(&after, best_pair), half[1].cloud.len());
}

#[test]
fn a_member_fitting_worse_than_the_threshold_is_searched_again_once_and_keeps_the_better_alignment() {
    use crate::synth::Design;
    let members = members_of(&[
        (1, Design::LadderBackChair, 1),
        (2, Design::LadderBackChair, 2),
        (3, Design::LadderBackChair, 3),
    ]);
    let with = |above: f32| CategoryConfig {
        second_search: SecondSearch {
            above,
            ..SecondSearch::default()
        },
        ..CategoryConfig::default()
    };
    let once = register_class(&members, &first_time(), &with(1.0), 7).expect("registered");
    assert!(
        once.pairs.0.values().all(|p| p.searches == PairSearches::First),
        "above 1: no member is searched again"
    );
    let twice = register_class(&members, &first_time(), &with(0.0), 7).expect("registered");
    assert_eq!(
        groups(&twice),
        groups(&once),
        "the subcategories are the first search's"
    );
    let group = &twice.groups[0];
    for (id, member) in group.members.iter().filter(|(id, _)| **id != group.representative) {
        let pair = &twice.pairs.0[&(*id, group.representative)];
        assert_eq!(pair.searches, PairSearches::Second, "member {id}");
        assert_eq!(
            pair.chamfer, member.alignment.chamfer,
            "the pair's answer is the member's"
        );
        let first = once.groups[0].members[id].alignment.chamfer;
        assert!(
            member.alignment.chamfer <= first,
            "member {id}: {} > {first}",
            member.alignment.chamfer
        );
    }
    // On the same clouds every pair is answered from the store, second search included: an
    // answer planted there stays.
    let mut planted = twice.clone();
    for pair in planted.pairs.0.values_mut() {
        pair.chamfer = 0.001;
    }
    let again = register_class(&members, &planted, &with(0.0), 7).expect("registered");
    assert_eq!(again.pairs, planted.pairs, "nothing searched again");
}
