use nalgebra::Point3;

use super::*;
use crate::objects::cell_evidence::{CellEvidence, cell_evidence};
use crate::objects::object_view::PixelState;
use crate::objects::view_fixtures::{Solid, aabb, render, render_pitched, slab_and_box};
use crate::rng::{RngStream, seeded_rng};

/// Every hidden cell solid, free draws around the cells seen free only (the rules before open
/// cells).
pub(super) const ALL: CellRules = CellRules {
    hidden: HiddenCells::All,
    unseen: UnseenCells::Unknown,
    free: FreeCells::Seen,
};

/// Enclosed hidden cells solid, free draws around the cells seen free only.
pub(super) const ENCLOSED: CellRules = CellRules {
    hidden: HiddenCells::Enclosed,
    unseen: UnseenCells::Unknown,
    free: FreeCells::Seen,
};

#[test]
fn cells_behind_the_seen_face_are_hidden_and_cells_seen_through_are_not() {
    let (scene, object_box) = slab_and_box();
    // Seen from the front only: everything behind the slab is hidden.
    let front = render([0.0, -1.0, 0.2], 0.0, &scene);
    let margin = 0.03;
    let behind = Point3::new(0.0, 1.3, 0.2);
    assert_eq!(cell_evidence(&[&front], &behind, margin), CellEvidence::Hidden);
    // In front of the slab the ray is free.
    assert_eq!(
        cell_evidence(&[&front], &Point3::new(0.0, 0.9, 0.2), margin),
        CellEvidence::SeenFree
    );
    let only_front = HiddenSpace::of_views(&[&front], &object_box, None, ALL);
    assert!(only_front.hidden_share() > 0.8, "{}", only_front.hidden_share());
    // A side view sees the slab's edge and the room through the rest of the box: the cells
    // behind the slab are seen free, only the slab's own cells stay hidden.
    let side = render([2.0, 1.2, 0.2], -std::f32::consts::FRAC_PI_2, &scene);
    assert_eq!(cell_evidence(&[&front, &side], &behind, margin), CellEvidence::SeenFree);
    let both = HiddenSpace::of_views(&[&front, &side], &object_box, None, ALL);
    assert!(both.hidden_share() < 0.2, "{}", both.hidden_share());
    for c in &both.centres {
        let world = both.world_from_box * c;
        assert!(
            world.y < 1.1,
            "a hidden cell at {world} lies behind the slab, where the side view saw through"
        );
    }
}

#[test]
fn a_patch_with_no_return_is_seen_through_and_a_lone_hole_says_nothing() {
    let (scene, _) = slab_and_box();
    let front = render([0.0, -1.0, 0.2], 0.0, &scene);
    let behind = Point3::new(0.0, 1.3, 0.2);
    let margin = 0.03;
    // The side view's room lies beyond the sensor's range: no depth anywhere but on the slab.
    let mut far = render([2.0, 1.2, 0.2], -std::f32::consts::FRAC_PI_2, &scene);
    for (d, state) in far.depth_m.iter_mut().zip(&far.states) {
        if *state != PixelState::ThisObject {
            *d = 0.0;
        }
    }
    assert_eq!(cell_evidence(&[&front, &far], &behind, margin), CellEvidence::SeenFree);
    // Deeper than the crop's deepest return the patch says nothing: the sensor's reach is known
    // only that far (a sofa's inside beyond a 5 m range, behind its front beyond it too).
    let short = ObjectView {
        deepest_return_m: far.world_from_camera.inverse_transform_point(&behind).z - 0.1,
        ..far.clone()
    };
    assert_eq!(cell_evidence(&[&front, &short], &behind, margin), CellEvidence::Hidden);
    // A single pixel without depth, its neighbours valid (a dropout, a hole at an edge): the
    // view says nothing there, and the cell stays hidden behind the front face.
    let mut holed = render([2.0, 1.2, 0.2], -std::f32::consts::FRAC_PI_2, &scene);
    let seen = holed.world_from_camera.inverse_transform_point(&behind);
    let (x, y) = holed.intrinsics.project(&seen).expect("in front of the side view");
    let i = holed
        .index_of(x.round() as u32, y.round() as u32)
        .expect("in the image");
    holed.depth_m[i] = 0.0;
    assert_eq!(cell_evidence(&[&front, &holed], &behind, margin), CellEvidence::Hidden);
}

#[test]
fn cells_behind_another_object_are_not_hidden() {
    // The same slab hidden behind a wall that is not the object: nothing is behind *its* surface.
    let (mut scene, object_box) = slab_and_box();
    scene.push(Solid {
        aabb: aabb([-1.0, 0.5, -0.5], [1.0, 0.55, 1.0]),
        is_object: false,
    });
    let front = render([0.0, -1.0, 0.2], 0.0, &scene);
    let space = HiddenSpace::of_views(&[&front], &object_box, None, ALL);
    assert!(space.centres.is_empty(), "{} hidden cells", space.centres.len());
    assert!(space.draw(&mut seeded_rng(0, RngStream::Mapper)).is_none());
}

#[test]
fn a_cell_behind_another_object_in_one_view_is_not_hidden_by_another() {
    // A tabletop (the object) with a block (another object) under its front edge. From above,
    // a point under the top lies behind the top; from the front, low, behind the block: the
    // views disagree on what hides it, so it may be empty and is not hidden.
    let scene = [
        Solid {
            aabb: aabb([-0.5, 1.0, 0.7], [0.5, 2.0, 0.75]),
            is_object: true,
        },
        Solid {
            aabb: aabb([-0.3, 0.9, 0.0], [0.3, 1.2, 0.45]),
            is_object: false,
        },
    ];
    let under_top = Point3::new(0.0, 1.4, 0.3);
    let above = render_pitched([0.0, 1.5, 2.5], 0.0, -1.45, &scene);
    let front = render([0.0, -1.0, 0.3], 0.0, &scene);
    let margin = 0.03;
    assert_eq!(cell_evidence(&[&above], &under_top, margin), CellEvidence::Hidden);
    assert_eq!(cell_evidence(&[&front], &under_top, margin), CellEvidence::Occluded);
    assert_eq!(
        cell_evidence(&[&above, &front], &under_top, margin),
        CellEvidence::Occluded
    );
}

/// A table (the object): a top 0.7–0.75 m high over [−0.5, 0.5] × [1, 2], and an apron hanging
/// down to 30 cm along its front edge and the front half of its +x side.
fn table_with_aprons() -> Vec<Solid> {
    vec![
        Solid {
            aabb: aabb([-0.5, 1.0, 0.7], [0.5, 2.0, 0.75]),
            is_object: true,
        },
        Solid {
            aabb: aabb([-0.5, 1.0, 0.3], [0.5, 1.02, 0.7]),
            is_object: true,
        },
        Solid {
            aabb: aabb([0.48, 1.0, 0.3], [0.5, 1.5, 0.7]),
            is_object: true,
        },
    ]
}

/// The table's box.
fn table_box() -> OrientedBox {
    aabb([-0.5, 1.0, 0.0], [0.5, 2.0, 0.75])
}

/// Views of the table's scene: from above, from the front (low), from the +x side (low).
fn table_views(scene: &[Solid]) -> [ObjectView; 3] {
    [
        render_pitched([0.0, 1.5, 2.5], 0.0, -1.45, scene),
        render([0.0, -1.0, 0.1], 0.0, scene),
        render([2.5, 1.5, 0.1], -std::f32::consts::FRAC_PI_2, scene),
    ]
}

#[test]
fn under_an_overhang_open_sideways_only_enclosed_cells_stay_hidden() {
    // From above the space under the table's top lies behind the top; from the front, low,
    // behind the apron; from the +x side, low, the view sees under the top through the back
    // half, and the front half lies behind the side apron.
    let scene = table_with_aprons();
    let [above, low, side] = table_views(&scene);
    let views = [&above, &low, &side];
    assert_eq!(
        cell_evidence(&views, &Point3::new(0.0, 1.5, 0.1), 0.03),
        CellEvidence::SeenFree
    );
    assert_eq!(
        cell_evidence(&[&above, &low], &Point3::new(0.0, 1.5, 0.5), 0.03),
        CellEvidence::Hidden
    );
    let under_top = |space: &HiddenSpace| {
        let world = space.centres.iter().map(|c| space.world_from_box * c);
        world
            .filter(|p| (0.35..0.65).contains(&p.z) && (1.1..1.45).contains(&p.y))
            .count()
    };
    let all = HiddenSpace::of_views(&views, &table_box(), None, ALL);
    let enclosed = HiddenSpace::of_views(&views, &table_box(), None, ENCLOSED);
    assert!(under_top(&all) > 50, "{} hidden cells under the top", under_top(&all));
    assert_eq!(
        under_top(&enclosed),
        0,
        "cells open sideways onto seen-free space are not asked to be solid"
    );
    // The cells the +x view saw free under the top's back half are the seen-free prior's: below
    // the top, and the draws stay within a quarter cell of their centres.
    assert_eq!(
        all.free_centres, enclosed.free_centres,
        "the rule only picks hidden cells"
    );
    let free_world: Vec<Point3<f32>> = enclosed
        .free_centres
        .iter()
        .map(|c| enclosed.world_from_box * c)
        .collect();
    assert!(
        free_world.iter().filter(|p| p.z < 0.69 && p.y > 1.5).count() > 20,
        "{} cells seen free under the top's back half",
        free_world.len()
    );
    let mut rng = seeded_rng(3, RngStream::Mapper);
    for _ in 0..200 {
        let p = enclosed.draw_free(&views, &mut rng).expect("cells seen free");
        let near = free_world
            .iter()
            .any(|c| (0..3).all(|a| (p[a] - c[a]).abs() <= 0.25 * enclosed.cell_size[a] + 1e-5));
        assert!(near, "{p:?} within a quarter cell of a seen-free centre");
    }
    // Under the rule of open cells, the hidden cells under the top that open onto the space the
    // +x view saw under its back half are drawn free too; none is solid.
    let open = HiddenSpace::of_views(
        &views,
        &table_box(),
        None,
        CellRules {
            hidden: HiddenCells::Enclosed,
            unseen: UnseenCells::Unknown,
            free: FreeCells::SeenAndOpen,
        },
    );
    assert_eq!(
        open.centres, enclosed.centres,
        "the free rule does not pick solid cells"
    );
    assert_eq!(open.free_centres, enclosed.free_centres);
    let open_under_top = open
        .open_centres
        .iter()
        .map(|c| open.world_from_box * c)
        .filter(|p| (0.35..0.65).contains(&p.z) && (1.1..1.45).contains(&p.y))
        .count();
    assert!(
        open_under_top > 50,
        "{open_under_top} open cells under the top drawn free"
    );
    // Seen from the front and above only, the space under the top is enclosed: the apron in
    // front, the box's faces elsewhere.
    let closed = HiddenSpace::of_views(&[&above, &low], &table_box(), None, ENCLOSED);
    assert!(
        under_top(&closed) > 50,
        "{} enclosed cells under the top",
        under_top(&closed)
    );
}

#[test]
fn space_under_an_overhang_that_opens_onto_occluded_space_is_not_enclosed() {
    // The table of the test above with a cabinet (another object) filling the back half of the
    // space under its top: from the +x side that half lies behind the cabinet, the front half
    // behind the side apron. The front half opens onto space that may be empty.
    let mut scene = table_with_aprons();
    scene.push(Solid {
        aabb: aabb([-0.5, 1.55, 0.0], [0.5, 1.95, 0.69]),
        is_object: false,
    });
    let [above, low, side] = table_views(&scene);
    let views = [&above, &low, &side];
    assert_eq!(
        cell_evidence(&views, &Point3::new(0.0, 1.75, 0.4), 0.03),
        CellEvidence::Occluded
    );
    let front_half = |space: &HiddenSpace| {
        let world = space.centres.iter().map(|c| space.world_from_box * c);
        world
            .filter(|p| (0.35..0.65).contains(&p.z) && (1.1..1.45).contains(&p.y))
            .count()
    };
    let all = HiddenSpace::of_views(&views, &table_box(), None, ALL);
    let enclosed = HiddenSpace::of_views(&views, &table_box(), None, ENCLOSED);
    assert!(
        front_half(&all) > 50,
        "{} hidden cells in the front half",
        front_half(&all)
    );
    assert_eq!(front_half(&enclosed), 0);
}

#[test]
fn the_cache_recomputes_when_the_box_changes_and_only_then() {
    let (scene, object_box) = slab_and_box();
    let front = render([0.0, -1.0, 0.2], 0.0, &scene);
    let mut cache = HiddenSpaceCache::default();
    let first = cache.current(&[&front], &object_box, None, ALL).clone();
    assert_eq!(first, HiddenSpace::of_views(&[&front], &object_box, None, ALL));
    let shallower = aabb([-0.2, 1.0, 0.0], [0.2, 1.2, 0.4]);
    let second = cache.current(&[&front], &shallower, None, ALL).clone();
    assert_ne!(second, first, "a new box, a new space");
    assert_eq!(second, HiddenSpace::of_views(&[&front], &shallower, None, ALL));
    assert_eq!(*cache.current(&[&front], &object_box, None, ALL), first);
}

#[test]
fn cells_no_view_saw_under_the_object_are_hidden_under_the_unseen_rule_only() {
    // A storage box (the object) the camera passes close by, looking down: the far part of its
    // top is in the frame, its front and the lower part of what lies under the top fall below
    // the frame's lower edge.
    let object_box = aabb([-0.25, 1.0, 0.0], [0.25, 1.4, 0.35]);
    let scene = [Solid {
        aabb: object_box,
        is_object: true,
    }];
    let view = render_pitched([0.0, 0.6, 1.2], 0.0, -0.3, &scene);
    let margin = 0.03;
    assert_eq!(
        cell_evidence(&[&view], &Point3::new(0.0, 1.3, 0.25), margin),
        CellEvidence::Hidden
    );
    assert_eq!(
        cell_evidence(&[&view], &Point3::new(0.0, 1.3, 0.05), margin),
        CellEvidence::Unknown
    );
    assert_eq!(
        cell_evidence(&[&view], &Point3::new(0.0, 1.05, 0.34), margin),
        CellEvidence::Unknown,
        "the front's top is out of the frame too"
    );
    let under = |rules: CellRules, y: std::ops::Range<f32>| {
        let space = HiddenSpace::of_views(&[&view], &object_box, None, rules);
        let world: Vec<Point3<f32>> = space.centres.iter().map(|c| space.world_from_box * c).collect();
        world.iter().filter(|p| p.z < 0.1 && y.contains(&p.y)).count()
    };
    let unseen_hidden = CellRules {
        unseen: UnseenCells::HiddenUnderTheObject,
        ..ENCLOSED
    };
    assert_eq!(
        under(ENCLOSED, 1.25..1.35),
        0,
        "unknown cells are not hidden by default rules"
    );
    assert!(
        under(unseen_hidden, 1.25..1.35) >= 16,
        "{} low cells under the seen top",
        under(unseen_hidden, 1.25..1.35)
    );
    assert_eq!(
        under(unseen_hidden, 1.0..1.1),
        0,
        "a column no view reached at any height has nothing of the object above it"
    );
}
