//! Segment stage: each new frame's instance mask is split into per-object observations.

use bevy_ecs::prelude::*;
use catmap::objects::instance_association::InstanceSource;
use catmap::objects::segment::segment_frame;

use crate::components::{CameraFrame, FrameObservations};
use crate::resources::{Association, BorderHistory, Settings, SmallInstances, StageTimes};

/// Groups each new frame's pixels by object (boxes, class votes, pixel lists), after trimming
/// masks that bleed past their object and, with per-frame instance ids, associating the masks
/// into objects, and with border votes deciding the masks' borders by the frames before (frames
/// in index order for both); a changed frame replaces the entity's.
pub fn observe_frames(
    settings: Res<Settings>,
    mut tracker: ResMut<Association>,
    mut history: ResMut<BorderHistory>,
    mut frames: Query<(Entity, &mut CameraFrame), Added<CameraFrame>>,
    mut times: ResMut<StageTimes>,
    mut small: ResMut<SmallInstances>,
    mut commands: Commands,
) {
    let _timer = times.start("masks");
    let mut batch: Vec<_> = frames.iter_mut().collect();
    if settings.0.objects.association.instances == InstanceSource::PerFrame
        || settings.0.objects.border_votes.frames > 0
    {
        batch.sort_by_key(|(_, frame)| frame.0.index);
    }
    for (entity, mut frame) in batch {
        let (changed, observation) = segment_frame(&frame.0, &settings.0.objects, &mut tracker.0, &mut history.0);
        if let Some(changed) = changed {
            frame.0 = std::sync::Arc::new(changed);
        }
        for id in &observation.ignored_small {
            tracing::trace!(frame = %frame.0.index, object = %id, "2D box too small, ignored in this frame");
            *small.0.entry(*id).or_default() += 1;
        }
        commands.entity(entity).insert(FrameObservations(observation));
    }
}
