use nalgebra::Point3;

use super::*;
use crate::objects::hidden_space::{FreeCells, HiddenCells, UnseenCells};
use crate::objects::view_fixtures::{Solid, aabb, render};

/// Every hidden cell solid.
const ALL: CellRules = CellRules {
    hidden: HiddenCells::All,
    unseen: UnseenCells::Unknown,
    free: FreeCells::Seen,
};

/// One copy of the fixtures' slab (5 cm thick, facing −y, in a box 40 cm deep behind it),
/// shifted along x by `x`: the scene and the box.
fn slab_at(x: f32) -> (Vec<Solid>, OrientedBox) {
    let slab = Solid {
        aabb: aabb([x - 0.2, 1.0, 0.0], [x + 0.2, 1.05, 0.4]),
        is_object: true,
    };
    (vec![slab], aabb([x - 0.2, 1.0, 0.0], [x + 0.2, 1.4, 0.4]))
}

/// The normalised frame of a box.
fn nocs_of(b: &OrientedBox) -> NocsFrame {
    NocsFrame::of_box(b.world_from_box, b.extents())
}

#[test]
fn a_cell_a_twin_saw_free_is_dropped_and_one_every_twin_left_hidden_is_kept() {
    // Member A seen from the front only: the box behind its slab is hidden.
    let (scene_a, box_a) = slab_at(0.0);
    let front_a = render([0.0, -1.0, 0.2], 0.0, &scene_a);
    let own = HiddenSpace::of_views(&[&front_a], &box_a, None, ALL);
    assert!(own.hidden_share() > 0.8, "{}", own.hidden_share());
    let behind = |space: &HiddenSpace| {
        space
            .centres
            .iter()
            .filter(|c| (space.world_from_box * **c).y > 1.1)
            .count()
    };
    // Twin B, 3 m along x, seen from the front too: every cell of A stays hidden in B.
    let (scene_b, box_b) = slab_at(3.0);
    let front_b = render([3.0, -1.0, 0.2], 0.0, &scene_b);
    let twin_from_front = MemberSight {
        views: vec![&front_b],
        nocs: nocs_of(&box_b),
    };
    let shared = hidden_in_every_member(&own, &nocs_of(&box_a), std::slice::from_ref(&twin_from_front));
    assert_eq!(
        shared.centres, own.centres,
        "a twin seen from the same side keeps every cell"
    );
    // Twin C seen from the side: the space behind its slab was seen through, and A's cells
    // there are dropped; only the slab's own cells stay.
    let (scene_c, box_c) = slab_at(-3.0);
    let side_c = render([-1.0, 1.2, 0.2], -std::f32::consts::FRAC_PI_2, &scene_c);
    let twin_from_side = MemberSight {
        views: vec![&side_c],
        nocs: nocs_of(&box_c),
    };
    let with_side = hidden_in_every_member(&own, &nocs_of(&box_a), &[twin_from_front, twin_from_side.clone()]);
    assert!(behind(&own) > 1000, "{}", behind(&own));
    assert_eq!(
        behind(&with_side),
        0,
        "no cell behind the slab where twin C saw through"
    );
    assert!(!with_side.centres.is_empty(), "the slab's own cells stay");
    assert!(with_side.centres.iter().all(|c| own.centres.contains(c)));
    assert!(with_side.free_centres.is_empty() && with_side.open_centres.is_empty());
    // With no other member every cell is the member's alone: all kept.
    assert_eq!(hidden_in_every_member(&own, &nocs_of(&box_a), &[]).centres, own.centres);
}

#[test]
fn cells_map_through_the_normalised_frames_scale_included() {
    // Twin D is twice A's size (slab and box), 3 m along x, seen from the side: A's cells
    // behind its slab land twice as deep behind D's, where D was seen through; they are dropped.
    let (scene_a, box_a) = slab_at(0.0);
    let front_a = render([0.0, -1.0, 0.2], 0.0, &scene_a);
    let own = HiddenSpace::of_views(&[&front_a], &box_a, None, ALL);
    let big = |min: [f32; 3], max: [f32; 3]| aabb(min.map(|c| 2.0 * c), max.map(|c| 2.0 * c));
    let shift = |b: OrientedBox| OrientedBox {
        world_from_box: nalgebra::Translation3::new(3.0, 0.0, 0.0) * b.world_from_box,
        ..b
    };
    let slab_d = shift(big([-0.2, 1.0, 0.0], [0.2, 1.05, 0.4]));
    let box_d = shift(big([-0.2, 1.0, 0.0], [0.2, 1.4, 0.4]));
    let scene_d = vec![Solid {
        aabb: slab_d,
        is_object: true,
    }];
    let side_d = render([5.0, 2.4, 0.4], -std::f32::consts::FRAC_PI_2, &scene_d);
    let deep = box_d.world_from_box * Point3::new(0.0, 0.3, 0.0);
    assert_eq!(
        crate::objects::cell_evidence::cell_evidence(&[&side_d], &deep, 0.02),
        CellEvidence::SeenFree,
        "the side view sees through D's box behind its slab"
    );
    let twin = MemberSight {
        views: vec![&side_d],
        nocs: nocs_of(&box_d),
    };
    let shared = hidden_in_every_member(&own, &nocs_of(&box_a), &[twin]);
    let deepest = shared
        .centres
        .iter()
        .map(|c| (shared.world_from_box * c).y)
        .fold(f32::MIN, f32::max);
    assert!(deepest < 1.15, "a cell {deepest} m deep behind A's slab was kept");
    assert!(!shared.centres.is_empty());
}

#[test]
fn the_cache_recomputes_when_another_members_views_change_and_not_otherwise() {
    let (scene_a, box_a) = slab_at(0.0);
    let front_a = render([0.0, -1.0, 0.2], 0.0, &scene_a);
    let (scene_b, box_b) = slab_at(3.0);
    let front_b = render([3.0, -1.0, 0.2], 0.0, &scene_b);
    let mut side_b = render([5.0, 1.2, 0.2], -std::f32::consts::FRAC_PI_2, &scene_b);
    side_b.frame = crate::ids::FrameIndex(7);
    let nocs_b = nocs_of(&box_b);
    let sight = |views| MemberSight { views, nocs: nocs_b };
    let mut cache = MemberHiddenCache::default();
    let nocs_a = nocs_of(&box_a);
    let a = (&[&front_a][..], &box_a);
    let first = cache.current(a, &nocs_a, &[sight(vec![&front_b])], ALL, 0.0).cloned();
    let first = first.expect("cells kept");
    let again = cache.current(a, &nocs_a, &[sight(vec![&front_b])], ALL, 0.0).cloned();
    assert_eq!(Some(&first), again.as_ref());
    let seen_through = cache.current(a, &nocs_a, &[sight(vec![&front_b, &side_b])], ALL, 0.0);
    let seen_through = seen_through.expect("the slab's cells kept");
    assert!(
        seen_through.centres.len() < first.centres.len() / 4,
        "{} of {} cells kept once the twin was seen from the side",
        seen_through.centres.len(),
        first.centres.len()
    );
}

#[test]
fn a_member_takes_the_cells_only_when_they_are_a_large_share_of_its_box() {
    // Seen from the front, A's box is hidden behind its slab (over 80 %); seen from the side
    // too, only the slab's own cells stay (a few per cent).
    let (scene_a, box_a) = slab_at(0.0);
    let front_a = render([0.0, -1.0, 0.2], 0.0, &scene_a);
    let side_a = render([2.0, 1.2, 0.2], -std::f32::consts::FRAC_PI_2, &scene_a);
    let nocs_a = nocs_of(&box_a);
    let mut cache = MemberHiddenCache::default();
    let from_front = cache.current((&[&front_a], &box_a), &nocs_a, &[], ALL, 0.25);
    assert!(from_front.is_some_and(|s| s.hidden_share() > 0.8));
    let both = (&[&front_a, &side_a][..], &box_a);
    assert!(cache.current(both, &nocs_a, &[], ALL, 0.25).is_none());
    let few = cache.current(both, &nocs_a, &[], ALL, 0.0).map(|s| s.hidden_share());
    assert!(few.is_some_and(|share| share > 0.0 && share < 0.25), "{few:?}");
}

#[test]
fn members_are_matched_only_with_the_members_of_their_own_field() {
    // A and B seen from the front, C from the side. With C in another field, A keeps every
    // cell behind its slab; with C in A's field, A keeps none of them (and neither does B).
    let (scene_a, box_a) = slab_at(0.0);
    let (scene_b, box_b) = slab_at(3.0);
    let (scene_c, box_c) = slab_at(-3.0);
    let front_a = render([0.0, -1.0, 0.2], 0.0, &scene_a);
    let front_b = render([3.0, -1.0, 0.2], 0.0, &scene_b);
    let side_c = render([-1.0, 1.2, 0.2], -std::f32::consts::FRAC_PI_2, &scene_c);
    let member = |field, member, views, fitted_box: OrientedBox| MemberCells {
        field,
        member,
        fitted_box,
        sight: MemberSight {
            views,
            nocs: nocs_of(&fitted_box),
        },
    };
    let shares = |c_field| {
        let members = [
            member(0, 0, vec![&front_a], box_a),
            member(0, 1, vec![&front_b], box_b),
            member(c_field, 2, vec![&side_c], box_c),
        ];
        let mut caches = vec![MemberHiddenCache::default(); 3];
        let shared = hidden_in_every_member_of_fields(&members, caches.iter_mut().collect(), ALL, 0.0);
        shared
            .iter()
            .map(|s| s.map_or(0.0, HiddenSpace::hidden_share))
            .collect::<Vec<_>>()
    };
    let apart = shares(1);
    assert!(apart[0] > 0.8 && apart[1] > 0.8, "{apart:?}");
    let together = shares(0);
    assert!(together[0] < 0.2 && together[1] < 0.2, "{together:?}");
}
