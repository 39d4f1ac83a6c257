//! Tests of [`super`]: the minimum-volume box, its canonical axes, the hull and support points.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

pub(crate) fn box_surface(pose: &Isometry3<f32>, half: Vector3<f32>, n: usize, seed: u64) -> Vec<Point3<f32>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let mut p: Vector3<f32> = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let face = rng.random_range(0..3usize);
            p[face] = if rng.random::<bool>() { 1.0 } else { -1.0 };
            pose * Point3::from(p.component_mul(&half))
        })
        .collect()
}

#[test]
fn a_rotated_box_is_recovered_with_its_extents_and_centre() {
    let pose = Isometry3::new(Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.3, -0.5, 0.9));
    let half = Vector3::new(0.4, 0.25, 0.1);
    let points = box_surface(&pose, half, 4000, 7);
    let fitted = fit_minimum_volume_box(&points).expect("non-empty cloud");
    let true_volume = 8.0 * half.x * half.y * half.z;
    let volume = fitted.volume();
    assert!(volume < true_volume * 1.03, "volume {volume} vs true {true_volume}");
    assert!((fitted.center() - pose.translation.vector).coords.norm() < 0.01);
    let mut got: Vec<f32> = fitted.half_extents.iter().copied().collect();
    got.sort_by(f32::total_cmp);
    for (g, t) in got.iter().zip([0.1, 0.25, 0.4]) {
        assert!((g - t).abs() < 0.01, "half extents {got:?}");
    }
    let all_inside = points.iter().all(|p| fitted.contains(p, 1e-4));
    assert!(all_inside, "every point lies inside");
}

#[test]
fn box_axes_are_canonical_and_right_handed() {
    let pose = Isometry3::new(Vector3::zeros(), Vector3::new(0.0, 0.0, 2.5));
    let fitted = fit_minimum_volume_box(&box_surface(&pose, Vector3::new(0.2, 0.5, 0.3), 3000, 1)).expect("ok");
    let r = fitted.world_from_box.rotation.to_rotation_matrix();
    assert!(r.matrix().column(2).z > 0.99, "box z points up");
    assert!(
        fitted.half_extents.x >= fitted.half_extents.y,
        "x is the longer horizontal axis"
    );
    assert!((r.matrix().determinant() - 1.0).abs() < 1e-5);
}

#[test]
fn degenerate_clouds_give_boxes_or_clear_errors() {
    assert!(fit_minimum_volume_box(&[]).is_err());
    assert!(fit_minimum_volume_box(&[Point3::new(f32::NAN, 0.0, 0.0)]).is_err());
    let single = fit_minimum_volume_box(&[Point3::new(1.0, 2.0, 3.0)]).expect("one point is a box");
    let grown = single.with_min_extent(0.1);
    assert_eq!(grown.extents(), Vector3::repeat(0.1));
    let line: Vec<Point3<f32>> = (0..10).map(|i| Point3::new(i as f32 * 0.1, 0.0, 0.0)).collect();
    let fitted = fit_minimum_volume_box(&line).expect("a line is a flat box");
    assert!((fitted.extents().max() - 0.9).abs() < 1e-4);
}

#[test]
fn convex_hull_drops_interior_and_collinear_points() {
    let pts = [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0), (1.0, 1.0)]
        .map(|(x, y)| Vector2::new(x, y))
        .to_vec();
    assert_eq!(convex_hull_2d(pts).len(), 4);
}

#[test]
fn support_points_are_the_last_maxima_along_each_direction_however_often_points_repeat() {
    // A cloud on a coarse grid (many exact ties between distinct points) with every point
    // repeated up to three times, in shuffled order: the support set is each direction's
    // last maximum, as a plain scan finds it.
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut points: Vec<Vector3<f64>> = (0..600)
        .map(|_| {
            Vector3::new(rng.random_range(0..6), rng.random_range(0..5), rng.random_range(0..4)).cast::<f64>() * 0.1
        })
        .collect();
    let copies: Vec<Vector3<f64>> = points.iter().take(400).copied().collect();
    points.extend(copies.iter().take(200));
    points.extend(copies);
    for k in (1..points.len()).rev() {
        points.swap(k, rng.random_range(0..=k));
    }
    let directions = fibonacci_sphere(300);
    let naive: Vec<usize> = directions
        .iter()
        .map(|d| {
            let d = d.cast::<f32>();
            let dot = |p: &Vector3<f64>| p.x as f32 * d.x + p.y as f32 * d.y + p.z as f32 * d.z;
            (0..points.len())
                .max_by(|&a, &b| dot(&points[a]).total_cmp(&dot(&points[b])).then(a.cmp(&b)))
                .expect("points")
        })
        .collect();
    let mut naive = naive;
    naive.sort_unstable();
    naive.dedup();
    let want: Vec<Vector3<f64>> = naive.into_iter().map(|i| points[i]).collect();
    assert_eq!(support_points(&points, &directions), want);
}

#[test]
fn the_upright_box_of_a_leaning_box_stands_on_world_z_and_encloses_it() {
    let leaning = OrientedBox {
        world_from_box: Isometry3::from_parts(
            Translation3::new(1.0, 2.0, 0.5),
            UnitQuaternion::from_euler_angles(0.3, 0.0, 0.7),
        ),
        half_extents: Vector3::new(1.0, 0.45, 0.3),
    };
    let upright = leaning.upright();
    let z = upright.world_from_box.rotation * Vector3::z();
    assert!((z - Vector3::z()).norm() < 1e-5, "box z {z} along world z");
    for c in leaning.corners() {
        assert!(upright.contains(&c, 1e-4), "corner {c} outside the upright box");
    }
    // Turned as the leaning box's x axis: its long side stays the upright box's x.
    let x = upright.world_from_box.rotation * Vector3::x();
    assert!((x.y.atan2(x.x) - 0.7).abs() < 1e-4, "yaw {}", x.y.atan2(x.x));
    assert!(upright.half_extents.x > upright.half_extents.y);
    // The leaning box's height grows by its tilt: 0.3 cos 0.3 + 0.45 sin 0.3.
    let height = 0.3 * 0.3f32.cos() + 0.45 * 0.3f32.sin();
    assert!(
        (upright.half_extents.z - height).abs() < 1e-4,
        "{}",
        upright.half_extents.z
    );
    // An upright box is its own upright box.
    let again = upright.upright();
    assert!((again.half_extents - upright.half_extents).norm() < 1e-5);
    assert!((again.center() - upright.center()).norm() < 1e-5);
}
