//! Segment stage: each new frame's instance mask is split into per-object observations.

use bevy_ecs::prelude::*;
use catmap::RgbdFrame;
use catmap::objects::frame_observation::{FrameObservation, observe_objects};
use catmap::objects::instance_association::{InstanceSource, associate_frame};
use catmap::objects::mask_trim::trim_bleeding_masks;

use crate::components::{CameraFrame, FrameObservations};
use crate::resources::{Association, Settings, SmallInstances, StageTimes};

/// Groups each new frame's pixels by object (boxes, class votes, pixel lists).
pub fn observe_frames(
    settings: Res<Settings>,
    frames: Query<(Entity, &CameraFrame), Added<CameraFrame>>,
    mut times: ResMut<StageTimes>,
    mut small: ResMut<SmallInstances>,
    mut commands: Commands,
) {
    let _timer = times.start("masks");
    for (entity, frame) in &frames {
        let observation = observe_objects(&frame.0, &settings.0.objects);
        if settings.0.objects.association.instances == InstanceSource::Consistent {
            count_small(&mut small, &frame.0, &observation);
        }
        commands.entity(entity).insert(FrameObservations(observation));
    }
}

/// Mask pixels that bleed past their object onto what lies behind become unknown.
pub fn trim_masks(
    settings: Res<Settings>,
    mut frames: Query<&mut CameraFrame, Added<CameraFrame>>,
    mut times: ResMut<StageTimes>,
) {
    let _timer = times.start("masks");
    for mut frame in &mut frames {
        if let Some(trimmed) = trim_bleeding_masks(&frame.0, &settings.0.objects) {
            frame.0 = std::sync::Arc::new(trimmed);
        }
    }
}

/// Per-frame instance ids: each new frame's masks (in frame order) are associated into objects;
/// the frame's mask and its observations are replaced by the associated ones.
pub fn associate_masks(
    settings: Res<Settings>,
    mut tracker: ResMut<Association>,
    mut frames: Query<(&mut CameraFrame, &mut FrameObservations), Added<FrameObservations>>,
    mut times: ResMut<StageTimes>,
    mut small: ResMut<SmallInstances>,
) {
    let _timer = times.start("associate");
    let mut batch: Vec<_> = frames.iter_mut().collect();
    batch.sort_by_key(|(frame, _)| frame.0.index);
    for (mut frame, mut observations) in batch {
        let (relabelled, observation) = associate_frame(&mut tracker.0, &frame.0, &observations.0, &settings.0.objects);
        count_small(&mut small, &relabelled, &observation);
        frame.0 = std::sync::Arc::new(relabelled);
        observations.0 = observation;
    }
}

fn count_small(small: &mut SmallInstances, frame: &RgbdFrame, observation: &FrameObservation) {
    for id in &observation.ignored_small {
        tracing::trace!(frame = %frame.index, object = %id, "2D box too small, ignored in this frame");
        *small.0.entry(*id).or_default() += 1;
    }
}
