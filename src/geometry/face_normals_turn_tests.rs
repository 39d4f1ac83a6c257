//! Tests of [`super`]: the turn to the upright faces' normals and when it applies.

use nalgebra::{Vector2, Vector3};
use rand::SeedableRng;

use super::*;
use crate::rng::standard_normal_f32;

/// Two upright walls meeting at a corner, `width` and `depth` long and `height` tall, every 2 cm,
/// turned `turn_deg` about up, each point moved by N(0, σ²) per axis (seeded); centred.
fn walls(width: f64, depth: f64, height: f64, turn_deg: f64, sigma_m: f32) -> Vec<Vector3<f64>> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let step = 0.02;
    let mut local = Vec::new();
    for k in 0..=(height / step) as usize {
        let z = k as f64 * step;
        local.extend((1..=(width / step) as usize).map(|i| Vector3::new(i as f64 * step, 0.0, z)));
        local.extend((1..=(depth / step) as usize).map(|j| Vector3::new(0.0, j as f64 * step, z)));
    }
    let (c, s) = (turn_deg.to_radians().cos(), turn_deg.to_radians().sin());
    let points: Vec<Vector3<f64>> = local
        .iter()
        .map(|p| {
            let noise = Vector3::from_fn(|_, _| f64::from(sigma_m * standard_normal_f32(&mut rng)));
            Vector3::new(c * p.x - s * p.y, s * p.x + c * p.y, p.z) + noise
        })
        .collect();
    let mean = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    points.iter().map(|p| p - mean).collect()
}

fn at(deg: f64) -> Vector2<f64> {
    Vector2::new(deg.to_radians().cos(), deg.to_radians().sin())
}

fn deg(x: Vector2<f64>) -> f64 {
    x.y.atan2(x.x).to_degrees()
}

#[test]
fn a_rectangle_turned_off_large_noisy_walls_comes_to_their_normals() {
    let points = walls(0.8, 0.5, 1.2, 30.0, 0.01);
    for off in [-3.0, 2.5] {
        let turned = turned_to_face_normals(&points, at(30.0 + off));
        assert!((deg(turned) - 30.0).abs() < 0.3, "{off}° off → {}°", deg(turned));
    }
    assert_eq!(
        BoxTurn::Rectangle.turned(&points, at(32.0)),
        at(32.0),
        "the rectangle's turn kept"
    );
}

#[test]
fn a_small_object_of_faces_keeps_the_rectangles_turn() {
    // 0.3 × 0.3 × 0.4 m: about 600 points on faces, fewer than FACE_MIN_VOTES.
    let points = walls(0.3, 0.3, 0.4, 30.0, 0.0);
    assert!(points.len() < FACE_MIN_VOTES);
    assert_eq!(turned_to_face_normals(&points, at(32.0)), at(32.0));
}

#[test]
fn an_object_mostly_off_upright_faces_keeps_the_rectangles_turn() {
    // The large walls with as many points again on a flat top (normals up: no vote).
    let mut points = walls(0.8, 0.5, 1.2, 30.0, 0.0);
    let top: Vec<Vector3<f64>> = (0..points.len())
        .map(|i| Vector3::new((i % 70) as f64 * 0.02 - 0.7, (i / 70) as f64 * 0.02 - 0.7, 0.9))
        .collect();
    points.extend(top);
    assert_eq!(turned_to_face_normals(&points, at(32.0)), at(32.0));
    let walls_alone = walls(0.8, 0.5, 1.2, 30.0, 0.0);
    assert!((deg(turned_to_face_normals(&walls_alone, at(32.0))) - 30.0).abs() < 0.1);
}
