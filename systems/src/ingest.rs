//! Ingest stage: frames leave the stream and become `CameraFrame` entities.

use bevy_ecs::prelude::*;
use catmap::dataset::stream::{StreamMessage, StreamStats};

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
    if progress.ended.is_none() && inbox.0.is_empty() && inbox.0.try_recv().is_err_and(|e| e.is_disconnected()) {
        // The reader is gone without its end message (it died): keep what was mapped.
        tracing::warn!(
            frames = progress.frames_ingested,
            "the stream stopped without its end; finishing"
        );
        progress.ended = Some(StreamStats {
            frames_sent: progress.frames_ingested,
            frames_skipped: progress.frames_skipped,
            ..StreamStats::default()
        });
    }
}
