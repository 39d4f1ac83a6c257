//! Per-frame instance masks associated into objects (`objects.association.instances =
//! "per-frame"`): what a 2D segmenter gives (ids that mean nothing beyond their frame, objects
//! missed in some frames, spurious masks, splits and merges) made into stable object ids.
//!
//! The [`InstanceTracker`] keeps, per object, the coarse voxels (`voxel_m`) its associated masks'
//! points fell into. A mask of frame *t* (its back-projected points, at most
//! `max_points_per_mask`, and its majority class) is decided against the state before frame
//! *t*:
//! - its **overlap** with an object of its class is the share of its points whose voxel or one of
//!   the 26 around it the object holds;
//! - the object of highest overlap takes it when the overlap is at least `min_overlap`, unless a
//!   second object of the class overlaps it by at least `ambiguity_ratio` × that (and
//!   `min_overlap`): the mask spans two objects (a segmenter's merge) and is held back;
//! - several masks may go to one object (a split object);
//! - a mask no object of its class takes but that an object of **another class** overlaps by at
//!   least `confused_class_overlap` shows that object under a confused class (a segmenter's
//!   occasional wrong class): it is held back and starts no candidate, so a few confused masks of
//!   one chair never make a second object on it;
//! - a mask no object takes goes to the **candidate** of its class it overlaps most (at least
//!   `min_overlap`), else starts a new candidate. A candidate seen in `min_frames` frames becomes an
//!   object with the next free id (1, 2, …); one not seen for `candidate_window_frames` frames is
//!   forgotten, so a spurious mask never makes an object;
//! - a mask with fewer than `min_points` valid depth points is held back.
//!
//! Held-back masks' pixels become unsure ([`crate::objects::segment::relabel_instances`]). Decisions
//! depend only on the masks and the state, never on the masks' own ids or their order.

use std::collections::{BTreeMap, BTreeSet, HashSet};
use std::hash::BuildHasherDefault;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::ids::{ClassId, FrameIndex, ObjectId};
use crate::objects::observed_cloud::VoxelKeyHasher;

/// Where object ids come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InstanceSource {
    /// The dataset's instance ids are one per object over the sequence (Replica, ScanNet).
    #[default]
    Consistent,
    /// Every frame numbers its masks anew; masks are associated into objects (module doc).
    PerFrame,
}

/// How masks are associated into objects (module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AssociationConfig {
    /// `"consistent"` (the default) or `"per-frame"`.
    pub instances: InstanceSource,
    /// Edge of the voxels an object's points are kept in, metres.
    pub voxel_m: f32,
    /// Least share of a mask's points near an object for the object to take it.
    pub min_overlap: f32,
    /// A second object overlapping a mask by this share of the best overlap makes it ambiguous.
    pub ambiguity_ratio: f32,
    /// Frames a candidate must be seen in to become an object.
    pub min_frames: u32,
    /// A candidate not seen for this many frames is forgotten.
    pub candidate_window_frames: u64,
    /// A mask no object of its class takes, overlapping an object of another class by at least
    /// this share, is that object under a confused class and is held back (module doc); above 1
    /// turns the check off.
    pub confused_class_overlap: f32,
    /// Points drawn from each mask (evenly over its pixels with depth).
    pub max_points_per_mask: usize,
    /// A mask with fewer valid points is held back.
    pub min_points: usize,
}

impl Default for AssociationConfig {
    fn default() -> Self {
        Self {
            instances: InstanceSource::Consistent,
            voxel_m: 0.05,
            min_overlap: 0.3,
            ambiguity_ratio: 0.5,
            min_frames: 3,
            candidate_window_frames: 30,
            confused_class_overlap: 0.5,
            max_points_per_mask: 400,
            min_points: 20,
        }
    }
}

/// One mask of a frame, as the association sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct MaskEvidence {
    /// The mask's id in its frame.
    pub local: ObjectId,
    /// Its majority class.
    pub class: ClassId,
    /// Back-projected points of its pixels, in world coordinates.
    pub points: Vec<Point3<f32>>,
}

/// Why a mask was held back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HoldReason {
    /// It belongs to a candidate not yet seen in enough frames.
    Candidate,
    /// It overlaps two objects of its class alike.
    Ambiguous,
    /// Too few of its pixels have depth.
    TooFewPoints,
    /// It shows an object of another class (its class confused).
    ConfusedClass,
}

/// What became of a mask.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaskFate {
    /// It shows this object.
    Object(ObjectId),
    /// It is held back (its pixels become unknown).
    Held(HoldReason),
}

type VoxelSet = HashSet<u64, BuildHasherDefault<VoxelKeyHasher>>;

/// Points kept as coarse voxels, with their class.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Footprint {
    class: ClassId,
    voxels: VoxelSet,
    last_seen: u64,
}

/// A mask seen too few times yet.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Candidate {
    footprint: Footprint,
    frames: u32,
}

/// The association's memory (module doc); checkpointed with the map.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct InstanceTracker {
    objects: BTreeMap<ObjectId, Footprint>,
    candidates: Vec<Candidate>,
}

/// Packs voxel `(x, y, z)` (21 bits each) into a key.
fn key(x: i64, y: i64, z: i64) -> u64 {
    const MASK: i64 = (1 << 21) - 1;
    const OFFSET: i64 = 1 << 20;
    let c = |v: i64| ((v + OFFSET) & MASK) as u64;
    (c(x) << 42) | (c(y) << 21) | c(z)
}

/// Whether voxel `[x, y, z]` or one of the 26 around it is in `voxels`.
fn near(voxels: &VoxelSet, [x, y, z]: [i64; 3]) -> bool {
    (-1..=1).any(|dx| (-1..=1).any(|dy| (-1..=1).any(|dz| voxels.contains(&key(x + dx, y + dy, z + dz)))))
}

fn cell(p: &Point3<f32>, voxel_m: f32) -> [i64; 3] {
    [p.x, p.y, p.z].map(|v| (v / voxel_m).floor() as i64)
}

impl Footprint {
    fn new(class: ClassId) -> Self {
        Self {
            class,
            voxels: VoxelSet::default(),
            last_seen: 0,
        }
    }

    fn add(&mut self, points: &[Point3<f32>], voxel_m: f32, frame: FrameIndex) {
        for p in points {
            let [x, y, z] = cell(p, voxel_m);
            self.voxels.insert(key(x, y, z));
        }
        self.last_seen = frame.0;
    }

    /// Share of `points` in or next to a voxel of the footprint.
    fn overlap(&self, points: &[Point3<f32>], voxel_m: f32) -> f32 {
        let hits = points.iter().filter(|p| near(&self.voxels, cell(p, voxel_m))).count();
        hits as f32 / points.len().max(1) as f32
    }
}

/// The best of `overlaps` (highest, then lowest key) and whether a second one rivals it.
fn best<K: Copy + Ord>(overlaps: &mut [(K, f32)], cfg: &AssociationConfig) -> Option<(K, bool)> {
    overlaps.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let (k, top) = *overlaps.first()?;
    if top < cfg.min_overlap {
        return None;
    }
    let rival = overlaps
        .get(1)
        .is_some_and(|&(_, second)| second >= cfg.min_overlap && second >= cfg.ambiguity_ratio * top);
    Some((k, rival))
}

impl InstanceTracker {
    /// Number of objects made so far.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Number of candidates waiting.
    pub fn candidate_count(&self) -> usize {
        self.candidates.len()
    }

    /// Decides every mask of frame `frame` (module doc) and updates the memory.
    pub fn associate(
        &mut self,
        frame: FrameIndex,
        masks: &[MaskEvidence],
        cfg: &AssociationConfig,
    ) -> BTreeMap<ObjectId, MaskFate> {
        let window = cfg.candidate_window_frames;
        self.candidates
            .retain(|c| frame.0.saturating_sub(c.footprint.last_seen) <= window);
        let v = cfg.voxel_m;
        // Decide every mask against the state before this frame.
        enum Decision {
            Fate(MaskFate),
            ToCandidate(usize),
            NewCandidate,
        }
        let decisions: Vec<Decision> = masks
            .iter()
            .map(|m| {
                if m.points.len() < cfg.min_points {
                    return Decision::Fate(MaskFate::Held(HoldReason::TooFewPoints));
                }
                let mut overlaps: Vec<(ObjectId, f32)> = self
                    .objects
                    .iter()
                    .filter(|(_, f)| f.class == m.class)
                    .map(|(&id, f)| (id, f.overlap(&m.points, v)))
                    .collect();
                match best(&mut overlaps, cfg) {
                    Some((_, true)) => Decision::Fate(MaskFate::Held(HoldReason::Ambiguous)),
                    Some((id, false)) => Decision::Fate(MaskFate::Object(id)),
                    None if self
                        .objects
                        .values()
                        .any(|f| f.class != m.class && f.overlap(&m.points, v) >= cfg.confused_class_overlap) =>
                    {
                        Decision::Fate(MaskFate::Held(HoldReason::ConfusedClass))
                    }
                    None => {
                        let mut overlaps: Vec<(usize, f32)> = (self.candidates.iter().enumerate())
                            .filter(|(_, c)| c.footprint.class == m.class)
                            .map(|(i, c)| (i, c.footprint.overlap(&m.points, v)))
                            .collect();
                        best(&mut overlaps, cfg).map_or(Decision::NewCandidate, |(i, _)| Decision::ToCandidate(i))
                    }
                }
            })
            .collect();
        // Apply: objects and candidates take their masks' points.
        let mut fates = BTreeMap::new();
        let mut slots: Vec<(ObjectId, usize)> = Vec::new();
        for (m, decision) in masks.iter().zip(decisions) {
            let slot = match decision {
                Decision::Fate(fate) => {
                    if let MaskFate::Object(id) = fate
                        && let Some(footprint) = self.objects.get_mut(&id)
                    {
                        footprint.add(&m.points, v, frame);
                    }
                    fates.insert(m.local, fate);
                    continue;
                }
                Decision::ToCandidate(i) => i,
                Decision::NewCandidate => {
                    self.candidates.push(Candidate {
                        footprint: Footprint::new(m.class),
                        frames: 0,
                    });
                    self.candidates.len() - 1
                }
            };
            self.candidates[slot].footprint.add(&m.points, v, frame);
            slots.push((m.local, slot));
        }
        // Candidates seen in this frame count it; those seen in enough frames become objects.
        let seen: BTreeSet<usize> = slots.iter().map(|&(_, slot)| slot).collect();
        let mut promoted: BTreeMap<usize, ObjectId> = BTreeMap::new();
        for slot in seen {
            let candidate = &mut self.candidates[slot];
            candidate.frames += 1;
            if candidate.frames >= cfg.min_frames {
                let id = ObjectId(self.objects.keys().next_back().map_or(1, |last| last.0 + 1));
                self.objects.insert(id, candidate.footprint.clone());
                promoted.insert(slot, id);
            }
        }
        for (local, slot) in slots {
            let fate = promoted
                .get(&slot)
                .map_or(MaskFate::Held(HoldReason::Candidate), |&id| MaskFate::Object(id));
            fates.insert(local, fate);
        }
        let mut slot = 0;
        self.candidates.retain(|_| {
            slot += 1;
            !promoted.contains_key(&(slot - 1))
        });
        fates
    }
}

#[cfg(test)]
#[path = "instance_association_tests.rs"]
mod tests;
