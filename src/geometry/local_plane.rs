//! The least-squares plane of a neighbourhood of points: its centre and the axes of its spread,
//! least first (the plane's normal), with the spread along each.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

/// A neighbourhood's least-squares plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalPlane {
    /// The neighbourhood's mean.
    pub centre: Vector3<f64>,
    /// The eigenvalues of its covariance, smallest first.
    pub spreads: [f64; 3],
    /// Their unit eigenvectors, in the same order: `axes[0]` is the plane's normal.
    pub axes: [Vector3<f64>; 3],
}

impl LocalPlane {
    /// The plane of `points` (covariance (1/n) Σ (p − μ)(p − μ)ᵀ about their mean μ; the iterator
    /// is walked twice); `None` when there are none.
    pub fn fit<I>(points: I) -> Option<Self>
    where
        I: Iterator<Item = Vector3<f64>> + Clone,
    {
        let n = points.clone().count();
        if n == 0 {
            return None;
        }
        let n = n as f64;
        let centre = points.clone().sum::<Vector3<f64>>() / n;
        let covariance: Matrix3<f64> = points
            .map(|p| {
                let d = p - centre;
                d * d.transpose()
            })
            .sum::<Matrix3<f64>>()
            / n;
        let eigen = SymmetricEigen::new(covariance);
        let mut order = [0, 1, 2];
        order.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
        Some(Self {
            centre,
            spreads: order.map(|k| eigen.eigenvalues[k]),
            axes: order.map(|k| eigen.eigenvectors.column(k).into_owned()),
        })
    }

    /// The plane's unit normal (the axis of least spread).
    pub fn normal(&self) -> Vector3<f64> {
        self.axes[0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tilted_grid_has_its_normal_least_spread_and_its_mean_as_centre() {
        let normal = Vector3::new(0.0, 0.6, 0.8);
        let (u, v) = (Vector3::x(), Vector3::new(0.0, 0.8, -0.6));
        let points: Vec<Vector3<f64>> = (0..100)
            .map(|i| Vector3::new(1.0, 2.0, 3.0) + u * f64::from(i % 10) * 0.1 + v * f64::from(i / 10) * 0.05)
            .collect();
        let plane = LocalPlane::fit(points.iter().copied()).expect("points");
        assert!(plane.normal().dot(&normal).abs() > 1.0 - 1e-9);
        assert!(plane.spreads[0].abs() < 1e-12 && plane.spreads[0] <= plane.spreads[1]);
        assert!(plane.spreads[1] <= plane.spreads[2], "least first");
        assert!((plane.axes[2].dot(&u)).abs() > 1.0 - 1e-9, "the widest spread along u");
        let mean = points.iter().sum::<Vector3<f64>>() / 100.0;
        assert!((plane.centre - mean).norm() < 1e-12);
        assert_eq!(LocalPlane::fit(std::iter::empty()), None);
    }
}
