//! A box fitted to a noisy cloud seen from afar, with and without its points moved onto their local surfaces
//! (`objects.box_smoothing_m`).

use nalgebra::Point3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::rng::standard_normal_f32;

/// A cabinet 80 × 50 × 120 cm (x from −0.4 to 0.4, y from −0.25 to 0.25, z from 0 to 1.2) seen
/// from −x: its front face (x = −0.4) and its top, every point of a 1 cm grid seen in 20 frames,
/// each time moved along x (the camera's depth) by N(0, σ²) — a Kinect v1's 3.3 cm at 4.5 m,
/// σ = 1.2 cm after the bilateral filter of `--depth camera`.
fn cabinet_front_seen_from_afar(sigma_m: f32) -> ObservedCloud {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let mut cloud = ObservedCloud::new(0.01);
    for _ in 0..20 {
        for j in 0..50 {
            let y = -0.245 + j as f32 * 0.01;
            for k in 0..120 {
                let z = 0.005 + k as f32 * 0.01;
                cloud.add_point(&Point3::new(-0.4 + sigma_m * standard_normal_f32(&mut rng), y, z));
            }
            for i in 0..80 {
                let x = -0.395 + i as f32 * 0.01;
                cloud.add_point(&Point3::new(x + sigma_m * standard_normal_f32(&mut rng), y, 1.2));
            }
        }
    }
    cloud
}

/// How far in front of the cabinet's front face (x = −0.4) the fitted box reaches, metres.
fn reach_in_front(cloud: &ObservedCloud, box_smoothing_m: f32) -> f32 {
    let cfg = ObjectConfig {
        box_min_voxel_points: 3,
        box_smoothing_m,
        box_fit: BoxFit::Upright,
        ..ObjectConfig::default()
    };
    let fitted = fit_object_box(cloud, &cfg).expect("a box");
    let front = fitted.corners().iter().map(|c| c.x).fold(f32::MAX, f32::min);
    -0.4 - front
}

#[test]
fn a_box_fitted_to_a_face_seen_through_noise_reaches_the_shells_extreme_unless_its_points_lie_on_their_planes() {
    let noisy = cabinet_front_seen_from_afar(0.012);
    let raw = reach_in_front(&noisy, 0.0);
    let smoothed = reach_in_front(&noisy, 0.05);
    assert!(raw > 0.025, "the shell's outermost voxels of three points: {raw}");
    // Along its edge with the top the neighbourhood is no plane: those points stay.
    assert!(
        smoothed.abs() < 0.02 && smoothed < 0.5 * raw,
        "the face's middle sheet: {smoothed}"
    );
    // Exact depth: a radius changes nothing that matters.
    let exact = cabinet_front_seen_from_afar(0.0);
    assert!(reach_in_front(&exact, 0.0).abs() < 0.006);
    assert!(reach_in_front(&exact, 0.05).abs() < 0.006);
}
