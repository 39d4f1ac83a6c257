//! Segment stage: each new frame's instance mask is split into per-object observations.

use bevy_ecs::prelude::*;
use catmap::objects::frame_observation::observe_objects;

use crate::components::{CameraFrame, FrameObservations};
use crate::resources::{Settings, SmallInstances, StageTimes};

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
        for id in &observation.ignored_small {
            tracing::trace!(frame = %frame.0.index, object = %id, "2D box too small, ignored in this frame");
            *small.0.entry(*id).or_default() += 1;
        }
        commands.entity(entity).insert(FrameObservations(observation));
    }
}
