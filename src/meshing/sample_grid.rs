//! A regular grid of scalar samples in some local frame: where sample `(i, j, k)` sits.

use nalgebra::{Point3, Vector3};

use crate::error::{CatmapError, Result};

/// Sample positions of a dense `nx × ny × nz` grid: sample `(i, j, k)` sits at
/// `origin + (i·voxel.x, j·voxel.y, k·voxel.z)`. Values are stored x fastest, then y, then z:
/// `index = i + nx·(j + ny·k)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleGrid {
    /// Position of sample `(0, 0, 0)`.
    pub origin: Point3<f32>,
    /// Spacing between neighbouring samples along x, y and z (all positive).
    pub voxel_size: Vector3<f32>,
    /// Number of samples along x, y and z.
    pub dims: [usize; 3],
}

impl SampleGrid {
    /// A grid with the same spacing on every axis.
    pub fn cubic(origin: Point3<f32>, voxel_size: f32, dims: [usize; 3]) -> Self {
        Self {
            origin,
            voxel_size: Vector3::repeat(voxel_size),
            dims,
        }
    }

    /// Total number of samples.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// True when the grid has no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Samples in one z-layer (`nx·ny`).
    pub fn layer_len(&self) -> usize {
        self.dims[0] * self.dims[1]
    }

    /// Position of sample `(i, j, k)` (indices may lie outside the grid, e.g. for padding).
    pub fn position(&self, i: f64, j: f64, k: f64) -> Point3<f32> {
        let o = self.origin.coords.cast::<f64>();
        let v = self.voxel_size.cast::<f64>();
        Point3::new(o.x + i * v.x, o.y + j * v.y, o.z + k * v.z).cast::<f32>()
    }

    /// The sample positions of z-layer `k`, x fastest, appended to `out` (cleared first).
    pub fn layer_positions(&self, k: usize, out: &mut Vec<Point3<f32>>) {
        out.clear();
        out.reserve(self.layer_len());
        for j in 0..self.dims[1] {
            for i in 0..self.dims[0] {
                out.push(self.position(i as f64, j as f64, k as f64));
            }
        }
    }

    /// Checks that the spacing is positive and finite, the origin finite and the grid not empty.
    pub fn validate(&self) -> Result<()> {
        if self.is_empty() {
            return Err(CatmapError::bad_value(
                "the dimensions of a sample grid",
                self.dims,
                "be at least 1 on every axis",
            ));
        }
        if !self.voxel_size.iter().all(|v| v.is_finite() && *v > 0.0) {
            return Err(CatmapError::bad_value(
                "a sample grid's voxel size",
                self.voxel_size,
                "be positive and finite",
            ));
        }
        if !self.origin.coords.iter().all(|v| v.is_finite()) {
            return Err(CatmapError::bad_value(
                "a sample grid's origin",
                self.origin,
                "be finite",
            ));
        }
        if u32::try_from(self.len()).is_err() {
            return Err(CatmapError::bad_value(
                "the dimensions of a sample grid",
                self.dims,
                "hold fewer than 2³² samples",
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layer_positions_run_x_fastest() {
        let grid = SampleGrid::cubic(Point3::new(1.0, 2.0, 3.0), 0.5, [2, 3, 4]);
        let mut layer = Vec::new();
        grid.layer_positions(2, &mut layer);
        assert_eq!(layer.len(), 6, "nx·ny samples per layer");
        assert_eq!(layer[1], Point3::new(1.5, 2.0, 4.0), "second sample steps along x");
        assert_eq!(layer[2], Point3::new(1.0, 2.5, 4.0), "third sample starts the next row");
    }

    #[test]
    fn empty_or_flat_grids_are_rejected() {
        assert!(SampleGrid::cubic(Point3::origin(), 0.1, [0, 4, 4]).validate().is_err());
        assert!(SampleGrid::cubic(Point3::origin(), 0.0, [4, 4, 4]).validate().is_err());
        assert!(
            SampleGrid::cubic(Point3::origin(), f32::NAN, [4, 4, 4])
                .validate()
                .is_err()
        );
        assert!(SampleGrid::cubic(Point3::origin(), 0.1, [4, 4, 4]).validate().is_ok());
    }
}
