//! Input checks and centroid voxel downsampling of point clouds.

use nalgebra::Point3;

use crate::error::{CatmapError, Result};
use crate::objects::observed_cloud::voxel_downsample;

/// Errors unless `points` holds at least `min_points` points, all finite. `what` names the cloud
/// in the message ("source", "template").
pub fn check_cloud(points: &[Point3<f32>], what: &str, min_points: usize) -> Result<()> {
    if points.len() < min_points {
        return Err(CatmapError::too_few(
            format!("points of the {what} cloud to register"),
            min_points,
            points.len(),
        ));
    }
    if let Some(i) = points.iter().position(|p| !p.coords.iter().all(|x| x.is_finite())) {
        return Err(CatmapError::NonFinitePoint {
            what: format!("{what} cloud point {i}"),
        });
    }
    Ok(())
}

/// Thins `points` to one point per occupied `voxel_m` voxel, the centroid of its points:
/// q_v = (1/|V|) Σ_{p ∈ V} p for every voxel V = {p : ⌊p / voxel_m⌋ = v}.
///
/// Reuses [`voxel_downsample`] (centroid-based, key-sorted, so deterministic). Errors on an
/// empty or non-finite cloud, or a voxel edge that is not positive and finite.
pub fn voxel_centroids(points: &[Point3<f32>], voxel_m: f32) -> Result<Vec<Point3<f32>>> {
    if !(voxel_m > 0.0 && voxel_m.is_finite()) {
        return Err(CatmapError::bad_value(
            "the voxel edge",
            voxel_m,
            "be positive and finite",
        ));
    }
    check_cloud(points, "input", 1)?;
    Ok(voxel_downsample(points, voxel_m))
}

/// Scale of a cloud: half the largest edge of its axis-aligned bounding box, max(extent)/2.
/// Zero for fewer than two distinct points.
pub fn half_max_extent(points: &[Point3<f32>]) -> f32 {
    crate::geometry::mesh::Aabb::from_points(points).map_or(0.0, |b| b.extent().max() / 2.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_of_one_voxel_become_their_centroid() {
        let points = [
            Point3::new(0.01, 0.01, 0.01),
            Point3::new(0.03, 0.05, 0.07),
            Point3::new(0.25, 0.05, 0.05),
        ];
        let thinned = voxel_centroids(&points, 0.1).expect("valid cloud");
        assert_eq!(thinned.len(), 2, "two occupied voxels");
        assert!(
            thinned
                .iter()
                .any(|p| (p - Point3::new(0.02, 0.03, 0.04)).norm() < 1e-6)
        );
    }

    #[test]
    fn degenerate_clouds_are_rejected_with_a_reason() {
        assert!(voxel_centroids(&[], 0.1).is_err(), "empty cloud");
        assert!(voxel_centroids(&[Point3::new(f32::NAN, 0.0, 0.0)], 0.1).is_err(), "NaN");
        assert!(voxel_centroids(&[Point3::origin()], 0.0).is_err(), "zero voxel");
        let err = check_cloud(&[Point3::origin(); 2], "source", 3).expect_err("two points are too few");
        assert!(
            matches!(&err, CatmapError::TooFew { what, needed: 3, found: 2 } if what.contains("source cloud")),
            "{err}"
        );
    }

    #[test]
    fn scale_is_half_the_largest_box_edge() {
        let points = [Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 1.0, 0.5)];
        assert_eq!(half_max_extent(&points), 1.0);
    }
}
