//! Invariant tests of [`super::marching_cubes`]: analytic area and volume, closedness, orientation.

use std::collections::BTreeMap;
use std::f32::consts::PI;

use nalgebra::Point3;
use rand::RngExt;

use super::*;
use crate::rng::{RngStream, seeded_rng};
use crate::synth::primitives::signed_volume;

/// Samples `f` on an `n³` grid spanning `[-1, 1]³`.
fn sampled(n: usize, f: impl Fn(Point3<f32>) -> f32) -> (Vec<f32>, SampleGrid) {
    let grid = SampleGrid::cubic(Point3::new(-1.0, -1.0, -1.0), 2.0 / (n - 1) as f32, [n; 3]);
    let mut values = Vec::with_capacity(grid.len());
    let mut layer = Vec::new();
    for k in 0..n {
        grid.layer_positions(k, &mut layer);
        values.extend(layer.iter().map(|&p| f(p)));
    }
    (values, grid)
}

/// Panics unless every directed edge appears once and its reverse once: closed, manifold along
/// edges and consistently oriented.
fn assert_closed_and_oriented(mesh: &TriangleMesh) {
    let mut directed: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    for t in &mesh.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    for (&(a, b), &count) in &directed {
        assert_eq!(count, 1, "directed edge {a}→{b} is used by exactly one triangle");
        assert_eq!(
            directed.get(&(b, a)),
            Some(&1),
            "edge {a}–{b} is shared by exactly two triangles"
        );
    }
}

fn assert_no_degenerate_triangles(mesh: &TriangleMesh) {
    for (t, tri) in mesh.triangles.iter().enumerate() {
        assert!(
            tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2],
            "triangle {t} repeats a vertex: {tri:?}"
        );
        assert!(mesh.triangle_area(t) > 0.0, "triangle {t} has zero area");
    }
}

#[test]
fn a_sphere_has_its_analytic_area_and_volume_and_is_closed_and_outward() {
    let r = 0.7;
    let (values, grid) = sampled(48, |p| r - p.coords.norm());
    let mesh = marching_cubes(&values, &grid, 0.0).expect("valid grid");
    let (area, volume) = (4.0 * PI * r * r, 4.0 / 3.0 * PI * r * r * r);
    assert!(
        (mesh.area() / area - 1.0).abs() < 0.02,
        "area {} vs analytic {area}",
        mesh.area()
    );
    let signed = signed_volume(&mesh);
    assert!(signed > 0.0, "normals point outward (signed volume {signed})");
    assert!(
        (signed / volume - 1.0).abs() < 0.02,
        "volume {signed} vs analytic {volume}"
    );
    assert_closed_and_oriented(&mesh);
    assert_no_degenerate_triangles(&mesh);
    assert_eq!(mesh.validate(), Ok(()));
}

#[test]
fn vertices_are_welded_so_each_grid_edge_has_one_vertex() {
    let (values, grid) = sampled(24, |p| 0.6 - p.coords.norm());
    let mesh = marching_cubes(&values, &grid, 0.0).expect("valid grid");
    let mut keys: Vec<[u32; 3]> = mesh
        .vertices
        .iter()
        .map(|v| v.coords.map(f32::to_bits).into())
        .collect();
    let total = keys.len();
    keys.sort_unstable();
    keys.dedup();
    assert_eq!(keys.len(), total, "no two vertices share a position");
    assert!(
        mesh.triangles.len() > mesh.vertices.len(),
        "a closed welded mesh has about 2 triangles per vertex"
    );
}

#[test]
fn a_box_touching_the_grid_border_is_closed_by_caps() {
    // Inside for x ≥ −0.5 (touches the +x, ±y, ±z borders of the grid).
    let (values, grid) = sampled(11, |p| p.x + 0.5);
    let mesh = marching_cubes(&values, &grid, 0.0).expect("valid grid");
    assert_closed_and_oriented(&mesh);
    assert_no_degenerate_triangles(&mesh);
    let expected = 1.5 * 2.0 * 2.0;
    let signed = signed_volume(&mesh);
    assert!(
        (signed / expected - 1.0).abs() < 0.01,
        "closed box volume {signed} vs {expected}"
    );
}

#[test]
fn an_all_inside_grid_is_one_closed_box_around_the_samples() {
    let (values, grid) = sampled(5, |_| 1.0);
    let mesh = marching_cubes(&values, &grid, 0.5).expect("valid grid");
    assert_closed_and_oriented(&mesh);
    assert!(
        (signed_volume(&mesh) - 8.0).abs() < 0.05,
        "the box spans the sample positions"
    );
}

#[test]
fn an_all_outside_grid_gives_an_empty_mesh() {
    let (values, grid) = sampled(6, |_| 0.0);
    let mesh = marching_cubes(&values, &grid, 0.5).expect("valid grid");
    assert!(mesh.is_empty() && mesh.vertices.is_empty(), "nothing is inside");
    let nan = vec![f32::NAN; grid.len()];
    assert!(
        marching_cubes(&nan, &grid, 0.5).expect("valid grid").is_empty(),
        "NaN counts as outside"
    );
}

#[test]
fn random_grids_with_ambiguous_faces_stay_closed_and_oriented() {
    let mut rng = seeded_rng(11, RngStream::Mapper);
    for _ in 0..4 {
        let n = 9;
        let values: Vec<f32> = (0..n * n * n).map(|_| rng.random::<f32>()).collect();
        let grid = SampleGrid::cubic(Point3::origin(), 0.1, [n; 3]);
        let mesh = marching_cubes(&values, &grid, 0.5).expect("valid grid");
        assert_closed_and_oriented(&mesh);
        assert_no_degenerate_triangles(&mesh);
        assert!(signed_volume(&mesh) > 0.0, "inside blobs have positive volume");
    }
}

#[test]
fn wrong_value_counts_and_layer_counts_are_errors() {
    let grid = SampleGrid::cubic(Point3::origin(), 0.1, [3, 3, 3]);
    assert!(
        marching_cubes(&[0.0; 26], &grid, 0.5).is_err(),
        "26 values for 27 samples"
    );
    let mut extractor = IsoSurfaceExtractor::new(grid, 0.5).expect("valid grid");
    assert!(extractor.push_layer(&[0.0; 8]).is_err(), "a layer has 9 values");
    extractor.push_layer(&[1.0; 9]).expect("a full layer");
    assert!(extractor.finish().is_err(), "two layers are missing");
    assert!(
        IsoSurfaceExtractor::new(grid, f32::NAN).is_err(),
        "the level must be finite"
    );
}

#[test]
fn crossings_interpolate_and_stay_off_the_samples() {
    assert!((crossing(1.0, -1.0, 0.0) - 0.5).abs() < 1e-12);
    assert!((crossing(0.0, 1.0, 0.25) - 0.25).abs() < 1e-7);
    assert_eq!(
        crossing(1.0, 0.5, 0.5),
        1.0 - EDGE_EPSILON,
        "a sample exactly at the level"
    );
    assert_eq!(
        crossing(1.0, f32::NEG_INFINITY, 0.5),
        EDGE_EPSILON,
        "padding pulls to the finite end"
    );
    assert_eq!(crossing(f32::NAN, 1.0, 0.5), 1.0 - EDGE_EPSILON);
}
