//! An object's shape points ([`shape_points`]) leave out what a segmenter added to its masks in
//! a few frames: a speck apart from it, and a neighbour most views saw as the neighbour.

use nalgebra::Point3;

use super::*;
use crate::objects::observed_cloud::ViewVotes;

/// Votes of a voxel seen as the object's in `own` views and as something else in `elsewhere`.
fn votes(own: u32, elsewhere: u32) -> ViewVotes {
    ViewVotes { own, elsewhere }
}

/// A cabinet's front face and top (x from −0.4 to 0.4, y from −0.25 to 0.25, z up to 1.2) on a
/// 1 cm grid, every voxel seen as the cabinet's in 8 views.
fn cabinet() -> ObservedCloud {
    let mut cloud = ObservedCloud::new(0.01);
    for j in 0..50 {
        let y = -0.245 + j as f32 * 0.01;
        for k in 0..120 {
            cloud.add_voted_point(&Point3::new(-0.4, y, 0.005 + k as f32 * 0.01), votes(8, 0));
        }
        for i in 0..80 {
            cloud.add_voted_point(&Point3::new(-0.395 + i as f32 * 0.01, y, 1.2), votes(8, 0));
        }
    }
    cloud
}

/// A panel of 50 × 20 voxels in the plane y = 0, x from `x0` on, z from 0.3 to 0.5, each with
/// `votes`.
fn add_panel(cloud: &mut ObservedCloud, x0: f32, votes: ViewVotes) {
    for i in 0..50 {
        for k in 0..20 {
            cloud.add_voted_point(&Point3::new(x0 + i as f32 * 0.01, 0.0, 0.3 + k as f32 * 0.01), votes);
        }
    }
}

/// The fitted box's x range under `shape_voxels`, metres.
fn x_range_under(cloud: &ObservedCloud, shape_voxels: ShapeVoxels) -> (f32, f32) {
    let cfg = ObjectConfig {
        box_fit: BoxFit::Upright,
        shape_voxels,
        ..ObjectConfig::default()
    };
    let fitted = fit_object_box(cloud, &cfg).expect("a box");
    let xs = fitted.corners().map(|c| c.x);
    (
        xs.iter().copied().fold(f32::MAX, f32::min),
        xs.iter().copied().fold(f32::MIN, f32::max),
    )
}

/// The fitted box's x range under a segmenter's rule, metres.
fn x_range(cloud: &ObservedCloud) -> (f32, f32) {
    x_range_under(cloud, ShapeVoxels::MostlyOwnMainParts)
}

#[test]
fn a_speck_metres_away_seen_in_one_view_does_not_stretch_the_box() {
    let mut cloud = cabinet();
    // A wall 3 m behind, 40 voxels that one bled mask gave the cabinet and no other view saw.
    for i in 0..40 {
        cloud.add_voted_point(&Point3::new(3.0, -0.2 + i as f32 * 0.01, 0.5), votes(1, 0));
    }
    let (_, uncontested) = x_range_under(&cloud, ShapeVoxels::Uncontested);
    assert!(
        uncontested > 2.9,
        "exact masks' rule keeps the speck: x to {uncontested}"
    );
    let (lo, hi) = x_range(&cloud);
    assert!(
        (lo + 0.4).abs() < 0.015 && (hi - 0.4).abs() < 0.015,
        "x from {lo} to {hi}"
    );
}

#[test]
fn a_neighbour_most_views_saw_as_its_own_is_left_out_even_when_it_touches() {
    let mut cloud = cabinet();
    // A chair touching the cabinet's side (x from 0.4 to 0.9), 1 000 voxels: merged into the
    // cabinet's mask in one frame of four (not contested: 3 to 1 is under CONTESTED_RATIO).
    add_panel(&mut cloud, 0.405, votes(1, 3));
    let (_, uncontested) = x_range_under(&cloud, ShapeVoxels::Uncontested);
    assert!(uncontested > 0.85, "not contested: x to {uncontested}");
    let (_, hi) = x_range(&cloud);
    assert!((hi - 0.4).abs() < 0.015, "x to {hi}");
}

#[test]
fn a_part_apart_that_holds_a_large_share_stays() {
    let mut cloud = cabinet();
    // A second piece 30 cm beside it (a lamp's shade beyond the pole a camera lost): 1 000 of
    // 11 000 voxels, seen as the object's in every view.
    add_panel(&mut cloud, 0.7, votes(8, 0));
    let (_, hi) = x_range(&cloud);
    assert!((hi - 1.19).abs() < 0.015, "x to {hi}");
}

#[test]
fn a_sparsely_sampled_object_keeps_its_whole_shape() {
    // A chair's back (x from −0.2 to 0.2, z from 0 to 0.9) that a camera of few pixels sampled
    // every 2 cm, one point per voxel, and a strip at the seat's height that many views saw,
    // 4 points per voxel: the count of 3 points per voxel keeps only the strip.
    let mut cloud = ObservedCloud::new(0.01);
    cloud.set_point_spacing(0.02);
    for i in 0..21 {
        for k in 0..46 {
            let p = Point3::new(-0.2 + i as f32 * 0.02, 0.0, 0.005 + k as f32 * 0.02);
            cloud.add_voted_point(&p, votes(2, 0));
            if (22..24).contains(&k) {
                for _ in 0..3 {
                    cloud.add_voted_point(&p, votes(0, 0));
                }
            }
        }
    }
    let cfg = ObjectConfig {
        box_fit: BoxFit::Upright,
        box_min_voxel_points: 3,
        shape_voxels: ShapeVoxels::MostlyOwnMainParts,
        ..ObjectConfig::default()
    };
    let dense_only = cloud.points_of_voxels_with(3);
    assert_eq!(dense_only.len(), 42, "the strip alone holds 3 points a voxel");
    let z_range = |cloud: &ObservedCloud| {
        let zs = fit_object_box(cloud, &cfg).expect("a box").corners().map(|c| c.z);
        (
            zs.iter().copied().fold(f32::MAX, f32::min),
            zs.iter().copied().fold(f32::MIN, f32::max),
        )
    };
    let (lo, hi) = z_range(&cloud);
    assert!(lo < 0.01 && hi > 0.89, "z from {lo} to {hi}");
    // Sampled every 5 mm (a view puts 4 points in a voxel), the count stands.
    cloud.set_point_spacing(0.005);
    let (lo, hi) = z_range(&cloud);
    assert!(lo > 0.4 && hi < 0.51, "z from {lo} to {hi}");
}
