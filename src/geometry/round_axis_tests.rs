//! Tests of [`super`]: the axis of a round object seen from one side, and none for a box.

use nalgebra::{Point3, Vector3};

use super::*;

/// A lamp at (`cx`, `cy`) seen from −x: the half of its shade (a cone, radius 0.21 → 0.09 m over
/// 1.3–1.6 m), its pole (radius 1.2 cm) and its base's rim (radius 0.16 m, 5 cm tall) facing −x,
/// a ring every `dz` metres of height with a point every `step_deg` degrees.
pub(crate) fn lamp_seen_from_minus_x(cx: f32, cy: f32, dz: f32, step_deg: f32) -> Vec<Point3<f32>> {
    let mut points = Vec::new();
    let mut ring = |radius: f32, z: f32| {
        for k in 0..=(180.0 / step_deg) as usize {
            let a = (90.0 + step_deg * k as f32).to_radians(); // 90°..270°: the −x half
            points.push(Point3::new(cx + radius * a.cos(), cy + radius * a.sin(), z));
        }
    };
    let rings = |from: f32, to: f32| (0..=((to - from) / dz).round() as usize).map(move |i| from + dz * i as f32);
    for z in rings(1.3, 1.6) {
        ring(0.21 - 0.12 * (z - 1.3) / 0.3, z);
    }
    for z in rings(0.06, 1.24) {
        ring(0.012, z);
    }
    for z in rings(0.0, 0.04) {
        ring(0.16, z);
    }
    points
}

#[test]
fn a_lamp_seen_from_one_side_gets_the_plane_across_the_views_through_its_pole() {
    let (cx, cy) = (2.7, 1.5);
    let points = lamp_seen_from_minus_x(cx, cy, 0.02, 10.0);
    // The plane along the views: normal y, through the pole.
    let first = MirrorPlane {
        normal: Vector3::y(),
        offset: cy,
    };
    let second = plane_across_axis(&points, &first).expect("round");
    assert!(second.normal.dot(&first.normal).abs() < 1e-6, "at right angles");
    assert!(second.normal.x.abs() > 0.999);
    let pole = Point3::new(cx, cy, 1.0);
    assert!(
        second.distance(&pole).abs() < 0.01,
        "through the pole: {}",
        second.distance(&pole)
    );
}

#[test]
fn a_box_seen_from_its_front_and_a_side_is_not_round() {
    // A 0.8 × 0.5 × 1.2 m cabinet: its front (y = 0) and its −x side, every 2 cm.
    let mut points = Vec::new();
    for k in 0..=60 {
        let z = 0.02 * k as f32;
        points.extend((0..=40).map(|i| Point3::new(0.02 * i as f32, 0.0, z)));
        points.extend((1..=25).map(|j| Point3::new(0.0, 0.02 * j as f32, z)));
    }
    let first = MirrorPlane {
        normal: Vector3::x(),
        offset: 0.4,
    };
    assert_eq!(plane_across_axis(&points, &first), None);
}
