//! Tests of [`super::score_object`] on meshes with known distances.

use std::f32::consts::PI;

use nalgebra::{Isometry3, Point3, Vector3};

use super::*;
use crate::rng::{RngStream, seeded_rng};
use crate::synth::primitives::cuboid;

/// A closed UV sphere of `radius` around `centre`, fine enough that faceting is below 0.3 mm.
fn sphere(centre: Point3<f32>, radius: f32) -> TriangleMesh {
    let (rings, segments) = (48u32, 96u32);
    let mut vertices = vec![centre + Vector3::z() * radius, centre - Vector3::z() * radius];
    for r in 1..rings {
        let theta = PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * PI * s as f32 / segments as f32;
            vertices
                .push(centre + radius * Vector3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
        }
    }
    let at = |r: u32, s: u32| 2 + (r - 1) * segments + s % segments;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, at(1, s), at(1, s + 1)]);
        triangles.push([1, at(rings - 1, s + 1), at(rings - 1, s)]);
        for r in 1..rings - 1 {
            triangles.push([at(r, s), at(r + 1, s), at(r + 1, s + 1)]);
            triangles.push([at(r, s), at(r + 1, s + 1), at(r, s + 1)]);
        }
    }
    TriangleMesh::new(vertices, triangles)
}

fn score(gt: &TriangleMesh, prediction: Option<&TriangleMesh>, crop: Crop) -> ObjectScores {
    let mut rng = seeded_rng(5, RngStream::Mapper);
    score_object(gt, prediction, crop, SAMPLES_PER_MESH, &mut rng).expect("the ground truth is a valid mesh")
}

fn accuracy(s: &ObjectScores) -> f32 {
    s.accuracy_cm.expect("some predicted samples lie in the crop")
}

fn completion(s: &ObjectScores) -> f32 {
    s.completion_cm.expect("the prediction is present")
}

#[test]
fn identical_meshes_score_about_zero_and_full_completion() {
    let gt = sphere(Point3::new(1.0, -2.0, 0.5), 0.2);
    let s = score(&gt, Some(&gt), Crop::Paper);
    // Two independent 10 000-sample sets of a 0.5 m² surface lie ~3.5 mm apart on average.
    assert!(accuracy(&s) < 0.5 && completion(&s) < 0.5, "sampling noise only: {s:?}");
    assert_eq!(
        s.completion_ratio_5cm_pct, 100.0,
        "every ground-truth sample is within 5 cm"
    );
    assert!(s.completion_ratio_1cm_pct > 99.0, "nearly all within 1 cm: {s:?}");
    assert_eq!(s.status, PredictionStatus::Reconstructed);
}

#[test]
fn a_surface_offset_by_three_centimetres_scores_three_centimetres() {
    // A concentric sphere 3 cm smaller: every point is exactly 3 cm from the other surface.
    let gt = sphere(Point3::origin(), 0.2);
    let s = score(&gt, Some(&sphere(Point3::origin(), 0.17)), Crop::Paper);
    assert!((accuracy(&s) - 3.0).abs() < 0.15, "accuracy ≈ 3 cm: {s:?}");
    assert!((completion(&s) - 3.0).abs() < 0.15, "completion ≈ 3 cm: {s:?}");
    assert_eq!(s.completion_ratio_5cm_pct, 100.0, "3 cm < 5 cm");
    assert_eq!(s.completion_ratio_1cm_pct, 0.0, "3 cm > 1 cm");
    assert_eq!(s.accuracy_far_5cm_pct, Some(0.0), "no predicted sample is 5 cm away");
}

#[test]
fn surface_inside_the_object_counts_as_farther_than_five_centimetres() {
    // The prediction is the ground-truth sphere plus a sphere of half its radius at its centre
    // (surface that is not there, like a table left solid under its top): a quarter of the
    // area, so a fifth of the samples, all 10 cm from the ground truth and inside its box.
    let gt = sphere(Point3::origin(), 0.2);
    let mut doubled = gt.clone();
    let inner = sphere(Point3::origin(), 0.1);
    let base = doubled.vertices.len() as u32;
    doubled.vertices.extend(inner.vertices);
    doubled
        .triangles
        .extend(inner.triangles.iter().map(|t| t.map(|i| i + base)));
    let s = score(&gt, Some(&doubled), Crop::Paper);
    let far_pct = s.accuracy_far_5cm_pct.expect("a prediction in the crop");
    assert!((16.0..24.0).contains(&far_pct), "the inner sphere's share: {far_pct} %");
    assert_eq!(score(&gt, None, Crop::Paper).accuracy_far_5cm_pct, None);
}

#[test]
fn a_sphere_shifted_by_three_centimetres_completes_to_half_the_shift() {
    // Points of a sphere shifted by d ≪ r lie |d·cos θ| from the original: d/2 on average.
    // Nearest *samples* are a little farther than the surface: ~0.1 cm more at this density.
    let gt = sphere(Point3::origin(), 0.2);
    let s = score(&gt, Some(&sphere(Point3::new(0.03, 0.0, 0.0), 0.2)), Crop::Paper);
    assert!((completion(&s) - 1.5).abs() < 0.2, "completion ≈ d/2 = 1.5 cm: {s:?}");
    assert!(
        s.completion_ratio_1cm_pct < 50.0,
        "most samples moved by more than 1 cm: {s:?}"
    );
}

#[test]
fn half_a_mesh_grows_completion_but_keeps_accuracy() {
    let gt = sphere(Point3::origin(), 0.2);
    let mut half = gt.clone();
    half.triangles
        .retain(|t| t.iter().all(|&i| half.vertices[i as usize].z >= 0.0));
    let s = score(&gt, Some(&half), Crop::Paper);
    assert!(accuracy(&s) < 0.5, "what is predicted is right: {s:?}");
    // The lower half lies 2r·sin(φ/2) from the rim: 0.55·r = 11 cm on average, 5.5 cm overall.
    assert!(completion(&s) > 4.5, "the lower half is far from the upper: {s:?}");
    // Covered: the upper half and the 5 cm band below the rim (a quarter of the lower half).
    assert!(
        (s.completion_ratio_5cm_pct - 62.0).abs() < 5.0,
        "about 62 % of the ground truth is covered: {s:?}"
    );
}

#[test]
fn the_crop_removes_far_away_clutter_from_accuracy_only() {
    let gt = sphere(Point3::origin(), 0.2);
    let mut cluttered = gt.clone();
    cluttered.append(&cuboid([1.0, 1.0, 0.0], [1.4, 1.4, 0.4])); // 1.2 m away, about twice the area
    let s = score(&gt, Some(&cluttered), Crop::Paper);
    assert!(
        accuracy(&s) < 0.6,
        "the clutter lies outside the ground-truth box: {s:?}"
    );
    assert!(
        s.accuracy_samples < 5_000,
        "most predicted samples fall on the clutter: {s:?}"
    );
    assert!(completion(&s) < 1.0, "the object itself is complete: {s:?}");
    let vmap = score(&gt, Some(&cluttered), Crop::Vmap);
    assert!(
        accuracy(&vmap) < 0.6 && completion(&vmap) < 1.0,
        "vMAP's crop also drops it: {vmap:?}"
    );
}

#[test]
fn missing_or_empty_predictions_are_reported_missing() {
    let gt = sphere(Point3::origin(), 0.2);
    assert_eq!(score(&gt, None, Crop::Paper), ObjectScores::missing(), "no prediction");
    assert_eq!(
        score(&gt, Some(&TriangleMesh::default()), Crop::Vmap),
        ObjectScores::missing(),
        "empty mesh"
    );
    let flat = TriangleMesh::new(vec![Point3::origin(); 3], vec![[0, 1, 2]]);
    assert_eq!(
        score(&gt, Some(&flat), Crop::Paper),
        ObjectScores::missing(),
        "no surface area"
    );
}

#[test]
fn a_prediction_entirely_outside_the_crop_has_no_accuracy() {
    let gt = sphere(Point3::origin(), 0.2);
    let far = gt.transformed(&Isometry3::translation(2.0, 0.0, 0.0));
    let s = score(&gt, Some(&far), Crop::Paper);
    assert_eq!(s.accuracy_cm, None, "nothing predicted inside the box");
    assert!(
        completion(&s) > 150.0,
        "the ground truth is ~2 m from the prediction: {s:?}"
    );
    let vmap = score(&gt, Some(&far), Crop::Vmap);
    assert_eq!(
        (vmap.accuracy_cm, vmap.completion_cm, vmap.completion_ratio_5cm_pct),
        (None, None, 0.0)
    );
}

#[test]
fn an_unusable_ground_truth_is_an_error() {
    let mut rng = seeded_rng(0, RngStream::Mapper);
    let empty = TriangleMesh::default();
    let pred = sphere(Point3::origin(), 0.2);
    assert!(
        score_object(&empty, Some(&pred), Crop::Paper, 10, &mut rng).is_err(),
        "no vertices, no box"
    );
    let flat = TriangleMesh::new(vec![Point3::origin(); 3], vec![[0, 1, 2]]);
    assert!(
        score_object(&flat, Some(&pred), Crop::Paper, 10, &mut rng).is_err(),
        "no area to sample"
    );
}

#[test]
fn the_same_seed_gives_the_same_scores() {
    let gt = sphere(Point3::origin(), 0.2);
    let pred = sphere(Point3::new(0.01, 0.0, 0.0), 0.19);
    assert_eq!(
        score(&gt, Some(&pred), Crop::Paper),
        score(&gt, Some(&pred), Crop::Paper)
    );
}
