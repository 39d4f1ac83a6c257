//! Tests of [`super`]'s ring of cells beyond the box ([`FreeCells::SeenOpenAndBeyond`]).

use nalgebra::Point3;

use super::*;
use crate::objects::view_fixtures::{Solid, aabb, render_pitched};
use crate::rng::{RngStream, seeded_rng};

/// A sofa (the object, 1.6 × 0.9 × 0.8 m) with its back 7 cm from a wall, on the floor, seen
/// from its front and from its +x end, both from above; its box is the sofa's.
fn sofa_against_a_wall() -> (Vec<ObjectView>, OrientedBox) {
    let other = |min, max| Solid {
        aabb: aabb(min, max),
        is_object: false,
    };
    let scene = [
        Solid {
            aabb: aabb([-0.8, 2.0, 0.0], [0.8, 2.9, 0.8]),
            is_object: true,
        },
        other([-5.0, 2.97, 0.0], [5.0, 3.1, 3.0]),
        other([-5.0, -5.0, -0.1], [5.0, 5.0, 0.0]),
    ];
    let views = vec![
        render_pitched([0.0, 0.4, 1.5], 0.0, -0.5, &scene),
        render_pitched([2.6, 2.45, 1.4], -std::f32::consts::FRAC_PI_2, -0.4, &scene),
    ];
    (views, aabb([-0.8, 2.0, 0.0], [0.8, 2.9, 0.8]))
}

#[test]
fn the_hidden_gap_behind_a_sofa_beyond_its_box_is_drawn_empty_unless_its_mirror_image_holds_it() {
    let (views, sofa_box) = sofa_against_a_wall();
    let views: Vec<&ObjectView> = views.iter().collect();
    let rules = CellRules {
        hidden: HiddenCells::Enclosed,
        unseen: UnseenCells::Unknown,
        free: FreeCells::SeenOpenAndBeyond,
    };
    let space = HiddenSpace::of_views(&views, &sofa_box, None, rules);
    let world: Vec<Point3<f32>> = space.beyond_centres.iter().map(|c| space.world_from_box * c).collect();
    let in_the_gap = |p: &&Point3<f32>| p.y > 2.9 && p.y < 2.97 && p.z < 0.8 && p.x.abs() < 0.8;
    assert!(
        world.iter().filter(in_the_gap).count() > 50,
        "the gap between the back and the wall: {} of {}",
        world.iter().filter(in_the_gap).count(),
        world.len()
    );
    assert!(
        world.iter().all(|p| !sofa_box.contains(p, 0.0)),
        "ring cells lie beyond the box"
    );
    // Before the front, the views see the sofa's surface (the two corner cells by the floor
    // beyond its ends are glimpsed: the floor just behind them).
    let before: Vec<_> = world.iter().filter(|p| p.y < 2.0 && p.x.abs() < 0.8).collect();
    assert!(
        before.is_empty(),
        "none before the seen front (at its surface): {before:?}"
    );
    // Past the +x end and above the top the views saw free (but by the floor, glimpsed).
    let past: Vec<_> = world
        .iter()
        .filter(|p| (p.x > 0.8 || p.z > 0.8) && p.z > 0.05)
        .collect();
    assert!(
        past.is_empty(),
        "none past the seen end or above the seen top: {past:?}"
    );
    assert!(
        world.iter().all(|p| p.z > 0.0),
        "none under the box (the support prior's)"
    );
    // Free draws come from the ring alone (no cell in the box is seen free or open), each within a
    // quarter cell of its centre: never inside the sofa, and in the gap as often as its cells are
    // of the ring's (227 of 478 here; 945 of 2 000 draws).
    let mut rng = seeded_rng(5, RngStream::Mapper);
    assert_eq!((space.free_centres.len(), space.open_centres.len()), (0, 0));
    let draws: Vec<Point3<f32>> = (0..2000)
        .map(|_| space.draw_free(&views, &mut rng).expect("a draw"))
        .collect();
    assert!(
        draws.iter().all(|p| !sofa_box.contains(p, 0.0)),
        "no free draw inside the sofa"
    );
    let near_the_gap = |p: &&Point3<f32>| p.y > 2.89 && p.y < 2.98 && p.z < 0.82 && p.x.abs() < 0.82;
    let share = draws.iter().filter(near_the_gap).count() as f32 / draws.len() as f32;
    let gap_share = world.iter().filter(in_the_gap).count() as f32 / world.len() as f32;
    assert!(
        (share - gap_share).abs() < 0.03,
        "draws in the gap {share:.3}, its cells' share of the ring {gap_share:.3}"
    );
    // A plane 2 cm before the back (its normal along y): the back's mirror image continues
    // into the gap, which is left to the mirrored rays.
    let plane = MirrorPlane {
        normal: nalgebra::Vector3::y(),
        offset: 2.88,
    };
    let mirrored = HiddenSpace::of_views(&views, &sofa_box, Some(&plane), rules);
    let mirrored_world: Vec<Point3<f32>> = mirrored
        .beyond_centres
        .iter()
        .map(|c| mirrored.world_from_box * c)
        .collect();
    assert_eq!(mirrored_world.iter().filter(in_the_gap).count(), 0);
    assert!(mirrored_world.len() < world.len());
    // Under the rule of seen and open cells, no ring cell.
    let open = CellRules {
        free: FreeCells::SeenAndOpen,
        ..rules
    };
    assert!(
        HiddenSpace::of_views(&views, &sofa_box, None, open)
            .beyond_centres
            .is_empty()
    );
}
