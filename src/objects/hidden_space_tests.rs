use nalgebra::Point3;

use super::*;
use crate::objects::cell_evidence::{CellEvidence, cell_evidence};
use crate::objects::view_fixtures::{Solid, aabb, bed_on_the_floor, bed_views, render, render_pitched, slab_and_box};
use crate::rng::{RngStream, seeded_rng};

/// Every hidden cell solid, free draws around the cells seen free only (the rules before open
/// cells).
const ALL: CellRules = CellRules {
    hidden: HiddenCells::All,
    free: FreeCells::Seen,
};

/// Enclosed hidden cells solid, free draws around the cells seen free only.
const ENCLOSED: CellRules = CellRules {
    hidden: HiddenCells::Enclosed,
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
fn the_floor_glimpsed_under_a_frame_opens_the_gap_and_only_the_gap() {
    let (scene, bed_box) = bed_on_the_floor();
    let [front, right, left] = bed_views(&scene);
    let views = [&front, &right, &left];
    // The bed's cells are 9.4 × 12.5 × 6.25 cm (half diagonal 8.4 cm). A cell's centre 3 cm
    // above the floor under the frame's front edge: the views see the floor behind it, nearer
    // than the half diagonal, but farther than the glimpse margin.
    let half_diagonal = 0.5 * (bed_box.extents() / CELLS_PER_AXIS as f32).norm();
    let under_the_edge = Point3::new(0.0, 1.06, 0.03);
    assert_eq!(
        cell_evidence(&views, &under_the_edge, half_diagonal),
        CellEvidence::Glimpsed
    );
    // Under the middle of the frame no view reaches: behind the frame, hidden.
    assert_eq!(
        cell_evidence(&views, &Point3::new(0.0, 2.0, 0.03), half_diagonal),
        CellEvidence::Hidden
    );
    let in_the_gap = |p: &Point3<f32>| p.z < 0.12 && (1.3..2.7).contains(&p.y) && p.x.abs() < 0.6;
    let in_the_frame = |p: &Point3<f32>| (0.15..0.47).contains(&p.z) && (1.3..2.7).contains(&p.y) && p.x.abs() < 0.6;
    let world = |space: &HiddenSpace, cells: &[Point3<f32>]| -> Vec<Point3<f32>> {
        cells.iter().map(|c| space.world_from_box * c).collect()
    };
    let open = CellRules {
        hidden: HiddenCells::Enclosed,
        free: FreeCells::SeenAndOpen,
    };
    let space = HiddenSpace::of_views(&views, &bed_box, None, open);
    let solid = world(&space, &space.centres);
    let free = [world(&space, &space.free_centres), world(&space, &space.open_centres)].concat();
    assert!(
        !solid.iter().any(in_the_gap),
        "the gap opens onto the glimpsed floor: no solid cell in it"
    );
    assert!(
        solid.iter().filter(|p| in_the_frame(p)).count() > 100,
        "the frame's inside, enclosed by its seen sides, stays solid"
    );
    assert!(!free.iter().any(in_the_frame), "no free draw inside the frame");
    assert!(
        free.iter().filter(|p| in_the_gap(p)).count() > 50,
        "the gap under the frame's middle joins the seen-free prior: {}",
        free.iter().filter(|p| in_the_gap(p)).count()
    );
    // Under the rule of the cells seen free alone, the gap's middle is left to the field.
    let seen = HiddenSpace::of_views(&views, &bed_box, None, ENCLOSED);
    assert_eq!(seen.centres, space.centres, "the free rule does not pick hidden cells");
    assert!(seen.open_centres.is_empty());
}

#[test]
fn space_seen_beside_the_object_does_not_open_its_inside() {
    // A sofa's back (the object) 50 cm high beside its arm, 20 cm high, in one box: from the
    // front and above the back's inside is hidden, and past the back's end, above the arm, the
    // views see free space. A walk from the back's inside along x ends there: the back's end
    // face, a cell's half diagonal from the cells that hold it, is not at its surface. That
    // space is beside the object, not under it: the back's inside is not drawn free.
    let object = |min, max| Solid {
        aabb: aabb(min, max),
        is_object: true,
    };
    let scene = [
        object([-0.5, 1.0, 0.3], [0.3, 1.2, 0.8]),
        object([0.3, 1.0, 0.3], [0.5, 1.2, 0.5]),
    ];
    let sofa_box = aabb([-0.5, 1.0, 0.3], [0.5, 1.2, 0.8]);
    let views = [
        render_pitched([0.0, -0.5, 1.2], 0.0, -0.4, &scene),
        render_pitched([0.0, 1.1, 2.5], 0.0, -1.45, &scene),
    ];
    let views: Vec<&ObjectView> = views.iter().collect();
    let margin = 0.5 * (sofa_box.extents() / CELLS_PER_AXIS as f32).norm();
    assert_eq!(
        cell_evidence(&views, &Point3::new(0.45, 1.1, 0.7), margin),
        CellEvidence::SeenFree,
        "above the arm"
    );
    let inside_the_back = |p: &Point3<f32>| p.x < 0.28 && p.y > 1.02 && (0.32..0.78).contains(&p.z);
    let space = HiddenSpace::of_views(
        &views,
        &sofa_box,
        None,
        CellRules {
            hidden: HiddenCells::Enclosed,
            free: FreeCells::SeenAndOpen,
        },
    );
    let all = HiddenSpace::of_views(&views, &sofa_box, None, ALL);
    let hidden_inside = all
        .centres
        .iter()
        .filter(|c| inside_the_back(&(all.world_from_box * *c)));
    assert!(hidden_inside.count() > 100, "the back's inside is hidden");
    let drawn_free = space
        .free_centres
        .iter()
        .chain(&space.open_centres)
        .filter(|c| inside_the_back(&(space.world_from_box * *c)))
        .count();
    assert_eq!(drawn_free, 0, "cells inside the back drawn free");
}

#[test]
fn the_gap_under_a_body_seen_under_its_front_edge_opens_to_its_back() {
    // A sofa (the object) on 8 cm legs against a wall: its body over [−1, 1] × [1, 1.9], 8–80
    // cm high. A low view from the front sees the floor under the front part of the body; the
    // cells there are seen free, and above them lies the body, hidden behind its front face (the
    // face itself is a row of cells away). The hidden cells under the back part open onto them:
    // the space seen under the object continues behind it, under the body.
    let object = |min, max| Solid {
        aabb: aabb(min, max),
        is_object: true,
    };
    let other = |min, max| Solid {
        aabb: aabb(min, max),
        is_object: false,
    };
    let mut scene = vec![
        object([-1.0, 1.0, 0.08], [1.0, 1.9, 0.8]),
        other([-5.0, -5.0, -0.1], [5.0, 5.0, 0.0]),
        other([-5.0, 1.95, 0.0], [5.0, 2.0, 2.0]),
    ];
    for (x, y) in [(-1.0, 1.0), (0.94, 1.0), (-1.0, 1.84), (0.94, 1.84)] {
        scene.push(object([x, y, 0.0], [x + 0.06, y + 0.06, 0.08]));
    }
    let sofa_box = aabb([-1.0, 1.0, 0.0], [1.0, 1.9, 0.8]);
    let views = [
        render_pitched([0.0, -1.2, 0.4], 0.0, -0.15, &scene),
        render_pitched([-0.8, -1.0, 0.45], -0.3, -0.15, &scene),
    ];
    let views: Vec<&ObjectView> = views.iter().collect();
    let rules = CellRules {
        hidden: HiddenCells::Enclosed,
        free: FreeCells::SeenAndOpen,
    };
    let space = HiddenSpace::of_views(&views, &sofa_box, None, rules);
    let world =
        |cells: &[Point3<f32>]| -> Vec<Point3<f32>> { cells.iter().map(|c| space.world_from_box * c).collect() };
    let (free, open, solid) = (
        world(&space.free_centres),
        world(&space.open_centres),
        world(&space.centres),
    );
    let under_the_front = |p: &&Point3<f32>| p.z < 0.05 && p.y < 1.3;
    let under_the_back = |p: &&Point3<f32>| p.z < 0.05 && p.y > 1.5;
    assert!(
        free.iter().filter(under_the_front).count() > 10,
        "the floor seen under the front edge"
    );
    assert_eq!(
        free.iter().filter(under_the_back).count(),
        0,
        "no view reaches under the back"
    );
    assert!(
        open.iter().filter(under_the_back).count() > 20,
        "the gap under the back joins the seen-free prior: {} open cells there",
        open.iter().filter(under_the_back).count()
    );
    assert!(!solid.iter().any(|p| p.z < 0.05), "no solid cell in the gap");
    assert!(
        !free.iter().chain(&open).any(|p| p.z > 0.1 && p.y > 1.1 && p.y < 1.85),
        "no free draw inside the body"
    );
    assert!(
        solid.iter().filter(|p| p.z > 0.1).count() > 100,
        "the body's inside stays solid"
    );
}
