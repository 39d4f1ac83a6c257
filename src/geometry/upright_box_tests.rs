//! Tests of [`super`]: the least-footprint and the faces-on-sides upright boxes.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector2, Vector3};

use super::*;
use crate::geometry::face_normals_turn::BoxTurn;
use crate::geometry::oriented_box::fit_minimum_volume_box;
use crate::geometry::oriented_box::tests::box_surface;

/// The turn of a box's x axis about world z, folded into [0°, 90°).
fn turn_deg(b: &OrientedBox) -> f32 {
    let x = b.world_from_box.rotation * Vector3::x();
    x.y.atan2(x.x).to_degrees().rem_euclid(90.0)
}

/// How far apart two turns are, folded as a rectangle repeats (every 90°), degrees.
fn turn_gap_deg(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(90.0);
    d.min(90.0 - d)
}

/// A cabinet 0.80 × 0.49 × 1.2 m turned `turn_deg` about world z, seen from one corner: its front
/// and one side every 2 cm, the part of its top near that corner, and the vertical edge where front and
/// side meet trimmed by 3 cm each way (a mask's border there is unsure).
fn cabinet_seen_from_a_corner(turn_deg: f32) -> Vec<Point3<f32>> {
    let (w, d, h) = (0.80f32, 0.49f32, 1.2f32);
    let step = 0.02;
    let mut local = Vec::new();
    for k in 0..=(h / step) as usize {
        let z = k as f32 * step;
        for i in 0..=(w / step) as usize {
            let x = i as f32 * step;
            if x > 0.03 {
                local.push(Point3::new(x, 0.0, z)); // the front
            }
        }
        for j in 0..=(d / step) as usize {
            let y = j as f32 * step;
            if y > 0.03 {
                local.push(Point3::new(0.0, y, z)); // the side
            }
        }
    }
    for i in 0..=(w / step) as usize {
        for j in 0..=(d / step) as usize {
            let (x, y) = (i as f32 * step, j as f32 * step);
            if x / w + y / d <= 0.6 && x + y > 0.03 {
                local.push(Point3::new(x, y, h)); // the top near the corner
            }
        }
    }
    let pose = Isometry3::from_parts(
        Translation3::new(-2.8, 2.0, 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn_deg.to_radians()),
    );
    local.iter().map(|p| pose * p).collect()
}

#[test]
fn the_upright_box_of_a_leaning_slab_stands_on_world_z_turned_as_the_slab() {
    // A 2 × 1.4 m slab 4 cm thick, tilted 15° about its long axis, turned 0.5 rad about world z:
    // its minimum-volume box leans with it; the upright box stands, turned as the slab.
    let tilt = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 15f32.to_radians());
    let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5);
    let pose = Isometry3::from_parts(Translation3::new(1.0, 2.0, 0.4), turn * tilt);
    let points = box_surface(&pose, Vector3::new(1.0, 0.7, 0.02), 6000, 3);
    let z_of = |b: &OrientedBox| b.world_from_box.rotation * Vector3::z();
    let leaning = fit_minimum_volume_box(&points).expect("ok");
    assert!(
        z_of(&leaning).z < 15f32.to_radians().cos() + 0.01,
        "the minimum-volume box leans"
    );
    let upright = fit_upright_box(&points).expect("ok");
    assert!(z_of(&upright).z > 0.9999, "box z is world z");
    let x = upright.world_from_box.rotation * Vector3::x();
    assert!(
        (x.y.atan2(x.x) - 0.5).abs() < 0.01,
        "x along the slab's long axis: {x:?}"
    );
    assert!(points.iter().all(|p| upright.contains(p, 1e-4)), "every point inside");
    // The footprint of the tilted slab: 2 m by 1.4·cos 15° + 4 cm·sin 15°.
    let width = 1.4 * 15f32.to_radians().cos() + 0.04 * 15f32.to_radians().sin();
    assert!((upright.extents().x - 2.0).abs() < 0.01 && (upright.extents().y - width).abs() < 0.01);
    assert!(fit_upright_box(&[]).is_err());
}

#[test]
fn a_cabinet_seen_from_a_corner_gets_its_box_turned_as_its_faces() {
    let points = cabinet_seen_from_a_corner(62.0);
    let least = fit_upright_box(&points).expect("ok");
    assert!(
        turn_gap_deg(turn_deg(&least), 62.0) > 10.0,
        "the least footprint lies along the L's diagonal: {}°",
        turn_deg(&least)
    );
    let on_faces = fit_upright_box_on_faces(&points, BoxTurn::Rectangle).expect("ok");
    assert!(
        turn_gap_deg(turn_deg(&on_faces), 62.0) < 0.5,
        "turned as the faces: {}°",
        turn_deg(&on_faces)
    );
    let e = on_faces.extents();
    assert!(
        (e.x - 0.80).abs() < 0.02 && (e.y - 0.49).abs() < 0.02 && (e.z - 1.2).abs() < 0.01,
        "{e:?}"
    );
    assert!(points.iter().all(|p| on_faces.contains(p, 1e-4)), "every point inside");
}

/// Asserts that both upright fits of `points` give the same box (turn and extents).
fn assert_same_upright_box(points: &[Point3<f32>]) {
    let least = fit_upright_box(points).expect("ok");
    let on_faces = fit_upright_box_on_faces(points, BoxTurn::Rectangle).expect("ok");
    let turn = least
        .world_from_box
        .rotation
        .angle_to(&on_faces.world_from_box.rotation);
    assert!(turn < 1e-6, "turned {turn} rad apart");
    assert!((least.extents() - on_faces.extents()).norm() < 1e-6);
}

#[test]
fn a_box_seen_whole_or_a_round_object_keeps_its_least_footprint() {
    // Seen whole, the least footprint is the faces' turn: the same box either way.
    let pose = Isometry3::from_parts(
        Translation3::new(1.0, 2.0, 0.4),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.5),
    );
    let whole = box_surface(&pose, Vector3::new(0.6, 0.3, 0.4), 6000, 5);
    assert_same_upright_box(&whole);
    // A lamp's round shade has no faces: its least footprint stays.
    let shade: Vec<Point3<f32>> = (0..40)
        .flat_map(|k| {
            (0..72).map(move |a| {
                let t = (a as f32 * 5.0).to_radians();
                Point3::new(0.2 * t.cos(), 0.2 * t.sin(), 1.2 + k as f32 * 0.01)
            })
        })
        .collect();
    assert_same_upright_box(&shade);
    assert!(fit_upright_box_on_faces(&[], BoxTurn::Rectangle).is_err());
    assert!(fit_upright_box_on_faces(&[], BoxTurn::FaceNormals).is_err());
}

#[test]
fn points_on_a_rectangles_sides_are_closest_at_its_turn() {
    let sides: Vec<Vector2<f64>> = (0..=20)
        .flat_map(|i| {
            let t = f64::from(i) / 20.0;
            [
                Vector2::new(t, 0.0),
                Vector2::new(t, 0.5),
                Vector2::new(0.0, t * 0.5),
                Vector2::new(1.0, t * 0.5),
            ]
        })
        .collect();
    let at = |deg: f64| closeness(&sides, Vector2::new(deg.to_radians().cos(), deg.to_radians().sin()));
    assert!(
        (at(0.0) - sides.len() as f64 / SIDE_DISTANCE_FLOOR_M).abs() < 1e-6,
        "every point on a side"
    );
    assert!(at(0.0) > 2.0 * at(30.0) && (at(0.0) - at(90.0)).abs() < 1e-6);
}

/// A stool-like object 0.40 × 0.30 × 0.60 m turned 20° about world z: a top every 2 cm and four
/// legs every centimetre of height, standing on the floor at z = 0.
fn stool() -> Vec<Point3<f32>> {
    let mut local = Vec::new();
    for i in 0..=20 {
        for j in 0..=15 {
            local.push(Point3::new(-0.2 + i as f32 * 0.02, -0.15 + j as f32 * 0.02, 0.6));
        }
    }
    for (x, y) in [(-0.19, -0.14), (0.19, -0.14), (-0.19, 0.14), (0.19, 0.14)] {
        for k in 0..60 {
            local.push(Point3::new(x, y, k as f32 * 0.01));
        }
    }
    let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 20f32.to_radians());
    local.iter().map(|p| turn * p).collect()
}

#[test]
fn floor_points_beside_the_feet_stay_out_of_the_footprint_but_not_out_of_the_height() {
    let clean = stool();
    let mut bled = clean.clone();
    // A mask grown onto the floor: points at floor height 6 cm beyond one side.
    let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 20f32.to_radians());
    for k in 0..10 {
        bled.push(turn * Point3::new(-0.15 + k as f32 * 0.03, 0.21, 0.005));
    }
    let on_faces = |p: &[Point3<f32>]| fit_upright_box_on_faces(p, BoxTurn::Rectangle);
    for fit in [fit_upright_box, on_faces] {
        let (a, b) = (fit(&clean).expect("a box"), fit(&bled).expect("a box"));
        assert!(
            (a.extents() - b.extents()).abs().max() < 1e-4,
            "the bled floor points leave the box alone: {:?} against {:?}",
            b.extents(),
            a.extents()
        );
        assert!((b.extents().z - 0.6).abs() < 1e-4, "the feet still reach the floor");
        assert!(
            turn_gap_deg(turn_deg(&b), 20.0) < 0.5,
            "turned as the stool: {}",
            turn_deg(&b)
        );
    }
    // Seen from the floor's height only, a flat object keeps all its points.
    let rug: Vec<Point3<f32>> = (0..100)
        .map(|i| Point3::new((i % 10) as f32 * 0.1, (i / 10) as f32 * 0.05, 0.0))
        .collect();
    let flat = fit_upright_box(&rug).expect("a box");
    assert!((flat.extents().x - 0.9).abs() < 1e-4, "{:?}", flat.extents());
}

/// [`cabinet_seen_from_a_corner`] through a noisy camera: every point moved by N(0, σ²) along
/// each axis, seeded.
fn noisy_cabinet(turn_deg: f32, sigma_m: f32, seed: u64) -> Vec<Point3<f32>> {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    cabinet_seen_from_a_corner(turn_deg)
        .into_iter()
        .map(|p| p + Vector3::from_fn(|_, _| sigma_m * crate::rng::standard_normal_f32(&mut rng)))
        .collect()
}

#[test]
fn a_noisy_cabinets_box_is_turned_as_its_faces_normals_not_as_its_noises_tails() {
    let (mut rectangle, mut normals) = (0.0f32, 0.0f32);
    for seed in 0..5 {
        let points = noisy_cabinet(62.0, 0.01, seed);
        let on_faces = fit_upright_box_on_faces(&points, BoxTurn::Rectangle).expect("ok");
        let on_normals = fit_upright_box_on_faces(&points, BoxTurn::FaceNormals).expect("ok");
        rectangle = rectangle.max(turn_gap_deg(turn_deg(&on_faces), 62.0));
        normals = normals.max(turn_gap_deg(turn_deg(&on_normals), 62.0));
    }
    assert!(normals < 0.5, "turned as the faces' normals: within {normals}°");
    assert!(
        rectangle > 2.0 * normals,
        "the rectangle's turn strays more: {rectangle}° against {normals}°"
    );
}

#[test]
fn a_stool_without_upright_faces_keeps_the_rectangles_turn() {
    let points = stool();
    let rectangle = fit_upright_box_on_faces(&points, BoxTurn::Rectangle).expect("ok");
    let normals = fit_upright_box_on_faces(&points, BoxTurn::FaceNormals).expect("ok");
    assert_eq!(
        turn_deg(&normals),
        turn_deg(&rectangle),
        "legs and a flat top are no faces"
    );
}
