//! Surface normals by PCA of each point's neighbourhood.
//!
//! With the neighbours N(p) = {q : |q − p| ≤ r} (p included) and their mean μ, the normal is the
//! eigenvector of the smallest eigenvalue of C = (1/|N|) Σ (q − μ)(q − μ)ᵀ, oriented away from
//! the cloud's centroid c: n·(p − c) ≥ 0.

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};

use crate::geometry::nearest::PointIndex;

/// Unit normal per point, or `None` where fewer than 3 points lie within `radius_m`.
pub fn pca_normals(points: &[Point3<f32>], index: &PointIndex, radius_m: f32) -> Vec<Option<Vector3<f32>>> {
    if points.is_empty() {
        return Vec::new();
    }
    let centroid: Vector3<f32> = points.iter().map(|p| p.coords).sum::<Vector3<f32>>() / points.len() as f32;
    points
        .iter()
        .map(|p| {
            let neighbours = index.within(p, radius_m);
            if neighbours.len() < 3 {
                return None;
            }
            let mean: Vector3<f32> =
                neighbours.iter().map(|&j| points[j].coords).sum::<Vector3<f32>>() / neighbours.len() as f32;
            let covariance: Matrix3<f32> = neighbours
                .iter()
                .map(|&j| {
                    let d = points[j].coords - mean;
                    d * d.transpose()
                })
                .sum::<Matrix3<f32>>()
                / neighbours.len() as f32;
            let eigen = SymmetricEigen::new(covariance);
            let smallest = eigen.eigenvalues.imin();
            let normal = eigen.eigenvectors.column(smallest).into_owned().normalize();
            if !normal.iter().all(|x| x.is_finite()) {
                return None;
            }
            Some(if normal.dot(&(p.coords - centroid)) < 0.0 {
                -normal
            } else {
                normal
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_on_a_plane_get_its_normal_facing_outwards() {
        // A 10×10 grid on z = 1 plus one point below, so the centroid lies under the plane.
        let mut points: Vec<Point3<f32>> = (0..100)
            .map(|i| Point3::new((i % 10) as f32 * 0.1, (i / 10) as f32 * 0.1, 1.0))
            .collect();
        points.push(Point3::new(0.45, 0.45, -5.0));
        let index = PointIndex::new(&points).expect("non-empty");
        let normals = pca_normals(&points, &index, 0.25);
        for n in &normals[..100] {
            let n = n.expect("grid points have neighbours");
            assert!((n - Vector3::z()).norm() < 1e-4, "normal {n:?}");
        }
        assert_eq!(normals[100], None, "the lone point has no neighbourhood");
    }
}
