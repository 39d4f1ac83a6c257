//! Tests of the open cells: hidden cells that continue space seen under the object (the gap
//! under a bed's frame, under a sofa's body on legs) and those that do not (inside a sofa's back).

use nalgebra::Point3;

use super::tests::{ALL, ENCLOSED};
use super::*;
use crate::objects::cell_evidence::{CellEvidence, cell_evidence};
use crate::objects::view_fixtures::{Solid, aabb, bed_on_the_floor, bed_views, render_pitched};

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
        unseen: UnseenCells::Unknown,
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
            unseen: UnseenCells::Unknown,
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
        unseen: UnseenCells::Unknown,
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
