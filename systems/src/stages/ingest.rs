//! Ingest stage: frames leave the stream and become `CameraFrame` entities.

use bevy_ecs::prelude::*;

use crate::components::CameraFrame;
use crate::resources::{FrameInbox, Settings, StageTimes, StreamProgress};

/// Takes up to `frames_per_tick` messages from the inbox: spawns a `CameraFrame` per frame,
/// counts skipped frames (logged), and records the end of the stream.
pub fn ingest_frames(
    settings: Res<Settings>,
    inbox: Res<FrameInbox>,
    mut progress: ResMut<StreamProgress>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let _timer = times.start("ingest");
    for frame in progress.take_from(&inbox.0, settings.0.stream.frames_per_tick) {
        commands.spawn(CameraFrame(frame));
    }
}
