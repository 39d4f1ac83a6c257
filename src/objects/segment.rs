//! The segment stage's one call on a frame ([`segment_frame`]): bleeding mask pixels trimmed,
//! the frame's masks grouped by object, and — with per-frame instance ids — the masks associated
//! into objects ([`crate::objects::instance_association`]) and the frame relabelled with their ids.

use std::collections::BTreeMap;

use nalgebra::Point3;

use crate::ids::ObjectId;
use crate::objects::border_votes::{LabelHistory, vote_on_band};
use crate::objects::config::ObjectConfig;
use crate::objects::frame_observation::{FrameObservation, observe_objects};
use crate::objects::instance_association::{
    AssociationConfig, FrameAssociation, InstanceSource, InstanceTracker, MaskEvidence, MaskFate,
};
use crate::objects::mask_footprint::voxel_key;
use crate::objects::mask_trim::{
    BandInFront, border_band, spare_pixels_in_front, trim_bleeding_masks, with_band_unsure,
};
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
    let association = associate_masks(tracker, frame, observation, cfg);
    let relabelled = unsure_where_foreign(
        relabel_instances(frame, &association.fates),
        &association,
        cfg.association.voxel_m,
    );
    let observation = FrameObservation {
        merges: association.merges,
        ..observe_objects(&relabelled, cfg)
    };
    (relabelled, observation)
}

/// What `tracker` makes of the masks of `frame` (`observation` its masks grouped).
fn associate_masks(
    tracker: &mut InstanceTracker,
    frame: &RgbdFrame,
    observation: &FrameObservation,
    cfg: &ObjectConfig,
) -> FrameAssociation {
    tracker.associate_frame(
        frame.index,
        &mask_evidence(frame, observation, &cfg.association),
        &cfg.association,
    )
}

/// `relabelled` with the pixels of each object that lie in a voxel another object holds
/// (`association.foreign`) made unsure: a merged neighbour's pixels.
fn unsure_where_foreign(mut relabelled: RgbdFrame, association: &FrameAssociation, voxel_m: f32) -> RgbdFrame {
    if association.foreign.is_empty() {
        return relabelled;
    }
    for i in 0..relabelled.instances.len() {
        let Some(id) = relabelled.instances.object_at(i) else {
            continue;
        };
        let (Some(theirs), Some(p)) = (association.foreign.get(&id), relabelled.point_in_world(i)) else {
            continue;
        };
        if theirs.contains(&voxel_key(&p, voxel_m)) {
            relabelled.instances.set(i, InstanceLabel::Unsure);
        }
    }
    relabelled
}

/// The segment stage's work on one frame: bleeding mask pixels trimmed (`bleed_radius_px`),
/// masks' borders made unsure (`mask_border_px`) or, with `border_votes.frames`, decided by the
/// last frames' labels kept in `history` ([`crate::objects::border_votes`]), the pixels grouped by
/// object, and, with per-frame ids, the masks associated into objects by `tracker` (from the
/// masks without their band). Returns the frame when it changed, and its observation (with the
/// objects the association merged in it).
pub fn segment_frame(
    frame: &RgbdFrame,
    cfg: &ObjectConfig,
    tracker: &mut InstanceTracker,
    history: &mut LabelHistory,
) -> (Option<RgbdFrame>, FrameObservation) {
    let trimmed = trim_bleeding_masks(frame, cfg);
    let base = trimmed.as_ref().unwrap_or(frame);
    let band = border_band(base, cfg.mask_border_px).map(|mut band| {
        if cfg.band_in_front == BandInFront::Kept {
            spare_pixels_in_front(base, &mut band, cfg.mask_border_px, cfg);
        }
        band
    });
    // With per-frame ids, the masks without their band are associated, and the frame before the
    // band relabelled.
    let (labelled, merges) = match cfg.association.instances {
        InstanceSource::Consistent => (None, Vec::new()),
        InstanceSource::PerFrame => {
            let bordered = band.as_ref().map(|band| with_band_unsure(base, band));
            let judged = bordered.as_ref().unwrap_or(base);
            let association = associate_masks(tracker, judged, &observe_objects(judged, cfg), cfg);
            let relabelled = relabel_instances(base, &association.fates);
            let voxel_m = cfg.association.voxel_m;
            (
                Some(unsure_where_foreign(relabelled, &association, voxel_m)),
                association.merges,
            )
        }
    };
    let raw = labelled.as_ref().unwrap_or(base);
    let decided = band.map(|band| match cfg.border_votes.frames {
        0 => with_band_unsure(raw, &band),
        _ => vote_on_band(raw, &band, history, &cfg.border_votes),
    });
    if cfg.border_votes.frames > 0 {
        history.push(raw, &raw.instances, cfg.border_votes.frames);
    }
    let changed = decided.or(labelled).or(trimmed);
    let observation = FrameObservation {
        merges,
        ..observe_objects(changed.as_ref().unwrap_or(frame), cfg)
    };
    (changed, observation)
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
