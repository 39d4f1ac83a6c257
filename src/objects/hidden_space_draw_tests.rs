//! Tests of the prior draws of [`super`]: points in the hidden cells, and free draws that stay
//! out of the object.

use nalgebra::Point3;

use super::tests::{ALL, ENCLOSED};
use super::*;
use crate::objects::view_fixtures::{Solid, aabb, render, slab_and_box};
use crate::rng::{RngStream, seeded_rng};

#[test]
fn drawn_points_lie_in_hidden_cells() {
    let (scene, object_box) = slab_and_box();
    let front = render([0.0, -1.0, 0.2], 0.0, &scene);
    let space = HiddenSpace::of_views(&[&front], &object_box, None, ALL);
    let mut rng = seeded_rng(3, RngStream::Mapper);
    for _ in 0..200 {
        let p = space.draw(&mut rng).expect("hidden cells");
        assert!(object_box.contains(&p, 1e-5), "{p} outside the box");
        assert!(p.y > 1.0, "{p} in front of the slab's face");
    }
}

#[test]
fn draws_around_cells_seen_free_stay_out_of_the_object() {
    // A block (the object) with its front face at y = 1 in a box of 10 cm cells, the first row
    // of cells centred 2 cm before that face. A view from the side sees those centres free (its
    // rays run along the face), but a quarter cell around them reaches 0.5 cm into the block —
    // as a quarter of a lamp's 2.75 cm cell beside its 2.6 cm pole reaches into the pole. Only
    // points a view sees free are drawn.
    let scene = [Solid {
        aabb: aabb([-0.8, 1.0, 0.0], [0.8, 1.6, 0.8]),
        is_object: true,
    }];
    let views = [
        render([0.0, -1.0, 0.4], 0.0, &scene),
        render([2.0, 1.0, 0.4], -std::f32::consts::FRAC_PI_2, &scene),
    ];
    let views: Vec<&ObjectView> = views.iter().collect();
    let object_box = aabb([-0.8, 0.93, 0.0], [0.8, 2.53, 0.8]);
    let space = HiddenSpace::of_views(&views, &object_box, None, ENCLOSED);
    let first_row = |p: &Point3<f32>| (p.y - 0.98).abs() < 1e-3;
    let world = |c: &Point3<f32>| space.world_from_box * c;
    assert!(
        space.free_centres.iter().map(world).filter(first_row).count() > 10,
        "the side view sees the first row free"
    );
    let in_block = |p: &Point3<f32>| (1.0..1.6).contains(&p.y) && p.x.abs() < 0.8 && (0.0..0.8).contains(&p.z);
    let mut rng = seeded_rng(5, RngStream::Mapper);
    let inside = (0..20_000)
        .filter(|_| in_block(&space.draw_free(&views, &mut rng).expect("cells seen free")))
        .count();
    assert_eq!(inside, 0, "free draws inside the block");
    // Unchecked, the same draws reach into it.
    let unchecked = (0..20_000)
        .filter(|_| {
            let p = space.draw_around(&space.free_centres, FREE_DRAW_SPREAD, &mut rng);
            in_block(&p.expect("cells seen free"))
        })
        .count();
    assert!(unchecked > 100, "{unchecked} unchecked draws in the block");
    // The same cells as open cells (no view saw into them): a point is kept unless a view sees
    // the block's surface within 2 cm of it — the front view does, for every point in the block.
    let as_open = HiddenSpace {
        open_centres: space.free_centres.clone(),
        free_centres: Vec::new(),
        ..space.clone()
    };
    let near_face =
        |p: &Point3<f32>| in_block(p) || ((0.99..1.0).contains(&p.y) && p.x.abs() < 0.8 && (0.0..0.8).contains(&p.z));
    let open_inside = (0..20_000)
        .filter(|_| near_face(&as_open.draw_free(&views, &mut rng).expect("open cells")))
        .count();
    assert_eq!(
        open_inside, 0,
        "open draws in the block or within 1 cm of its seen face"
    );
    let open_unchecked = (0..20_000)
        .filter(|_| {
            let p = as_open.draw_around(&as_open.open_centres, FREE_DRAW_SPREAD, &mut rng);
            near_face(&p.expect("open cells"))
        })
        .count();
    assert!(
        open_unchecked > 100,
        "{open_unchecked} unchecked open draws near the face"
    );
}
