//! Ingest stage: frames leave the stream and become `CameraFrame` entities.

use bevy_ecs::prelude::*;
use catmap::stream::StreamMessage;

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
        match message {
            StreamMessage::Frame(frame) => {
                tracing::trace!(frame = %frame.index, "ingest");
                progress.frames_ingested += 1;
                progress.last_frame = Some(frame.index);
                commands.spawn(CameraFrame(frame));
            }
            StreamMessage::Skipped { position, reason } => {
                tracing::warn!(position, %reason, "skipping frame");
                progress.frames_skipped += 1;
            }
            StreamMessage::End(stats) => {
                tracing::debug!(?stats, "end of stream");
                progress.ended = Some(stats);
                break;
            }
        }
    }
}
