//! Per-frame instance masks associated into objects (`objects.association.instances =
//! "per-frame"`): what a 2D segmenter gives (ids that mean nothing beyond their frame, objects
//! missed in some frames, spurious masks, splits and merges) made into stable object ids.
//!
//! The [`InstanceTracker`] keeps, per object, a [`Footprint`]: the coarse voxels (`voxel_m`) its
//! masks' points fell into, each with how often the object's masks covered it and how often other
//! masks did while the object was seen apart; a voxel **holds** for the object once two of its
//! frames covered it and its own frames outnumber the others (one mask is no evidence: a
//! segmenter's merge). A mask of frame *t* (its back-projected points, at most
//! `max_points_per_mask`, and its majority class) is decided against the state before frame
//! *t*:
//! - its **overlap** with an object of its class is the share of its points whose voxel or one of
//!   the 26 around it holds for the object;
//! - the object of highest overlap takes it when the overlap is at least `min_overlap`, unless a
//!   second object of the class overlaps it by at least `ambiguity_ratio` × that (and
//!   `min_overlap`): the mask spans two objects (a segmenter's merge) and is held back;
//! - several masks may go to one object (a split object): the one of highest overlap, and any
//!   other most of whose points lie on the object ([`SPLIT_MASK_OVERLAP`]); a mask below that is
//!   decided again without the object (a neighbour the object's footprint reaches). Of the masks
//!   an object takes in a frame, the one of most points on it is its own: the voxels of the others
//!   that it did not cover count against the object as another mask's would. An object its
//!   segmenter splits now and then keeps them (its own masks cover them in most frames); an
//!   object made of two that one mask covered in its first frames (adjacent in the image, metres
//!   apart) lets the second go once frames showing them apart outnumber those;
//! - a mask no object of its class takes but that an object of **another class** overlaps by at
//!   least `confused_class_overlap` shows that object under a confused class (a segmenter's
//!   occasional wrong class): it is held back and starts no candidate, so a few confused masks of
//!   one chair never make a second object on it;
//! - a mask no object takes goes to the **candidate** of its class it overlaps most (at least
//!   `min_overlap`), else starts a new candidate. A candidate seen in `min_frames` frames becomes an
//!   object with the next free id (1, 2, …); one not seen for `candidate_window_frames` frames is
//!   forgotten, so a spurious mask never makes an object. A candidate that two masks of one frame
//!   go to was two objects seen as one mask: it is dropped and each mask starts a candidate;
//! - a mask with fewer than `min_points` valid depth points is held back.
//!
//! An object's footprint grows only into voxels no other object holds and no candidate of its
//! class covers: what a mask merging it with a neighbour not yet made adds is the neighbour's.
//! Held-back masks' pixels become unsure ([`crate::objects::segment::relabel_instances`]). Decisions
//! depend only on the masks and the state, never on the masks' own ids or their order.
//!
//! An object made twice (its ends seen in views that barely overlap as the camera panned, or a
//! fragment of a mask the segmenter split) is **merged**: two objects of one class shown joined
//! (one mask over both) in more frames than apart, and in at least two, become the one of lower
//! id once the younger was first seen `candidate_window_frames` ago
//! ([`crate::objects::pair_evidence`]); [`FrameAssociation::merges`] reports it and the map
//! takes the other's sightings into it ([`crate::objects::object_merge`]).

use std::collections::{BTreeMap, BTreeSet};

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::ids::{ClassId, FrameIndex, ObjectId};
pub use crate::objects::association_config::{AssociationConfig, InstanceSource};
use crate::objects::mask_footprint::{Counted, Footprint, VoxelKeys, voxel_keys};
pub use crate::objects::pair_evidence::ObjectMerge;
use crate::objects::pair_evidence::{MaskOwners, PairLedger, merge_joined, pairs_shown};

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

/// What the association made of one frame's masks.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrameAssociation {
    /// Each mask's fate, by its id in the frame.
    pub fates: BTreeMap<ObjectId, MaskFate>,
    /// Per object, the voxels (`voxel_m`) its masks covered that another object holds or a
    /// candidate of its class covers: a merged neighbour's surface, whose pixels are not the
    /// object's.
    pub foreign: BTreeMap<ObjectId, VoxelKeys>,
    /// Objects found to be one with another in this frame, in the order they were merged.
    pub merges: Vec<ObjectMerge>,
}

/// What became of a mask.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaskFate {
    /// It shows this object.
    Object(ObjectId),
    /// It is held back (its pixels become unknown).
    Held(HoldReason),
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
    /// Per pair of objects of one class, the frames that showed them apart and joined.
    #[serde(default)]
    pairs: PairLedger,
    /// The id the next object gets (ids of merged objects are not given again).
    #[serde(default)]
    next_id: u32,
    /// Every merge so far, in order.
    #[serde(default)]
    merges: Vec<ObjectMerge>,
}

/// The best of `overlaps` (highest, then lowest key) and the second one if it rivals it.
fn best<K: Copy + Ord>(overlaps: &mut [(K, f32)], cfg: &AssociationConfig) -> Option<(K, Option<K>)> {
    overlaps.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let (k, top) = *overlaps.first()?;
    if top < cfg.min_overlap {
        return None;
    }
    let rival = (overlaps.get(1))
        .filter(|&&(_, second)| second >= cfg.min_overlap && second >= cfg.ambiguity_ratio * top)
        .map(|&(r, _)| r);
    Some((k, rival))
}

/// What the association makes of one mask.
enum Decision {
    Fate(MaskFate),
    /// Held back: it spans these two objects of its class.
    Ambiguous(ObjectId, ObjectId),
    ToCandidate(usize),
    NewCandidate,
}

/// Least share of a second mask of one frame on an object for it to show the same object.
const SPLIT_MASK_OVERLAP: f32 = 0.5;

impl InstanceTracker {
    /// Mask `m` decided against the objects (but `excluded`) and candidates, with its overlap
    /// with the object it shows (0 otherwise).
    fn decide(&self, m: &MaskEvidence, excluded: Option<ObjectId>, cfg: &AssociationConfig) -> (Decision, f32) {
        let v = cfg.voxel_m;
        if m.points.len() < cfg.min_points {
            return (Decision::Fate(MaskFate::Held(HoldReason::TooFewPoints)), 0.0);
        }
        let mut overlaps: Vec<(ObjectId, f32)> = (self.objects.iter())
            .filter(|&(&id, f)| f.class == m.class && Some(id) != excluded)
            .map(|(&id, f)| (id, f.overlap(&m.points, v, Counted::Holding)))
            .collect();
        match best(&mut overlaps, cfg) {
            Some((id, Some(rival))) => (Decision::Ambiguous(id, rival), 0.0),
            Some((id, None)) => (Decision::Fate(MaskFate::Object(id)), overlaps[0].1),
            None if self.objects.values().any(|f| {
                f.class != m.class && f.overlap(&m.points, v, Counted::Holding) >= cfg.confused_class_overlap
            }) =>
            {
                (Decision::Fate(MaskFate::Held(HoldReason::ConfusedClass)), 0.0)
            }
            None => {
                let mut overlaps: Vec<(usize, f32)> = (self.candidates.iter().enumerate())
                    .filter(|(_, c)| c.footprint.class == m.class)
                    .map(|(i, c)| (i, c.footprint.overlap(&m.points, v, Counted::Covered)))
                    .collect();
                let decision =
                    best(&mut overlaps, cfg).map_or(Decision::NewCandidate, |(i, _)| Decision::ToCandidate(i));
                (decision, 0.0)
            }
        }
    }

    /// Number of objects made so far.
    pub fn object_count(&self) -> usize {
        self.objects.len()
    }

    /// Every merge so far, in the order they were made.
    pub fn merges(&self) -> &[ObjectMerge] {
        &self.merges
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
        self.associate_frame(frame, masks, cfg).fates
    }

    /// [`InstanceTracker::associate`], with the voxels each object's masks covered that are
    /// another's.
    pub fn associate_frame(
        &mut self,
        frame: FrameIndex,
        masks: &[MaskEvidence],
        cfg: &AssociationConfig,
    ) -> FrameAssociation {
        let window = cfg.candidate_window_frames;
        self.candidates
            .retain(|c| frame.0.saturating_sub(c.footprint.last_seen) <= window);
        let v = cfg.voxel_m;
        // Decide every mask against the state before this frame. An object two masks of one
        // frame go to keeps the one most of it shows; another stays with it only when most of
        // that mask lies on it (the object split in two), else it is decided without it (a
        // neighbour that touches it).
        let mut decisions: Vec<(Decision, f32)> = masks.iter().map(|m| self.decide(m, None, cfg)).collect();
        let mut by_object: BTreeMap<ObjectId, Vec<usize>> = BTreeMap::new();
        for (i, (d, _)) in decisions.iter().enumerate() {
            if let Decision::Fate(MaskFate::Object(id)) = d {
                by_object.entry(*id).or_default().push(i);
            }
        }
        for (id, mut shown) in by_object {
            shown.sort_by(|&a, &b| decisions[b].1.total_cmp(&decisions[a].1).then(a.cmp(&b)));
            for &i in &shown[1..] {
                if decisions[i].1 < SPLIT_MASK_OVERLAP {
                    decisions[i] = self.decide(&masks[i], Some(id), cfg);
                }
            }
        }
        // Of the masks an object takes, the one of most points on it is its own in this frame.
        let mut own_mask: BTreeMap<ObjectId, (usize, f32)> = BTreeMap::new(); // (mask, points on it)
        for (i, (d, overlap)) in decisions.iter().enumerate() {
            if let Decision::Fate(MaskFate::Object(id)) = d {
                let on = overlap * masks[i].points.len() as f32;
                if own_mask.get(id).is_none_or(|&(_, most)| on > most) {
                    own_mask.insert(*id, (i, on));
                }
            }
        }
        let decisions: Vec<Decision> = decisions.into_iter().map(|(d, _)| d).collect();
        let keys: Vec<VoxelKeys> = masks.iter().map(|m| voxel_keys(&m.points, v)).collect();
        let owners: Vec<MaskOwners> = (decisions.iter())
            .map(|d| match *d {
                Decision::Fate(MaskFate::Object(id)) => MaskOwners::Given(id),
                Decision::Ambiguous(a, b) => MaskOwners::Between(a, b),
                _ => MaskOwners::None,
            })
            .collect();
        let classes: Vec<ClassId> = masks.iter().map(|m| m.class).collect();
        let shown = pairs_shown(&classes, &keys, &owners, &self.objects);
        // A candidate two masks of one frame go to was two objects seen as one: each mask
        // starts a candidate of its own instead.
        let mut masks_per_candidate: BTreeMap<usize, usize> = BTreeMap::new();
        for d in &decisions {
            if let Decision::ToCandidate(i) = d {
                *masks_per_candidate.entry(*i).or_default() += 1;
            }
        }
        let contradicted: BTreeSet<usize> = (masks_per_candidate.into_iter())
            .filter_map(|(i, n)| (n > 1).then_some(i))
            .collect();
        // Apply: objects and candidates take their masks' voxels.
        let mut fates = BTreeMap::new();
        let mut own: BTreeMap<ObjectId, VoxelKeys> = BTreeMap::new();
        let mut slots: Vec<(ObjectId, usize)> = Vec::new();
        for ((m, decision), keys) in masks.iter().zip(decisions).zip(&keys) {
            let slot = match decision {
                Decision::Fate(fate) => {
                    if let MaskFate::Object(id) = fate {
                        own.entry(id).or_default().extend(keys);
                    }
                    fates.insert(m.local, fate);
                    continue;
                }
                Decision::Ambiguous(..) => {
                    fates.insert(m.local, MaskFate::Held(HoldReason::Ambiguous));
                    continue;
                }
                Decision::ToCandidate(i) if !contradicted.contains(&i) => i,
                Decision::ToCandidate(_) | Decision::NewCandidate => {
                    self.candidates.push(Candidate {
                        footprint: Footprint::new(m.class),
                        frames: 0,
                    });
                    self.candidates.len() - 1
                }
            };
            self.candidates[slot].footprint.add(keys, frame);
            slots.push((m.local, slot));
        }
        // Objects count this frame's own mask for them, every other mask (another object's, or a
        // second one it took) against them. An object grows only into voxels no other object
        // holds and no candidate of its class covers (what a mask that merged it with a neighbour
        // adds is the neighbour's).
        // Every object in `own` took a mask, so it has an own mask.
        let counts: Vec<(ObjectId, VoxelKeys, VoxelKeys, usize)> = (own.iter())
            .filter_map(|(&id, own_keys)| {
                let &(own_index, _) = own_mask.get(&id)?;
                let class = self.objects.get(&id).map(|f| f.class);
                let claimed = |k: u64| {
                    self.objects
                        .iter()
                        .any(|(&other, f)| other != id && f.covers(k, Counted::Holding))
                        || (self.candidates.iter())
                            .any(|c| Some(c.footprint.class) == class && c.footprint.covers(k, Counted::Covered))
                };
                let footprint = self.objects.get(&id);
                let grown: VoxelKeys = (own_keys.iter().copied())
                    .filter(|&k| footprint.is_some_and(|f| f.covers(k, Counted::Covered)) || !claimed(k))
                    .collect();
                let others: VoxelKeys = (keys.iter().enumerate())
                    .filter(|&(i, _)| i != own_index)
                    .flat_map(|(_, k)| k.iter().copied())
                    .collect();
                Some((id, grown, others, own_index))
            })
            .collect();
        let mut foreign = BTreeMap::new();
        for (id, grown, others, own_index) in counts {
            if let Some(footprint) = self.objects.get_mut(&id) {
                let own_mask_keys = &keys[own_index];
                let grown_by_own_mask: VoxelKeys = grown.intersection(own_mask_keys).copied().collect();
                footprint.add(&grown_by_own_mask, frame);
                footprint.count_against(&others, own_mask_keys);
            }
            let theirs: VoxelKeys = own[&id].difference(&grown).copied().collect();
            if !theirs.is_empty() {
                foreign.insert(id, theirs);
            }
        }
        // Candidates seen in this frame count it; those seen in enough frames become objects.
        let seen: BTreeSet<usize> = slots.iter().map(|&(_, slot)| slot).collect();
        let mut promoted: BTreeMap<usize, ObjectId> = BTreeMap::new();
        for slot in seen {
            let candidate = &mut self.candidates[slot];
            candidate.frames += 1;
            if candidate.frames >= cfg.min_frames {
                let last = self.objects.keys().next_back().map_or(0, |last| last.0);
                let id = ObjectId(self.next_id.max(last + 1));
                self.next_id = id.0 + 1;
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
            !promoted.contains_key(&(slot - 1)) && !contradicted.contains(&(slot - 1))
        });
        // Pairs shown joined more often than apart are one object: the lower id takes the other.
        self.pairs.record(&shown);
        let merges = merge_joined(&mut self.objects, &mut self.pairs, &shown, frame, window);
        self.merges.extend(&merges);
        for merge in &merges {
            for fate in fates.values_mut() {
                if *fate == MaskFate::Object(merge.absorbed) {
                    *fate = MaskFate::Object(merge.kept);
                }
            }
            let theirs = foreign.remove(&merge.absorbed).unwrap_or_default();
            let kept = foreign.entry(merge.kept).or_default();
            kept.extend(theirs);
            let footprint = &self.objects[&merge.kept];
            kept.retain(|&k| !footprint.covers(k, Counted::Covered));
            if kept.is_empty() {
                foreign.remove(&merge.kept);
            }
        }
        FrameAssociation { fates, foreign, merges }
    }
}

#[cfg(test)]
#[path = "instance_association_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "instance_merge_tests.rs"]
mod merge_tests;
