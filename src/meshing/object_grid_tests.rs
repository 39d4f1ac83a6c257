//! Tests of [`super`]: the sample grid over an object's box, meshes of analytic fields in world
//! coordinates, coarse-to-fine meshing, empty fields and bad callbacks.

use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use super::*;
use crate::synth::primitives::signed_volume;

fn tilted_frame(extents: Vector3<f32>) -> ObjectFrame {
    let rotation = UnitQuaternion::from_euler_angles(0.1, -0.2, 0.7);
    let pose = Isometry3::from_parts(Translation3::new(1.0, 2.0, 0.5), rotation);
    ObjectFrame {
        world_from_object: Similarity3::from_isometry(pose, 1.0),
        extents,
    }
}

#[test]
fn the_grid_covers_the_box_enlarged_by_one_over_point_nine_at_five_millimetres() {
    let frame = tilted_frame(Vector3::new(0.45, 0.9, 2.7));
    let object_grid = ObjectGrid::new(&frame, &ObjectMeshConfig::default()).expect("valid frame");
    let g = object_grid.grid;
    assert_eq!(g.dims[0], 101, "0.5 m at 5 mm is 100 voxels, 101 samples");
    assert_eq!(g.dims[1], 201, "1 m at 5 mm");
    assert_eq!(g.dims[2], 256, "3 m is capped at 256 samples");
    assert!((g.origin.y + 0.5).abs() < 1e-6, "the grid starts at −extent/(2·0.9)");
    let far = g.position((g.dims[0] - 1) as f64, (g.dims[1] - 1) as f64, (g.dims[2] - 1) as f64);
    assert!(
        (far - Point3::new(0.25, 0.5, 1.5)).norm() < 1e-5,
        "the last sample is on the far corner, got {far}"
    );
}

#[test]
fn a_scaled_object_frame_samples_five_millimetres_in_world_units() {
    let mut frame = tilted_frame(Vector3::new(0.9, 0.9, 0.9)); // object units
    frame.world_from_object.set_scaling(0.5); // 1 object unit = 0.5 m
    let g = ObjectGrid::new(&frame, &ObjectMeshConfig::default())
        .expect("valid frame")
        .grid;
    assert_eq!(g.dims, [101; 3], "1 object unit = 0.5 m = 100 voxels");
}

#[test]
fn a_ball_field_meshes_to_a_closed_ball_in_world_coordinates() {
    let frame = tilted_frame(Vector3::new(0.2, 0.2, 0.2));
    let centre = frame.world_from_object * Point3::origin();
    let mut batches = 0;
    let dense = ObjectMeshConfig {
        coarse_block: 1,
        ..ObjectMeshConfig::default()
    };
    let mut mesh = extract_object_mesh(&frame, &dense, |points| {
        batches += 1;
        points
            .iter()
            .map(|p| if (p - centre).norm() < 0.1 { 1.0 } else { 0.0 })
            .collect()
    })
    .expect("valid frame");
    assert_eq!(batches, 46, "one batch per z-layer of the 46-sample grid");
    let volume = signed_volume(&mesh.transformed(&Isometry3::translation(-centre.x, -centre.y, -centre.z)));
    let expected = 4.0 / 3.0 * std::f32::consts::PI * 0.1f32.powi(3);
    assert!(
        (volume / expected - 1.0).abs() < 0.1,
        "binary occupancy ball volume {volume} vs {expected}"
    );
    assert!(
        mesh.vertices.iter().all(|v| ((v - centre).norm() - 0.1).abs() < 0.006),
        "surface within a voxel of the ball"
    );
    paint_vertices(&mut mesh, |points| points.iter().map(|_| [10, 20, 30]).collect()).expect("one colour per vertex");
    assert_eq!(mesh.validate(), Ok(()), "coloured mesh is consistent");
}

/// A smooth occupancy (σ of the signed distance over 4 mm) of a seat on a thin leg and a
/// thinner rod: a ball of radius 0.15 m, a 2 cm-wide leg under it, a 1 cm rod beside it.
fn chair_like(p: &Point3<f32>, centre: &Point3<f32>) -> f32 {
    let d = p - centre;
    let ball = d.norm() - 0.15;
    let leg = (d.x * d.x + d.y * d.y).sqrt() - 0.01;
    let leg = leg.max(-(d.z + 0.3)).max(d.z);
    let rod = ((d.x - 0.2).powi(2) + d.z * d.z).sqrt() - 0.005;
    let rod = rod.max(d.y.abs() - 0.2);
    let distance = ball.min(leg).min(rod);
    1.0 / (1.0 + (distance / 0.004).exp())
}

#[test]
fn coarse_to_fine_gives_the_dense_mesh_with_fewer_evaluations() {
    let frame = tilted_frame(Vector3::new(0.5, 0.5, 0.5));
    let centre = frame.world_from_object * Point3::new(0.0, 0.0, 0.05);
    let run = |coarse_block: usize| {
        let cfg = ObjectMeshConfig {
            coarse_block,
            ..ObjectMeshConfig::default()
        };
        let mut evaluated = 0;
        let mesh = extract_object_mesh(&frame, &cfg, |points| {
            evaluated += points.len();
            points.iter().map(|p| chair_like(p, &centre)).collect()
        })
        .expect("valid frame");
        (mesh, evaluated)
    };
    let (dense, dense_evaluations) = run(1);
    assert!(!dense.is_empty());
    for block in [2, 4] {
        let (mesh, evaluations) = run(block);
        assert_eq!(mesh.vertices, dense.vertices, "block {block}: same vertices");
        assert_eq!(mesh.triangles, dense.triangles, "block {block}: same triangles");
        assert!(
            evaluations * 2 < dense_evaluations,
            "block {block}: {evaluations} of {dense_evaluations} samples evaluated"
        );
    }
}

#[test]
fn a_feature_the_coarse_samples_never_see_is_missed_only_without_margin() {
    // A small ball midway between coarse samples (1.7 cm from the nearest): its occupancy is
    // 0.79 at its centre and ~0.18 at the coarse samples, so the margin is what finds it,
    // and a margin that reaches only 0.45 below the level would not.
    let frame = tilted_frame(Vector3::new(0.3, 0.3, 0.3));
    let grid = ObjectGrid::new(&frame, &ObjectMeshConfig::default()).unwrap().grid;
    let centre = frame.world_from_object * grid.position(2.0, 2.0, 2.0);
    let field = |points: &[Point3<f32>]| -> Vec<f32> {
        points
            .iter()
            .map(|p| 1.0 / (1.0 + (((p - centre).norm() - 0.008) / 0.006).exp()))
            .collect()
    };
    let with = |coarse_margin: f32, coarse_block: usize| {
        let cfg = ObjectMeshConfig {
            coarse_block,
            coarse_margin,
            ..ObjectMeshConfig::default()
        };
        extract_object_mesh(&frame, &cfg, field).unwrap()
    };
    let margin = ObjectMeshConfig::default().coarse_margin;
    let dense = with(margin, 1);
    assert!(!dense.is_empty());
    assert_eq!(with(margin, 4).vertices, dense.vertices, "the default margin finds it");
    assert!(
        with(0.45, 4).is_empty(),
        "0.45 below the level: the coarse samples miss it"
    );
    assert!(with(0.0, 4).is_empty(), "no margin: the coarse samples alone miss it");
}

#[test]
fn empty_fields_give_empty_meshes_and_bad_callbacks_give_errors() {
    let frame = tilted_frame(Vector3::new(0.1, 0.1, 0.1));
    let config = ObjectMeshConfig::default();
    let empty = extract_object_mesh(&frame, &config, |p| vec![0.0; p.len()]).expect("valid frame");
    assert!(empty.is_empty(), "nothing occupied, nothing meshed");
    assert!(
        extract_object_mesh(&frame, &config, |_| vec![1.0]).is_err(),
        "one value for many points"
    );
    let flat = ObjectFrame {
        extents: Vector3::new(0.1, 0.0, 0.1),
        ..frame
    };
    assert!(
        extract_object_mesh(&flat, &config, |p| vec![0.0; p.len()]).is_err(),
        "a flat box has no grid"
    );
}
