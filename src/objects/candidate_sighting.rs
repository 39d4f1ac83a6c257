//! What a candidate saw before it became an object ([`crate::objects::instance_association`]).
//!
//! With per-frame ids a mask no object takes is held back for a candidate until the candidate has
//! been seen in `min_frames` frames, and its pixels teach no field meanwhile (they are unsure).
//! So that the object does not lose its first sightings — for an object seen briefly, or whose
//! thin part shows best in them, most of what it is ever seen as — the candidate keeps each held
//! mask's view: the crop the object's keyframe window would have been offered, with the mask's
//! pixels as the object's, its class votes and how many of its pixels had a depth. The object
//! the candidate becomes takes them in, in frame order, before the frame that made it.

use std::collections::BTreeMap;

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::ids::{ClassId, FrameIndex, ObjectId};
use crate::objects::config::ObjectConfig;
use crate::objects::frame_observation::{DepthCoverage, observe_objects};
use crate::objects::instance_association::MaskFate;
use crate::objects::object_view::{ObjectView, ViewOwner};
use crate::sensor::frame::{InstanceLabel, InstanceMask, RgbdFrame};

/// One held mask of a candidate, as its object's view of that frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateSighting {
    /// The crop inside the mask's sampling box, the mask's pixels the object's.
    pub view: ObjectView,
    /// Pixel count per semantic class inside the mask.
    pub class_votes: BTreeMap<ClassId, u32>,
    /// The mask's pixels, and those with a depth.
    pub coverage: DepthCoverage,
}

/// The sightings of the masks of `frame` held for candidates (`held`: each such mask's id in the
/// frame and its candidate's key). `frame` is the frame as the association saw it before
/// relabelling (its bleeding pixels trimmed); `finish` turns a relabelled frame into what the
/// objects' views are cropped from (the band about the masks' borders made unsure), so that a
/// sighting is the view the object would have had of the frame. Every other mask is labelled as
/// `fates` says, held ones unsure; a held mask's pixel whose point lies in a voxel an object
/// holds (`claimed`) is unsure too: a merged neighbour's surface.
pub fn candidate_sightings(
    frame: &RgbdFrame,
    fates: &BTreeMap<ObjectId, MaskFate>,
    held: &BTreeMap<ObjectId, u64>,
    cfg: &ObjectConfig,
    claimed: impl Fn(&Point3<f32>) -> bool,
    finish: impl Fn(RgbdFrame) -> RgbdFrame,
) -> Vec<(u64, CandidateSighting)> {
    if held.is_empty() {
        return Vec::new();
    }
    // Each held mask gets an id no object has (counted down from the largest).
    let provisional: BTreeMap<ObjectId, (ObjectId, u64)> = (held.iter().enumerate())
        .map(|(i, (&local, &key))| (local, (ObjectId(u32::MAX - i as u32), key)))
        .collect();
    let labels = (0..frame.instances.len()).map(|i| match frame.instances.label(i) {
        InstanceLabel::Object(local) => match (provisional.get(&local), fates.get(&local)) {
            (Some(_), _) if frame.point_in_world(i).is_some_and(|p| claimed(&p)) => InstanceLabel::Unsure,
            (Some(&(id, _)), _) | (None, Some(&MaskFate::Object(id))) => InstanceLabel::Object(id),
            _ => InstanceLabel::Unsure,
        },
        other => other,
    });
    let labelled = finish(RgbdFrame {
        instances: InstanceMask::from_labels(labels),
        ..frame.clone()
    });
    let observation = observe_objects(&labelled, cfg);
    (provisional.values())
        .filter_map(|&(id, key)| {
            let seen = observation.objects.get(&id)?;
            let mut coverage = DepthCoverage::default();
            coverage.add(seen, &labelled.depth_m);
            let sighting = CandidateSighting {
                view: ObjectView::crop(&labelled, seen.sample_box, ViewOwner::Object(id)),
                class_votes: seen.class_votes.clone(),
                coverage,
            };
            Some((key, sighting))
        })
        .collect()
}

impl CandidateSighting {
    /// The frame it was seen in.
    pub fn frame(&self) -> FrameIndex {
        self.view.frame
    }
}
