//! Whether two objects of one class are one object: per pair, the frames that showed them
//! **apart** (each by a mask of its own) and the frames that showed them **joined** (one mask
//! over both) ([`crate::objects::instance_association`]).
//!
//! A segmenter that merges two touching objects does so in a few frames and shows them apart in
//! the others. An object made twice — its ends seen in views that barely overlap as the camera
//! panned, or a fragment of a mask the segmenter split — is shown joined whenever a view spans it
//! and apart only when the segmenter splits it. Two objects are one ([`PairEvidence::one_object`])
//! once they were seen joined in at least [`JOINED_FRAMES`] frames and more often joined than
//! apart: a segmenter that merges or splits in fewer than half of its frames never makes two
//! objects one, nor leaves one object two.

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use crate::ids::{ClassId, FrameIndex, ObjectId};
use crate::objects::mask_footprint::{Footprint, VoxelKeys};

/// Frames that must show two objects joined before they are one (one mask is no evidence).
pub const JOINED_FRAMES: u32 = 2;

/// Frames that showed a pair apart and joined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct PairEvidence {
    /// Frames with a mask of each.
    pub apart: u32,
    /// Frames with one mask over both.
    pub joined: u32,
}

impl PairEvidence {
    /// Whether the two are one object (module doc).
    pub fn one_object(self) -> bool {
        self.joined >= JOINED_FRAMES && self.joined > self.apart
    }
}

/// A pair of objects, the lower id first.
pub type ObjectPair = (ObjectId, ObjectId);

/// The pair of `a` and `b`, the lower id first.
pub fn pair(a: ObjectId, b: ObjectId) -> ObjectPair {
    (a.min(b), a.max(b))
}

/// The pairs one frame showed apart and joined (a pair shown apart is not also joined).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct FramePairs {
    /// Pairs each shown by a mask of its own.
    pub apart: BTreeSet<ObjectPair>,
    /// Pairs one mask showed together.
    pub joined: BTreeSet<ObjectPair>,
}

/// Which objects a mask of a frame was given to, or held back between.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaskOwners {
    /// Given to this object.
    Given(ObjectId),
    /// Held back: it spans these two objects of its class alike.
    Between(ObjectId, ObjectId),
    /// Neither (a candidate's, a confused class, too few points).
    None,
}

/// The pairs of objects of one class a frame's masks (each's class, voxel keys and owners,
/// decided against `objects` before the frame) showed apart and joined: apart, two objects each
/// given a mask; joined, a mask held back between two objects, or a mask given to one that
/// covers at least half of what a sighting of another covers of the voxels that hold for it.
pub fn pairs_shown(
    classes: &[ClassId],
    keys: &[VoxelKeys],
    owners: &[MaskOwners],
    objects: &BTreeMap<ObjectId, Footprint>,
) -> FramePairs {
    let mut shown = FramePairs::default();
    let given: BTreeSet<ObjectId> = (owners.iter())
        .filter_map(|o| match o {
            MaskOwners::Given(id) => Some(*id),
            _ => None,
        })
        .collect();
    let class_of = |id: &ObjectId| objects.get(id).map(|f| f.class);
    for a in &given {
        for b in given.range(*a..).skip(1) {
            if class_of(a) == class_of(b) {
                shown.apart.insert(pair(*a, *b));
            }
        }
    }
    for ((&class, keys), &owner) in classes.iter().zip(keys).zip(owners) {
        let owners = match owner {
            MaskOwners::Given(id) => vec![id],
            MaskOwners::Between(a, b) => {
                shown.joined.insert(pair(a, b));
                vec![a, b]
            }
            MaskOwners::None => continue,
        };
        for (&other, f) in objects {
            if f.class != class || owners.contains(&other) {
                continue;
            }
            let covered = f.holding_among(keys);
            if covered > 0 && covered as f32 >= 0.5 * f.voxels_per_sighting() {
                shown.joined.extend(owners.iter().map(|&o| pair(o, other)));
            }
        }
    }
    shown
}

/// The evidence of every pair seen so far; checkpointed with the association.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PairLedger(BTreeMap<ObjectId, BTreeMap<ObjectId, PairEvidence>>);

impl PairLedger {
    /// The evidence of `pair` (none yet: zero frames).
    pub fn get(&self, (a, b): ObjectPair) -> PairEvidence {
        self.0.get(&a).and_then(|m| m.get(&b)).copied().unwrap_or_default()
    }

    fn entry(&mut self, (a, b): ObjectPair) -> &mut PairEvidence {
        self.0.entry(a).or_default().entry(b).or_default()
    }

    /// Counts one frame's pairs.
    pub fn record(&mut self, frame: &FramePairs) {
        for &p in &frame.apart {
            self.entry(p).apart += 1;
        }
        for &p in frame.joined.difference(&frame.apart) {
            self.entry(p).joined += 1;
        }
    }

    /// `absorbed` became part of `kept`: its evidence with every other object is added to
    /// `kept`'s, and the pair of the two is forgotten.
    pub fn absorb(&mut self, kept: ObjectId, absorbed: ObjectId) {
        let mut moved: Vec<(ObjectId, PairEvidence)> = self.0.remove(&absorbed).into_iter().flatten().collect();
        for (&a, with) in &mut self.0 {
            if let Some(e) = with.remove(&absorbed) {
                moved.push((a, e));
            }
        }
        for (other, e) in moved {
            if other != kept {
                let into = self.entry(pair(kept, other));
                into.apart += e.apart;
                into.joined += e.joined;
            }
        }
        self.0.retain(|_, with| !with.is_empty());
    }
}

/// Two objects found to be one: the lower id is kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct ObjectMerge {
    /// The frame whose masks showed it.
    pub frame: FrameIndex,
    /// The object that keeps its id.
    pub kept: ObjectId,
    /// The object taken into it; its id is never given again.
    pub absorbed: ObjectId,
}

/// Merges in `objects`, one pair at a time, the pairs `shown` joined in `frame` that are now one
/// object ([`PairEvidence::one_object`] in `ledger`), once the younger of the two was first seen
/// at least `window` frames ago (a segmenter that merges two touching objects in a run of frames
/// may do so before they were ever seen apart). The kept footprint takes the other's voxels, the
/// ledger its pairs.
pub fn merge_joined(
    objects: &mut BTreeMap<ObjectId, Footprint>,
    ledger: &mut PairLedger,
    shown: &FramePairs,
    frame: FrameIndex,
    window: u64,
) -> Vec<ObjectMerge> {
    let mut merges = Vec::new();
    let mut pending: Vec<ObjectPair> = shown.joined.iter().copied().collect();
    let due = |objects: &BTreeMap<ObjectId, Footprint>, ledger: &PairLedger, (a, b): ObjectPair| {
        let (Some(fa), Some(fb)) = (objects.get(&a), objects.get(&b)) else {
            return false;
        };
        let judged = frame.0.saturating_sub(fa.first_seen.max(fb.first_seen)) >= window;
        a != b && judged && ledger.get((a, b)).one_object()
    };
    while let Some(i) = pending.iter().position(|&p| due(objects, ledger, p)) {
        let (kept, absorbed) = pending.swap_remove(i);
        let Some(footprint) = objects.remove(&absorbed) else {
            continue;
        };
        if let Some(into) = objects.get_mut(&kept) {
            into.absorb(&footprint);
        }
        ledger.absorb(kept, absorbed);
        let renamed = |id: ObjectId| if id == absorbed { kept } else { id };
        for p in &mut pending {
            *p = pair(renamed(p.0), renamed(p.1));
        }
        merges.push(ObjectMerge { frame, kept, absorbed });
    }
    merges
}

#[cfg(test)]
mod tests {
    use super::*;

    const A: ObjectId = ObjectId(1);
    const B: ObjectId = ObjectId(2);
    const C: ObjectId = ObjectId(3);

    fn frame(apart: &[ObjectPair], joined: &[ObjectPair]) -> FramePairs {
        FramePairs {
            apart: apart.iter().copied().collect(),
            joined: joined.iter().copied().collect(),
        }
    }

    #[test]
    fn two_are_one_after_two_joined_frames_and_only_while_joined_outnumbers_apart() {
        let mut ledger = PairLedger::default();
        ledger.record(&frame(&[], &[pair(B, A)]));
        assert!(!ledger.get((A, B)).one_object(), "one mask is no evidence");
        ledger.record(&frame(&[], &[(A, B)]));
        assert!(ledger.get((A, B)).one_object());
        ledger.record(&frame(&[(A, B)], &[]));
        ledger.record(&frame(&[(A, B)], &[]));
        assert_eq!(ledger.get((A, B)), PairEvidence { apart: 2, joined: 2 });
        assert!(!ledger.get((A, B)).one_object(), "as often apart as joined");
        ledger.record(&frame(&[(A, B)], &[(A, B)]));
        assert_eq!(
            ledger.get((A, B)),
            PairEvidence { apart: 3, joined: 2 },
            "apart wins a frame"
        );
    }

    #[test]
    fn an_absorbed_objects_evidence_moves_to_the_object_that_kept_its_id() {
        let mut ledger = PairLedger::default();
        ledger.record(&frame(&[(A, C)], &[(A, B)]));
        ledger.record(&frame(&[(B, C)], &[(A, B), (B, C)]));
        ledger.absorb(A, B);
        assert_eq!(ledger.get((A, B)), PairEvidence::default());
        assert_eq!(ledger.get((A, C)), PairEvidence { apart: 2, joined: 0 });
        assert_eq!(ledger.get((B, C)), PairEvidence::default());
    }
}
