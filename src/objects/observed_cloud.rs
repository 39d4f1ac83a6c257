//! An object's observed point cloud: every masked depth pixel, accumulated in a voxel grid.
//!
//! Each occupied voxel keeps the centroid of the points that fell into it, so the cloud grows
//! with new views but not with repeated ones. Voxels are never removed: the cloud only grows.
//!
//! Each voxel also keeps what the views of its owner said of it ([`ViewVotes`],
//! [`ObservedCloud::add_view`]): how many frames saw its surface under the owner's mask and how
//! many under another label (the background, another object). A segmenter's mask that bled a
//! pixel onto the floor beside a chair's leg or the wall behind a sofa puts a voxel in the cloud
//! that the other views see as floor or wall; such a *contested* voxel (more than four views
//! elsewhere for each of the owner's) is left out of [`ObservedCloud::points`], so it neither grows the object's box
//! nor enters its registration. With exact masks no voxel is contested.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use nalgebra::{Point3, Vector3};

use crate::ids::ObjectId;
use crate::sensor::frame::{InstanceLabel, RgbdFrame};

/// A view sees a voxel's surface when the depth at the voxel's pixel lies within this of the
/// voxel centroid's depth (plus the depth's noise allowance), metres: a 1 cm voxel's centroid
/// lies within a centimetre of the surface it sums.
pub const VIEW_DEPTH_TOLERANCE_M: f32 = 0.02;

/// What the views of a cloud's owner said of one voxel: the frames whose pixel at the voxel saw
/// its surface under the owner's label, and under another (background or another object).
/// Unsure and unknown pixels, and views that saw something nearer or farther, say nothing.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ViewVotes {
    /// Frames that saw the voxel under its owner's label.
    pub own: u32,
    /// Frames that saw it under another label.
    pub elsewhere: u32,
}

/// A voxel is contested when more than this many of the views that saw it saw something else
/// for each one that saw its owner. A voxel where an object meets the floor sums both, and the
/// views split over it (on the default scene's exact masks one voxel of the scene beyond 3.1 to 1,
/// at 5 to 1); a bled pixel's voxel is its owner's in the one or two frames that bled.
pub const CONTESTED_RATIO: u32 = 4;

impl ViewVotes {
    /// More than [`CONTESTED_RATIO`] views saw the voxel as something else for each that saw it
    /// as its owner.
    pub fn contested(&self) -> bool {
        self.elsewhere > CONTESTED_RATIO * self.own
    }

    /// At least half the views that saw the voxel saw it as its owner (true when none voted).
    pub fn mostly_own(&self) -> bool {
        self.own >= self.elsewhere
    }
}

/// Whether an object's views vote on its cloud's voxels (`objects.voxel_votes`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VoxelVotes {
    /// Every frame that segments the object votes on every voxel of its cloud in view; contested
    /// voxels are left out of its points (module doc).
    #[default]
    ByViews,
    /// No votes: every voxel counts.
    Off,
}

/// Packs a voxel coordinate into one integer key (21 bits per axis, ±10 km at 1 cm).
#[inline]
fn voxel_key(p: &Point3<f32>, inv_voxel: f32) -> u64 {
    pack_voxel([p.x, p.y, p.z].map(|x| floor_to_i64(x * inv_voxel)))
}

/// Packs integer voxel coordinates into one key (21 bits per axis).
#[inline]
pub(crate) fn pack_voxel([x, y, z]: [i64; 3]) -> u64 {
    const OFFSET: i64 = 1 << 20;
    const MASK: i64 = (1 << 21) - 1;
    let c = |v: i64| ((v + OFFSET) & MASK) as u64;
    (c(x) << 42) | (c(y) << 21) | c(z)
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
    votes: ViewVotes,
}

impl VoxelSum {
    fn centroid(&self) -> Point3<f32> {
        Point3::from((self.sum / f64::from(self.count)).cast::<f32>())
    }
}

/// Points observed on one object (or the background), thinned by a voxel grid.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ObservedCloud {
    voxel_m: f32,
    voxels: HashMap<u64, VoxelSum, BuildHasherDefault<VoxelKeyHasher>>,
    points_added: u64,
    /// Sum over the points back-projected from frames of the distance between neighbouring
    /// pixels' points at the point's depth (depth / focal length), metres; and their number.
    spacing_sum_m: f64,
    spaced_points: u64,
}

impl ObservedCloud {
    /// An empty cloud on a grid of `voxel_m` metres.
    pub fn new(voxel_m: f32) -> Self {
        debug_assert!(voxel_m > 0.0, "voxel edge must be positive");
        Self {
            voxel_m,
            voxels: HashMap::default(),
            points_added: 0,
            spacing_sum_m: 0.0,
            spaced_points: 0,
        }
    }

    /// Edge of the voxel grid, metres.
    pub fn voxel_m(&self) -> f32 {
        self.voxel_m
    }

    /// The mean distance between neighbouring pixels' points on the object's surface, over the
    /// points its frames gave it (each point's depth over the focal length), metres: how densely
    /// the camera samples the object. `None` before any frame.
    pub fn point_spacing_m(&self) -> Option<f32> {
        (self.spaced_points > 0).then(|| (self.spacing_sum_m / self.spaced_points as f64) as f32)
    }

    /// Adds one world point.
    #[inline]
    pub fn add_point(&mut self, p: &Point3<f32>) {
        let key = voxel_key(p, 1.0 / self.voxel_m);
        self.add_to_voxel(key, p.coords.cast::<f64>(), 1);
    }

    #[inline]
    fn add_to_voxel(&mut self, key: u64, sum: Vector3<f64>, count: u32) -> &mut VoxelSum {
        self.points_added += u64::from(count);
        let v = self.voxels.entry(key).or_insert(VoxelSum {
            sum: Vector3::zeros(),
            count: 0,
            votes: ViewVotes::default(),
        });
        v.sum += sum;
        v.count += count;
        v
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
        let mut depth_sum_m = 0.0f64;
        for &i in pixels {
            let Some(p) = frame.point_in_world(i as usize) else {
                continue;
            };
            added += 1;
            depth_sum_m += f64::from(frame.depth_m[i as usize]);
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
        let focal_px = 0.5 * f64::from(frame.intrinsics.fx + frame.intrinsics.fy);
        self.spacing_sum_m += depth_sum_m / focal_px;
        self.spaced_points += added as u64;
        added
    }

    /// One view of the cloud's owner `owner`: adds `pixels` (its mask's pixels, as
    /// [`ObservedCloud::add_pixels`]) and, under [`VoxelVotes::ByViews`], lets `frame` vote on
    /// every voxel in view: the label at the voxel's pixel when the depth there lies within
    /// [`VIEW_DEPTH_TOLERANCE_M`] + `depth_noise_per_m2` · z² of the voxel's depth z.
    pub fn add_view(
        &mut self,
        frame: &RgbdFrame,
        pixels: &[u32],
        owner: ObjectId,
        votes: VoxelVotes,
        depth_noise_per_m2: f32,
    ) -> usize {
        let added = self.add_pixels(frame, pixels);
        if votes == VoxelVotes::ByViews {
            let camera_from_world = frame.world_from_camera.inverse();
            let (w, h) = (frame.intrinsics.width as f32, frame.intrinsics.height as f32);
            for voxel in self.voxels.values_mut() {
                let p = camera_from_world * voxel.centroid();
                let Some((u, v)) = frame.intrinsics.project(&p) else {
                    continue;
                };
                let (u, v) = (u.round(), v.round());
                if !(u >= 0.0 && v >= 0.0 && u < w && v < h) {
                    continue;
                }
                let i = v as usize * frame.intrinsics.width as usize + u as usize;
                let d = frame.depth_m[i];
                if d.is_nan() || d <= 0.0 || (d - p.z).abs() > VIEW_DEPTH_TOLERANCE_M + depth_noise_per_m2 * p.z * p.z {
                    continue;
                }
                match frame.instances.label(i) {
                    InstanceLabel::Object(id) if id == owner => voxel.votes.own += 1,
                    InstanceLabel::Object(_) | InstanceLabel::Background => voxel.votes.elsewhere += 1,
                    InstanceLabel::Unsure | InstanceLabel::Unknown => {}
                }
            }
        }
        added
    }

    /// Adds one world point and `votes` to its voxel's votes (tests' fixtures).
    #[cfg(test)]
    pub(crate) fn add_voted_point(&mut self, p: &Point3<f32>, votes: ViewVotes) {
        let key = voxel_key(p, 1.0 / self.voxel_m);
        let voxel = self.add_to_voxel(key, p.coords.cast::<f64>(), 1);
        voxel.votes.own += votes.own;
        voxel.votes.elsewhere += votes.elsewhere;
    }

    /// Sets the points' spacing as if every point had come from views at that spacing (tests'
    /// fixtures).
    #[cfg(test)]
    pub(crate) fn set_point_spacing(&mut self, spacing_m: f32) {
        self.spacing_sum_m = f64::from(spacing_m);
        self.spaced_points = 1;
    }

    /// Takes in the cloud of an object found to be part of this one (on the same grid): points
    /// and view votes add up voxel by voxel.
    pub fn absorb(&mut self, other: &ObservedCloud) {
        self.spacing_sum_m += other.spacing_sum_m;
        self.spaced_points += other.spaced_points;
        for (&key, theirs) in &other.voxels {
            let votes = &mut self.add_to_voxel(key, theirs.sum, theirs.count).votes;
            votes.own += theirs.votes.own;
            votes.elsewhere += theirs.votes.elsewhere;
        }
    }

    /// Every occupied voxel, contested or not: its centroid, its point count and its view votes,
    /// in key order.
    pub fn voxels(&self) -> Vec<(Point3<f32>, u32, ViewVotes)> {
        let mut keyed: Vec<(u64, (Point3<f32>, u32, ViewVotes))> = self
            .voxels
            .iter()
            .map(|(&k, v)| (k, (v.centroid(), v.count, v.votes)))
            .collect();
        keyed.sort_unstable_by_key(|(k, _)| *k);
        keyed.into_iter().map(|(_, v)| v).collect()
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

    /// One point per occupied voxel that is not contested (the centroid of its points), sorted
    /// by voxel key so that the order does not depend on hashing.
    pub fn points(&self) -> Vec<Point3<f32>> {
        self.points_of_voxels_with(1)
    }

    /// The centroids of the uncontested voxels holding at least `min_points` points, in key
    /// order.
    pub fn points_of_voxels_with(&self, min_points: u32) -> Vec<Point3<f32>> {
        self.points_of_voxels_where(|count, votes| count >= min_points && !votes.contested())
    }

    /// The centroids of the voxels whose point count and view votes `keep` takes, in key order.
    pub fn points_of_voxels_where(&self, keep: impl Fn(u32, ViewVotes) -> bool) -> Vec<Point3<f32>> {
        let mut keyed: Vec<(u64, Point3<f32>)> = self
            .voxels
            .iter()
            .filter(|(_, v)| keep(v.count, v.votes))
            .map(|(&k, v)| (k, v.centroid()))
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
#[path = "observed_cloud_tests.rs"]
mod tests;
