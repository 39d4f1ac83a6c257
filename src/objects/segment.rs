//! The segment stage's one call on a frame ([`segment_frame`]): bleeding mask pixels trimmed,
//! the frame's masks grouped by object, and — with per-frame instance ids — the masks associated
//! into objects ([`crate::objects::instance_association`]) and the frame relabelled with their ids.

use std::collections::BTreeMap;

use nalgebra::Point3;

use crate::ids::ObjectId;
use crate::objects::config::ObjectConfig;
use crate::objects::frame_observation::{FrameObservation, observe_objects};
use crate::objects::instance_association::{
    AssociationConfig, InstanceSource, InstanceTracker, MaskEvidence, MaskFate,
};
use crate::objects::mask_trim::{mark_unsure_borders, trim_bleeding_masks};
use crate::sensor::frame::{InstanceLabel, InstanceMask, RgbdFrame};

/// The masks of `frame` as the association sees them: every mask of `observation`, its majority
/// class and at most `max_points_per_mask` of its pixels' points, evenly spaced.
pub fn mask_evidence(frame: &RgbdFrame, observation: &FrameObservation, cfg: &AssociationConfig) -> Vec<MaskEvidence> {
    observation
        .objects
        .iter()
        .filter_map(|(&local, o)| {
            let class = o.majority_class()?;
            let valid: Vec<Point3<f32>> = o
                .pixels
                .iter()
                .filter_map(|&i| frame.point_in_world(i as usize))
                .collect();
            let step = valid.len().div_ceil(cfg.max_points_per_mask.max(1)).max(1);
            let points = valid.into_iter().step_by(step).collect();
            Some(MaskEvidence { local, class, points })
        })
        .collect()
}

/// One frame of per-frame masks made into objects: its masks' evidence is associated by
/// `tracker`, the frame relabelled, and its observation made again from the relabelled mask.
pub fn associate_frame(
    tracker: &mut InstanceTracker,
    frame: &RgbdFrame,
    observation: &FrameObservation,
    cfg: &ObjectConfig,
) -> (RgbdFrame, FrameObservation) {
    let fates = tracker.associate(
        frame.index,
        &mask_evidence(frame, observation, &cfg.association),
        &cfg.association,
    );
    let relabelled = relabel_instances(frame, &fates);
    let observation = observe_objects(&relabelled, cfg);
    (relabelled, observation)
}

/// The segment stage's work on one frame: bleeding mask pixels trimmed (`bleed_radius_px`),
/// masks' borders made unsure (`mask_border_px`), the pixels grouped by object, and, with
/// per-frame ids, the masks associated into objects by `tracker`. Returns the frame when it
/// changed, and its observation.
pub fn segment_frame(
    frame: &RgbdFrame,
    cfg: &ObjectConfig,
    tracker: &mut InstanceTracker,
) -> (Option<RgbdFrame>, FrameObservation) {
    let trimmed = trim_bleeding_masks(frame, cfg);
    let bordered = mark_unsure_borders(trimmed.as_ref().unwrap_or(frame), cfg.mask_border_px);
    let changed = bordered.or(trimmed);
    let frame_now = changed.as_ref().unwrap_or(frame);
    let observation = observe_objects(frame_now, cfg);
    match cfg.association.instances {
        InstanceSource::Consistent => (changed, observation),
        InstanceSource::PerFrame => {
            let (relabelled, observation) = associate_frame(tracker, frame_now, &observation, cfg);
            (Some(relabelled), observation)
        }
    }
}

/// `frame` with its masks renamed as `fates` says: a mask that shows an object gets its id; a
/// held-back mask, and any mask `fates` does not name, becomes unsure.
pub fn relabel_instances(frame: &RgbdFrame, fates: &BTreeMap<ObjectId, MaskFate>) -> RgbdFrame {
    let labels = (0..frame.instances.len()).map(|i| match frame.instances.label(i) {
        InstanceLabel::Object(local) => match fates.get(&local) {
            Some(MaskFate::Object(id)) => InstanceLabel::Object(*id),
            Some(MaskFate::Held(_)) | None => InstanceLabel::Unsure,
        },
        other => other,
    });
    RgbdFrame {
        instances: InstanceMask::from_labels(labels),
        ..frame.clone()
    }
}
