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
    if progress.ended.is_some() {
        return;
    }
    for message in inbox.0.try_iter().take(settings.0.stream.frames_per_tick) {
        if let Some(frame) = progress.record(message) {
            commands.spawn(CameraFrame(frame));
        }
        if progress.ended.is_some() {
            return;
        }
    }
    if inbox.0.is_empty() && inbox.0.try_recv().is_err_and(|e| e.is_disconnected()) {
        progress.end_without_message();
    }
}
