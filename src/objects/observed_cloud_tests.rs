//! Tests of [`super`]: voxels and centroids, pixel runs, the views' votes.

use super::*;

#[test]
fn points_in_one_voxel_merge_into_their_centroid() {
    let mut cloud = ObservedCloud::new(0.01);
    cloud.add_point(&Point3::new(0.001, 0.002, 0.003));
    cloud.add_point(&Point3::new(0.003, 0.004, 0.005));
    cloud.add_point(&Point3::new(0.5, 0.5, 0.5));
    assert_eq!(cloud.len(), 2);
    assert_eq!(cloud.points_added(), 3);
    let points = cloud.points();
    assert!(
        points
            .iter()
            .any(|p| (p - Point3::new(0.002, 0.003, 0.004)).norm() < 1e-6)
    );
}

#[test]
fn the_fast_floor_matches_floor() {
    for x in [-2.5_f32, -2.0, -1.0, -0.5, -0.0, 0.0, 0.25, 1.0, 1.75, 1e6, -1e6 - 0.5] {
        assert_eq!(floor_to_i64(x), x.floor() as i64, "floor of {x}");
    }
}

#[test]
fn pixel_runs_give_the_same_cloud_as_single_points() {
    let frame = RgbdFrame {
        world_from_camera: nalgebra::Isometry3::translation(0.1, -0.2, 0.3),
        depth_m: (0..32)
            .map(|i| if i % 5 == 0 { 0.0 } else { 1.0 + 0.01 * i as f32 })
            .collect(),
        ..wall_frame(|_| InstanceLabel::Background, |_| 1.0)
    };
    let pixels: Vec<u32> = (0..32).collect();
    let mut by_pixels = ObservedCloud::new(0.01);
    let added = by_pixels.add_pixels(&frame, &pixels);
    let mut by_points = ObservedCloud::new(0.01);
    for &i in &pixels {
        if let Some(p) = frame.point_in_world(i as usize) {
            by_points.add_point(&p);
        }
    }
    assert_eq!(added, 25, "every fifth pixel has no depth");
    assert_eq!(by_pixels.points_added(), by_points.points_added());
    assert_eq!(by_pixels.len(), by_points.len(), "same voxels either way");
    for (a, b) in by_pixels.points().iter().zip(by_points.points()) {
        assert!((a - b).norm() < 1e-6, "same centroids either way");
    }
}

#[test]
fn negative_coordinates_get_their_own_voxels() {
    let mut cloud = ObservedCloud::new(0.1);
    cloud.add_point(&Point3::new(-0.05, 0.0, 0.0));
    cloud.add_point(&Point3::new(0.05, 0.0, 0.0));
    assert_eq!(cloud.len(), 2, "the grid is split at 0, not rounded towards it");
}

#[test]
fn the_point_order_does_not_depend_on_insertion_order() {
    let pts: Vec<Point3<f32>> = (0..50)
        .map(|i| Point3::new(i as f32 * 0.03, (i % 7) as f32 * 0.1, 0.0))
        .collect();
    let mut reversed = pts.clone();
    reversed.reverse();
    assert_eq!(voxel_downsample(&pts, 0.02), voxel_downsample(&reversed, 0.02));
}

/// An 8×4 frame at the origin looking down +z at a wall 1 m away (a pixel every 2 cm), labelled
/// `label(column)`, with depth `depth(column)`.
fn wall_frame(label: impl Fn(u32) -> InstanceLabel, depth: impl Fn(u32) -> f32) -> RgbdFrame {
    use crate::ids::{ClassId, FrameIndex};
    use crate::sensor::frame::{CameraIntrinsics, InstanceMask};
    let (width, height) = (8u32, 4u32);
    let n = (width * height) as usize;
    RgbdFrame {
        index: FrameIndex(0),
        world_from_camera: nalgebra::Isometry3::identity(),
        intrinsics: CameraIntrinsics {
            width,
            height,
            fx: 50.0,
            fy: 50.0,
            cx: 3.5,
            cy: 1.5,
        },
        rgb: vec![[0; 3]; n],
        depth_m: (0..n as u32).map(|i| depth(i % width)).collect(),
        instances: InstanceMask::from_labels((0..n as u32).map(|i| label(i % width))),
        classes: vec![ClassId(0); n],
    }
}

#[test]
fn voxels_more_views_see_as_something_else_are_left_out_and_unsure_or_hidden_pixels_do_not_vote() {
    let owner = ObjectId(4);
    let object_to = |last: u32| {
        move |u: u32| {
            if u <= last {
                InstanceLabel::Object(owner)
            } else {
                InstanceLabel::Background
            }
        }
    };
    let at_1m = |_: u32| 1.0;
    let pixels_of = |f: &RgbdFrame| -> Vec<u32> {
        (0..f.instances.len() as u32)
            .filter(|&i| f.instances.object_at(i as usize) == Some(owner))
            .collect()
    };
    let view = |cloud: &mut ObservedCloud, f: &RgbdFrame, votes: VoxelVotes| {
        cloud.add_view(f, &pixels_of(f), owner, votes, 0.0);
    };
    // A mask that bled over columns 4–7 once, then views that see them as background.
    let bled = wall_frame(object_to(7), at_1m);
    let exact = wall_frame(object_to(3), at_1m);
    let mut cloud = ObservedCloud::new(0.01);
    let mut unvoted = ObservedCloud::new(0.01);
    view(&mut cloud, &bled, VoxelVotes::ByViews);
    view(&mut unvoted, &bled, VoxelVotes::Off);
    assert_eq!(
        cloud.points().len(),
        32,
        "one voxel per pixel, every one the owner's so far"
    );
    view(&mut cloud, &exact, VoxelVotes::ByViews);
    assert_eq!(cloud.points().len(), 32, "one view each way: not contested");
    // Views that say nothing: the columns unsure, or something 30 cm nearer hiding them.
    let unsure = wall_frame(
        |u| {
            if u <= 3 {
                InstanceLabel::Object(owner)
            } else {
                InstanceLabel::Unsure
            }
        },
        at_1m,
    );
    let hidden = wall_frame(object_to(3), |u| if u <= 3 { 1.0 } else { 0.7 });
    view(&mut cloud, &unsure, VoxelVotes::ByViews);
    view(&mut cloud, &hidden, VoxelVotes::ByViews);
    assert_eq!(cloud.points().len(), 32, "unsure and hidden pixels do not vote");
    for _ in 0..3 {
        view(&mut cloud, &exact, VoxelVotes::ByViews);
        assert_eq!(
            cloud.points().len(),
            32,
            "at most four views elsewhere to the owner's one"
        );
    }
    view(&mut cloud, &exact, VoxelVotes::ByViews);
    let kept = cloud.points();
    assert_eq!(kept.len(), 16, "the bled columns are contested: {kept:?}");
    assert!(
        kept.iter().all(|p| p.x < 0.0),
        "only columns 0–3 (left of the centre) stay"
    );
    assert_eq!(cloud.len(), 32, "contested voxels stay in the grid");
    for f in [&exact, &unsure, &hidden, &exact, &exact, &exact, &exact] {
        view(&mut unvoted, f, VoxelVotes::Off);
    }
    assert_eq!(unvoted.points().len(), 32, "without votes every voxel counts");
}

#[test]
fn the_point_spacing_is_the_mean_depth_over_the_focal_length() {
    // Half the wall at 2 m, half at 3 m, f = 50 px: points 4 cm and 6 cm apart.
    let frame = wall_frame(|_| InstanceLabel::Background, |u| if u < 4 { 2.0 } else { 3.0 });
    let mut cloud = ObservedCloud::new(0.01);
    assert_eq!(cloud.point_spacing_m(), None, "nothing seen yet");
    cloud.add_pixels(&frame, &(0..32).collect::<Vec<u32>>());
    let spacing = cloud.point_spacing_m().expect("seen");
    assert!((spacing - 0.05).abs() < 1e-6, "spacing {spacing}");
    let mut merged = ObservedCloud::new(0.01);
    merged.absorb(&cloud);
    assert_eq!(
        merged.point_spacing_m(),
        Some(spacing),
        "a merged cloud keeps its spacing"
    );
}
