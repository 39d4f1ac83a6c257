//! Where the association has seen an object: the coarse voxels its masks' points fell into, each
//! with how often the object's own masks covered it and how often another mask of the same frame
//! did while the object was seen apart ([`crate::objects::instance_association`]).
//!
//! A voxel **holds** for the object when the object's masks covered it in at least
//! [`HOLDING_FRAMES`] frames and more often than other masks did. One mask is no evidence: a
//! segmenter that merges two touching objects into one mask puts the second object's voxels
//! into the first's once, and every frame that shows the second by its own mask while the first
//! has its own counts against them.

use std::collections::{HashMap, HashSet};
use std::hash::BuildHasherDefault;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::ids::{ClassId, FrameIndex};
use crate::objects::observed_cloud::{VoxelKeyHasher, pack_voxel};

/// Frames whose masks must cover a voxel before it holds for an object (module doc).
pub const HOLDING_FRAMES: u16 = 2;

/// Voxel keys.
pub type VoxelKeys = HashSet<u64, BuildHasherDefault<VoxelKeyHasher>>;

/// How often a voxel was covered, by the object's masks and by others while it was seen apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
struct VoxelEvidence {
    own: u16,
    others: u16,
}

impl VoxelEvidence {
    fn holds(self) -> bool {
        self.own >= HOLDING_FRAMES && self.own > self.others
    }
}

/// Which voxels a footprint's overlap counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Counted {
    /// Every voxel a mask covered (a candidate: its few masks are all it has).
    Covered,
    /// The voxels that hold (module doc).
    Holding,
}

/// Coarse voxels with their evidence, and the class they were seen as.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Footprint {
    /// The majority class of the masks that made it.
    pub class: ClassId,
    voxels: HashMap<u64, VoxelEvidence, BuildHasherDefault<VoxelKeyHasher>>,
    /// The first frame a mask was added.
    #[serde(default)]
    pub first_seen: u64,
    /// The last frame a mask was added.
    pub last_seen: u64,
    /// Frames whose masks were added, and the voxels they added in all (what one sighting
    /// covers, on average).
    #[serde(default)]
    sightings: (u32, u64),
}

fn cell(p: &Point3<f32>, voxel_m: f32) -> [i64; 3] {
    [p.x, p.y, p.z].map(|v| (v / voxel_m).floor() as i64)
}

/// The key of the voxel `p` falls into.
pub fn voxel_key(p: &Point3<f32>, voxel_m: f32) -> u64 {
    pack_voxel(cell(p, voxel_m))
}

/// The keys of the voxels `points` fall into.
pub fn voxel_keys(points: &[Point3<f32>], voxel_m: f32) -> VoxelKeys {
    points.iter().map(|p| voxel_key(p, voxel_m)).collect()
}

impl Footprint {
    /// An empty footprint of `class`.
    pub fn new(class: ClassId) -> Self {
        Self {
            class,
            voxels: HashMap::default(),
            first_seen: 0,
            last_seen: 0,
            sightings: (0, 0),
        }
    }

    /// Counts one frame's mask (or masks: `keys` is their union) of the object.
    pub fn add(&mut self, keys: &VoxelKeys, frame: FrameIndex) {
        for &k in keys {
            let e = self.voxels.entry(k).or_default();
            e.own = e.own.saturating_add(1);
        }
        if self.sightings.0 == 0 {
            self.first_seen = frame.0;
        }
        self.last_seen = frame.0;
        self.sightings = (self.sightings.0 + 1, self.sightings.1 + keys.len() as u64);
    }

    /// The voxels one sighting of the object adds, on average (0 before any).
    pub fn voxels_per_sighting(&self) -> f32 {
        self.sightings.1 as f32 / self.sightings.0.max(1) as f32
    }

    /// How many of `keys` hold for the object.
    pub fn holding_among(&self, keys: &VoxelKeys) -> usize {
        keys.iter().filter(|&&k| self.covers(k, Counted::Holding)).count()
    }

    /// Takes in `other`, a footprint of the same object: every voxel's counts summed.
    pub fn absorb(&mut self, other: &Footprint) {
        for (&k, e) in &other.voxels {
            let mine = self.voxels.entry(k).or_default();
            mine.own = mine.own.saturating_add(e.own);
            mine.others = mine.others.saturating_add(e.others);
        }
        self.first_seen = self.first_seen.min(other.first_seen);
        self.last_seen = self.last_seen.max(other.last_seen);
        self.sightings = (
            self.sightings.0 + other.sightings.0,
            self.sightings.1 + other.sightings.1,
        );
    }

    /// Counts against the object the voxels of `others` (masks of a frame that showed the object
    /// by its own masks, covering `own`) that its own masks did not cover.
    pub fn count_against(&mut self, others: &VoxelKeys, own: &VoxelKeys) {
        for k in others.difference(own) {
            if let Some(e) = self.voxels.get_mut(k) {
                e.others = e.others.saturating_add(1);
            }
        }
    }

    /// Whether voxel `k` is counted.
    pub fn covers(&self, k: u64, counted: Counted) -> bool {
        self.voxels.get(&k).is_some_and(|e| match counted {
            Counted::Covered => true,
            Counted::Holding => e.holds(),
        })
    }

    /// Share of `points` in or next to (one of the 26 around) a counted voxel.
    pub fn overlap(&self, points: &[Point3<f32>], voxel_m: f32, counted: Counted) -> f32 {
        let near = |[x, y, z]: [i64; 3]| {
            (-1..=1).any(|dx| {
                (-1..=1).any(|dy| (-1..=1).any(|dz| self.covers(pack_voxel([x + dx, y + dy, z + dz]), counted)))
            })
        };
        let hits = points.iter().filter(|p| near(cell(p, voxel_m))).count();
        hits as f32 / points.len().max(1) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(points: &[[f32; 3]]) -> VoxelKeys {
        let points: Vec<Point3<f32>> = points.iter().map(|&[x, y, z]| Point3::new(x, y, z)).collect();
        voxel_keys(&points, 0.05)
    }

    #[test]
    fn a_voxel_holds_after_two_own_frames_and_only_while_its_own_frames_outnumber_the_others() {
        let a = [Point3::new(0.01, 0.01, 0.01)];
        let mut f = Footprint::new(ClassId(20));
        f.add(&keys(&[[0.01, 0.01, 0.01]]), FrameIndex(0));
        assert_eq!(f.overlap(&a, 0.05, Counted::Covered), 1.0);
        assert_eq!(f.overlap(&a, 0.05, Counted::Holding), 0.0, "one mask is no evidence");
        f.add(&keys(&[[0.01, 0.01, 0.01]]), FrameIndex(1));
        assert_eq!(f.overlap(&a, 0.05, Counted::Holding), 1.0);
        // Another mask covers it twice while the object shows elsewhere: two against two.
        let elsewhere = keys(&[[1.0, 0.0, 0.0]]);
        f.count_against(&keys(&[[0.01, 0.01, 0.01]]), &elsewhere);
        assert_eq!(f.overlap(&a, 0.05, Counted::Holding), 1.0);
        f.count_against(&keys(&[[0.01, 0.01, 0.01]]), &elsewhere);
        assert_eq!(f.overlap(&a, 0.05, Counted::Holding), 0.0);
        // A voxel the object's own masks also covered in that frame is not counted against it.
        f.count_against(&keys(&[[0.01, 0.01, 0.01]]), &keys(&[[0.01, 0.01, 0.01]]));
        f.add(&keys(&[[0.01, 0.01, 0.01]]), FrameIndex(2));
        assert_eq!(f.overlap(&a, 0.05, Counted::Holding), 1.0, "three own against two");
        assert_eq!(f.last_seen, 2);
    }

    #[test]
    fn overlap_counts_points_next_to_a_voxel_and_not_two_voxels_away() {
        let mut f = Footprint::new(ClassId(20));
        f.add(&keys(&[[0.01, 0.01, 0.01]]), FrameIndex(0));
        let points = [Point3::new(0.06, 0.01, 0.01), Point3::new(0.11, 0.01, 0.01)];
        assert_eq!(f.overlap(&points, 0.05, Counted::Covered), 0.5);
    }
}
