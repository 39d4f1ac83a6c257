//! How well per-frame masks were associated into objects, against the truth: for every object the
//! association made, the pixels it was given and which ground-truth object each shows.
//!
//! A pixel counts when the association gave it an object and the exact (noise-free) render shows
//! an object there; pixels of a mask that bled onto a wall or the floor show none and are left
//! out (they are the segmenter's error, not the association's). An object's **purity** is the
//! share of its counted pixels that show its main ground-truth object.

use std::collections::BTreeMap;

use crate::ids::ObjectId;
use crate::sensor::frame::{InstanceLabel, InstanceMask};

/// Pixel counts per associated object and ground-truth object.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AssociationTally {
    counts: BTreeMap<ObjectId, BTreeMap<ObjectId, u64>>,
    on_background: BTreeMap<ObjectId, u64>,
}

/// One associated object against the truth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AssociatedObject {
    /// The association's id.
    pub id: ObjectId,
    /// The ground-truth object most of its pixels show.
    pub truth: ObjectId,
    /// Share of its counted pixels that show `truth`.
    pub purity: f32,
    /// Its counted pixels.
    pub pixels: u64,
    /// Its pixels where the exact render shows the background (the mask bled onto a wall or the
    /// floor), not counted in `pixels`.
    pub background_pixels: u64,
}

impl AssociationTally {
    /// Counts one frame: `associated` is the association's mask, `truth` the exact render's.
    pub fn add(&mut self, associated: &InstanceMask, truth: &InstanceMask) {
        for i in 0..associated.len().min(truth.len()) {
            let Some(id) = associated.object_at(i) else {
                continue;
            };
            match truth.label(i) {
                InstanceLabel::Object(true_id) => *self.counts.entry(id).or_default().entry(true_id).or_default() += 1,
                InstanceLabel::Background => *self.on_background.entry(id).or_default() += 1,
                InstanceLabel::Unknown | InstanceLabel::Unsure => {}
            }
        }
    }

    /// `absorbed` was found to be part of `kept`: its pixels are counted as `kept`'s.
    pub fn merge(&mut self, kept: ObjectId, absorbed: ObjectId) {
        for (truth, n) in self.counts.remove(&absorbed).unwrap_or_default() {
            *self.counts.entry(kept).or_default().entry(truth).or_default() += n;
        }
        if let Some(n) = self.on_background.remove(&absorbed) {
            *self.on_background.entry(kept).or_default() += n;
        }
    }

    /// Every associated object with its main ground-truth object and purity, in id order.
    pub fn objects(&self) -> Vec<AssociatedObject> {
        self.counts
            .iter()
            .filter_map(|(&id, by_truth)| {
                let total: u64 = by_truth.values().sum();
                let (&truth, &n) = by_truth.iter().max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))?;
                Some(AssociatedObject {
                    id,
                    truth,
                    purity: n as f32 / total as f32,
                    pixels: total,
                    background_pixels: self.on_background.get(&id).copied().unwrap_or(0),
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(ids: &[u32]) -> InstanceMask {
        InstanceMask::from_labels(ids.iter().map(|&id| match id {
            0 => InstanceLabel::Background,
            id => InstanceLabel::Object(ObjectId(id)),
        }))
    }

    #[test]
    fn purity_counts_pixels_that_show_an_object_and_names_the_main_one() {
        let mut tally = AssociationTally::default();
        // Associated object 1 covers four pixels of truth 7, one of truth 8 and one of the wall.
        tally.add(&mask(&[1, 1, 1, 1, 1, 1, 2]), &mask(&[7, 7, 7, 7, 8, 0, 8]));
        let objects = tally.objects();
        assert_eq!(objects.len(), 2);
        assert_eq!((objects[0].truth, objects[0].pixels), (ObjectId(7), 5));
        assert_eq!(objects[0].background_pixels, 1, "the wall pixel is counted apart");
        assert!((objects[0].purity - 0.8).abs() < 1e-6);
        assert_eq!((objects[1].truth, objects[1].purity), (ObjectId(8), 1.0));
    }
}
