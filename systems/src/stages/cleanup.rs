//! Cleanup stage: consumed frames leave the world (keyframe windows keep their own references).

use bevy_ecs::prelude::*;

use crate::components::CameraFrame;

/// Despawns every camera frame entity at the end of the tick it arrived in.
pub fn despawn_consumed_frames(frames: Query<Entity, With<CameraFrame>>, mut commands: Commands) {
    for entity in &frames {
        commands.entity(entity).despawn();
    }
}
