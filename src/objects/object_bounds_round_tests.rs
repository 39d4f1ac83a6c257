//! A round object's second mirror plane (`objects.round_objects`).

use nalgebra::Point3;

use super::*;

/// A lamp at (2.7, 1.5) seen from −x: the −x half of its shade (radius 0.21 → 0.09 m over
/// 1.3–1.6 m), of its pole (1.2 cm) and of its base's rim (0.16 m, 5 cm tall), every 1 cm of
/// height and 5° of turn.
fn lamp_seen_from_minus_x() -> ObservedCloud {
    let mut cloud = ObservedCloud::new(0.01);
    let mut ring = |radius: f32, z: f32| {
        for k in 0..=36 {
            let a = (90.0 + 5.0 * k as f32).to_radians();
            cloud.add_point(&Point3::new(2.7 + radius * a.cos(), 1.5 + radius * a.sin(), z));
        }
    };
    for i in 0..=30 {
        let z = 1.3 + 0.01 * i as f32;
        ring(0.21 - 0.12 * (z - 1.3) / 0.3, z);
    }
    for i in 0..125 {
        ring(0.012, 0.055 + 0.01 * i as f32);
    }
    for i in 0..5 {
        ring(0.16, 0.005 + 0.01 * i as f32);
    }
    cloud
}

#[test]
fn a_round_object_seen_from_one_side_gets_a_second_plane_through_its_axis_unless_off() {
    let cloud = lamp_seen_from_minus_x();
    let cfg = ObjectConfig {
        box_fit: Some(BoxFit::UprightOnFaces),
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
