//! A round object's second mirror plane (`objects.round_objects`).

use nalgebra::Point3;

use super::*;
use crate::geometry::round_axis::tests::lamp_seen_from_minus_x;

/// The lamp of [`lamp_seen_from_minus_x`] at (2.7, 1.5), a ring every centimetre, a point every 5°.
fn lamp_seen_from_minus_x_cloud() -> ObservedCloud {
    let mut cloud = ObservedCloud::new(0.01);
    for p in lamp_seen_from_minus_x(2.7, 1.5, 0.01, 5.0) {
        cloud.add_point(&p);
    }
    cloud
}

#[test]
fn a_round_object_seen_from_one_side_gets_a_second_plane_through_its_axis_unless_off() {
    let cloud = lamp_seen_from_minus_x_cloud();
    let cfg = ObjectConfig {
        box_fit: BoxFit::UprightOnFaces,
        ..ObjectConfig::default()
    };
    let fit = |round_objects| {
        let cfg = ObjectConfig {
            round_objects,
            ..cfg.clone()
        };
        fit_object_bounds(&cloud, MirrorStep::Search, &cfg)
            .expect("bounds")
            .mirror
            .expect("searched")
    };
    let across = fit(RoundObjects::AcrossAxis);
    let (first, second) = (
        across.plane.expect("a first plane"),
        across.second.expect("a second plane"),
    );
    let pole = Point3::new(2.7, 1.5, 1.0);
    assert!(
        first.distance(&pole).abs() < 0.01,
        "the first plane runs through the pole"
    );
    assert!(
        second.distance(&pole).abs() < 0.01,
        "so does the second: {}",
        second.distance(&pole)
    );
    assert!(first.normal.dot(&second.normal).abs() < 0.02, "at right angles");
    let off = fit(RoundObjects::Off);
    assert_eq!(off.plane, across.plane);
    assert_eq!(off.second, None, "no plane matches across the views");
}
