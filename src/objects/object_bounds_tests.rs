//! Tests of [`super`]: mirror fits, shape points and the object bounds.

use nalgebra::Point3;

use super::*;

#[test]
fn the_second_plane_is_used_only_when_asked_and_only_beside_a_first() {
    let (first, second) = (MirrorPlane::vertical(0.0, 0.5), MirrorPlane::vertical(1.5, -0.2));
    let fit = MirrorFit {
        plane: Some(first),
        second: Some(second),
        fitted_at_points: 100,
    };
    assert_eq!(fit.planes(MirrorPlanes::BothWhenFound), vec![first, second]);
    assert_eq!(fit.planes(MirrorPlanes::Best), vec![first]);
    let alone = MirrorFit { plane: None, ..fit };
    assert!(alone.planes(MirrorPlanes::BothWhenFound).is_empty());
    let one = MirrorFit { second: None, ..fit };
    assert_eq!(one.planes(MirrorPlanes::BothWhenFound), vec![first]);
}

#[test]
fn a_box_goes_stale_only_after_the_configured_growth() {
    assert!(!box_is_stale(None, 3, 0.1), "too few points for a first box");
    assert!(box_is_stale(None, 10, 0.1));
    assert!(!box_is_stale(Some(100), 110, 0.1));
    assert!(box_is_stale(Some(100), 111, 0.1));
}

#[test]
fn voxels_with_too_few_points_are_left_out_of_the_box_unless_too_few_remain() {
    // A 40 cm square seen five times over, and three stray points a metre off.
    let mut cloud = ObservedCloud::new(0.01);
    for _ in 0..5 {
        for i in 0..40 {
            for j in 0..40 {
                cloud.add_point(&Point3::new(0.005 + i as f32 * 0.01, 0.005 + j as f32 * 0.01, 0.5));
            }
        }
    }
    for k in 0..3 {
        cloud.add_point(&Point3::new(1.5 + k as f32 * 0.1, 0.2, 0.5));
    }
    let all = fit_object_box(&cloud, &ObjectConfig::default()).expect("enough points");
    assert!(
        all.extents().max() > 1.0,
        "the stray points stretch it: {:?}",
        all.extents()
    );
    let cfg = ObjectConfig {
        box_min_voxel_points: 3,
        ..ObjectConfig::default()
    };
    let kept = fit_object_box(&cloud, &cfg).expect("enough points");
    assert!(kept.extents().max() < 0.6, "the square alone: {:?}", kept.extents());
    // A cloud seen once has no voxel of three points: every voxel counts.
    let mut once = ObservedCloud::new(0.01);
    for i in 0..20 {
        once.add_point(&Point3::new(i as f32 * 0.02, 0.0, 0.5));
    }
    assert!(fit_object_box(&once, &cfg).is_ok());
}

#[test]
fn a_small_flat_object_gets_the_minimum_extent() {
    let mut cloud = ObservedCloud::new(0.01);
    for i in 0..20 {
        for j in 0..20 {
            cloud.add_point(&Point3::new(i as f32 * 0.002, j as f32 * 0.002, 0.5));
        }
    }
    let fitted = fit_object_box(&cloud, &ObjectConfig::default()).expect("enough points");
    assert!(fitted.extents().min() >= 0.1 - 1e-6, "extents {:?}", fitted.extents());
}

#[test]
fn only_stale_boxes_are_refitted_and_every_grown_one_once_the_stream_ends() {
    let mut cloud = ObservedCloud::new(0.01);
    for i in 0..20 {
        for j in 0..20 {
            cloud.add_point(&Point3::new(i as f32 * 0.02, j as f32 * 0.02, (i + j) as f32 * 0.01));
        }
    }
    let n = cloud.len();
    let cfg = ObjectConfig::default();
    let objects = || {
        [
            ("new", None, None, MirrorSearch::Search, &cloud),
            ("fresh", Some(n), None, MirrorSearch::Search, &cloud),
            ("grown", Some(n - 1), None, MirrorSearch::Search, &cloud),
        ]
    };
    let streaming = refit_stale_boxes(objects(), StreamPhase::Streaming, &cfg);
    let keys: Vec<&str> = streaming.iter().map(|(k, _)| *k).collect();
    assert_eq!(keys, vec!["new"], "one more point is less than the growth");
    let fitted = streaming[0].1.as_ref().expect("enough points");
    assert_eq!(
        (fitted.oriented_box, fitted.fitted_at_points),
        (fit_object_box(&cloud, &cfg).expect("enough points"), n)
    );
    let ended = refit_stale_boxes(objects(), StreamPhase::Ended, &cfg);
    let keys: Vec<&str> = ended.iter().map(|(k, _)| *k).collect();
    assert_eq!(keys, vec!["new", "grown"]);
    let few = ObservedCloud::new(0.01);
    let none = refit_stale_boxes(
        [("empty", Some(0), None, MirrorSearch::Search, &few)],
        StreamPhase::Ended,
        &cfg,
    );
    assert!(none.is_empty(), "a cloud that did not grow keeps its box");
}

#[test]
fn the_mirror_plane_is_searched_again_only_after_its_own_growth_and_at_the_end() {
    // Two posts 0.6 m apart: mirror-symmetric about x = 0.3.
    let mut cloud = ObservedCloud::new(0.01);
    for x in [0.0, 0.6] {
        for k in 0..60 {
            for a in 0..8 {
                let t = a as f32 * std::f32::consts::TAU / 8.0;
                cloud.add_point(&Point3::new(x + 0.04 * t.cos(), 0.04 * t.sin(), k as f32 * 0.02));
            }
        }
    }
    let n = cloud.len();
    let cfg = ObjectConfig::default();
    let fitted = fit_object_bounds(&cloud, MirrorStep::Search, &cfg).expect("enough points");
    let plane = fitted.mirror.and_then(|m| m.plane).expect("two posts are symmetric");
    assert!(
        plane.normal.x.abs() > 0.999 && (plane.distance(&Point3::new(0.3, 0.0, 0.0))).abs() < 0.01,
        "{plane:?}"
    );
    // A remembered search (here: none found) is kept while the cloud grew by less than the
    // growth, though the box is refitted.
    let remembered = MirrorFit {
        plane: None,
        second: None,
        fitted_at_points: (n as f32 / (1.0 + MIRROR_REFRESH_GROWTH)) as usize + 1,
    };
    let refit = |mirror, phase, search| refit_stale_boxes([("a", Some(1), Some(mirror), search, &cloud)], phase, &cfg);
    let streaming = refit(remembered, StreamPhase::Streaming, MirrorSearch::Search);
    assert_eq!(streaming[0].1.as_ref().expect("fitted").mirror, Some(remembered));
    let ended = refit(remembered, StreamPhase::Ended, MirrorSearch::Search);
    assert_eq!(
        ended[0].1.as_ref().expect("fitted").mirror,
        fitted.mirror,
        "searched again at the end"
    );
    let older = MirrorFit {
        fitted_at_points: remembered.fitted_at_points - 2,
        ..remembered
    };
    let grown = refit(older, StreamPhase::Streaming, MirrorSearch::Search);
    assert_eq!(
        grown[0].1.as_ref().expect("fitted").mirror,
        fitted.mirror,
        "grown past the growth"
    );
    assert_eq!(MirrorSearch::for_object(24, 1), MirrorSearch::Search);
    assert_eq!(MirrorSearch::for_object(0, 1), MirrorSearch::Skip);
    assert_eq!(
        MirrorSearch::for_object(24, 2),
        MirrorSearch::Skip,
        "an object with a twin"
    );
    let skipped = refit(older, StreamPhase::Ended, MirrorSearch::for_object(0, 1));
    assert_eq!(
        skipped[0].1.as_ref().expect("fitted").mirror,
        Some(older),
        "no search without mirrored rays"
    );
    let twin = refit(older, StreamPhase::Ended, MirrorSearch::for_object(24, 3));
    assert_eq!(
        twin[0].1.as_ref().expect("fitted").mirror,
        Some(older),
        "no search for an object with twins"
    );
}
