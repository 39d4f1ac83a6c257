//! An object's observed point cloud: every masked depth pixel, accumulated in a voxel grid.
//!
//! Each occupied voxel keeps the centroid of the points that fell into it, so the cloud grows
//! with new views but not with repeated ones. Voxels are never removed: the cloud only grows.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use nalgebra::{Point3, Vector3};

use crate::sensor::frame::RgbdFrame;

/// Packs a voxel coordinate into one integer key (21 bits per axis, ±10 km at 1 cm).
#[inline]
fn voxel_key(p: &Point3<f32>, inv_voxel: f32) -> u64 {
    const OFFSET: i64 = 1 << 20;
    const MASK: i64 = (1 << 21) - 1;
    let c = |x: f32| ((floor_to_i64(x * inv_voxel) + OFFSET) & MASK) as u64;
    (c(p.x) << 42) | (c(p.y) << 21) | c(p.z)
}

/// `x.floor() as i64` without a libm call (exact for finite `x` in the key's range).
#[inline]
fn floor_to_i64(x: f32) -> i64 {
    let truncated = x as i64;
    truncated - i64::from(x < truncated as f32)
}

/// A fast hasher for packed voxel keys (multiplicative, like FxHash). Deterministic.
#[derive(Default, Clone, Copy)]
pub struct VoxelKeyHasher(u64);

impl Hasher for VoxelKeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(5) ^ u64::from(b)).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
        }
    }
    fn write_u64(&mut self, key: u64) {
        self.0 = (self.0 ^ key).wrapping_mul(0x9e37_79b9_7f4a_7c15).rotate_left(26);
    }
}

#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
struct VoxelSum {
    sum: Vector3<f64>,
    count: u32,
}

/// Points observed on one object (or the background), thinned by a voxel grid.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ObservedCloud {
    voxel_m: f32,
    voxels: HashMap<u64, VoxelSum, BuildHasherDefault<VoxelKeyHasher>>,
    points_added: u64,
}

impl ObservedCloud {
    /// An empty cloud on a grid of `voxel_m` metres.
    pub fn new(voxel_m: f32) -> Self {
        debug_assert!(voxel_m > 0.0, "voxel edge must be positive");
        Self {
            voxel_m,
            voxels: HashMap::default(),
            points_added: 0,
        }
    }

    /// Edge of the voxel grid, metres.
    pub fn voxel_m(&self) -> f32 {
        self.voxel_m
    }

    /// Adds one world point.
    #[inline]
    pub fn add_point(&mut self, p: &Point3<f32>) {
        let key = voxel_key(p, 1.0 / self.voxel_m);
        self.add_to_voxel(key, p.coords.cast::<f64>(), 1);
    }

    #[inline]
    fn add_to_voxel(&mut self, key: u64, sum: Vector3<f64>, count: u32) {
        let v = self.voxels.entry(key).or_insert(VoxelSum {
            sum: Vector3::zeros(),
            count: 0,
        });
        v.sum += sum;
        v.count += count;
        self.points_added += u64::from(count);
    }

    /// Back-projects the listed pixels of `frame` (invalid depth skipped) and adds them.
    /// Returns how many points were added.
    ///
    /// Neighbouring pixels mostly fall into the same voxel: runs of equal keys are summed first
    /// and looked up in the grid once.
    pub fn add_pixels(&mut self, frame: &RgbdFrame, pixels: &[u32]) -> usize {
        let inv_voxel = 1.0 / self.voxel_m;
        let mut run: Option<(u64, Vector3<f64>, u32)> = None;
        let mut added = 0;
        for &i in pixels {
            let Some(p) = frame.point_in_world(i as usize) else {
                continue;
            };
            added += 1;
            let key = voxel_key(&p, inv_voxel);
            let coords = p.coords.cast::<f64>();
            match &mut run {
                Some((run_key, sum, count)) if *run_key == key => {
                    *sum += coords;
                    *count += 1;
                }
                _ => {
                    if let Some((run_key, sum, count)) = run.replace((key, coords, 1)) {
                        self.add_to_voxel(run_key, sum, count);
                    }
                }
            }
        }
        if let Some((run_key, sum, count)) = run {
            self.add_to_voxel(run_key, sum, count);
        }
        added
    }

    /// Number of occupied voxels (= points of [`ObservedCloud::points`]).
    pub fn len(&self) -> usize {
        self.voxels.len()
    }

    /// True when nothing was observed yet.
    pub fn is_empty(&self) -> bool {
        self.voxels.is_empty()
    }

    /// Raw points added so far (before thinning).
    pub fn points_added(&self) -> u64 {
        self.points_added
    }

    /// One point per occupied voxel (the centroid of its points), sorted by voxel key so that
    /// the order does not depend on hashing.
    pub fn points(&self) -> Vec<Point3<f32>> {
        self.points_of_voxels_with(1)
    }

    /// The centroids of the voxels holding at least `min_points` points, in key order.
    pub fn points_of_voxels_with(&self, min_points: u32) -> Vec<Point3<f32>> {
        let mut keyed: Vec<(u64, Point3<f32>)> = self
            .voxels
            .iter()
            .filter(|(_, v)| v.count >= min_points)
            .map(|(&k, v)| (k, Point3::from((v.sum / f64::from(v.count)).cast::<f32>())))
            .collect();
        keyed.sort_unstable_by_key(|(k, _)| *k);
        keyed.into_iter().map(|(_, p)| p).collect()
    }
}

/// Thins `points` to one centroid per `voxel_m` voxel, in a deterministic (key-sorted) order.
pub fn voxel_downsample(points: &[Point3<f32>], voxel_m: f32) -> Vec<Point3<f32>> {
    let mut cloud = ObservedCloud::new(voxel_m);
    for p in points {
        cloud.add_point(p);
    }
    cloud.points()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_in_one_voxel_merge_into_their_centroid() {
        let mut cloud = ObservedCloud::new(0.01);
        cloud.add_point(&Point3::new(0.001, 0.002, 0.003));
        cloud.add_point(&Point3::new(0.003, 0.004, 0.005));
        cloud.add_point(&Point3::new(0.5, 0.5, 0.5));
        assert_eq!(cloud.len(), 2);
        assert_eq!(cloud.points_added(), 3);
        let points = cloud.points();
        assert!(
            points
                .iter()
                .any(|p| (p - Point3::new(0.002, 0.003, 0.004)).norm() < 1e-6)
        );
    }

    #[test]
    fn the_fast_floor_matches_floor() {
        for x in [-2.5_f32, -2.0, -1.0, -0.5, -0.0, 0.0, 0.25, 1.0, 1.75, 1e6, -1e6 - 0.5] {
            assert_eq!(floor_to_i64(x), x.floor() as i64, "floor of {x}");
        }
    }

    #[test]
    fn pixel_runs_give_the_same_cloud_as_single_points() {
        use crate::ids::{ClassId, FrameIndex};
        use crate::sensor::frame::{CameraIntrinsics, InstanceMask};
        let (width, height) = (8, 4);
        let frame = RgbdFrame {
            index: FrameIndex(0),
            world_from_camera: nalgebra::Isometry3::translation(0.1, -0.2, 0.3),
            intrinsics: CameraIntrinsics {
                width,
                height,
                fx: 50.0,
                fy: 50.0,
                cx: 3.5,
                cy: 1.5,
            },
            rgb: vec![[0; 3]; 32],
            depth_m: (0..32)
                .map(|i| if i % 5 == 0 { 0.0 } else { 1.0 + 0.01 * i as f32 })
                .collect(),
            instances: InstanceMask::background(32),
            classes: vec![ClassId(0); 32],
        };
        let pixels: Vec<u32> = (0..32).collect();
        let mut by_pixels = ObservedCloud::new(0.01);
        let added = by_pixels.add_pixels(&frame, &pixels);
        let mut by_points = ObservedCloud::new(0.01);
        for &i in &pixels {
            if let Some(p) = frame.point_in_world(i as usize) {
                by_points.add_point(&p);
            }
        }
        assert_eq!(added, 25, "every fifth pixel has no depth");
        assert_eq!(by_pixels.points_added(), by_points.points_added());
        assert_eq!(by_pixels.len(), by_points.len(), "same voxels either way");
        for (a, b) in by_pixels.points().iter().zip(by_points.points()) {
            assert!((a - b).norm() < 1e-6, "same centroids either way");
        }
    }

    #[test]
    fn negative_coordinates_get_their_own_voxels() {
        let mut cloud = ObservedCloud::new(0.1);
        cloud.add_point(&Point3::new(-0.05, 0.0, 0.0));
        cloud.add_point(&Point3::new(0.05, 0.0, 0.0));
        assert_eq!(cloud.len(), 2, "the grid is split at 0, not rounded towards it");
    }

    #[test]
    fn the_point_order_does_not_depend_on_insertion_order() {
        let pts: Vec<Point3<f32>> = (0..50)
            .map(|i| Point3::new(i as f32 * 0.03, (i % 7) as f32 * 0.1, 0.0))
            .collect();
        let mut reversed = pts.clone();
        reversed.reverse();
        assert_eq!(voxel_downsample(&pts, 0.02), voxel_downsample(&reversed, 0.02));
    }
}
