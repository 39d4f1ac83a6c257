//! The recording stream the log systems write to (a resource only when the mapper records).

use bevy_ecs::prelude::*;

use crate::rerun_paths as paths;

/// The recording stream every log system writes to.
#[derive(Resource, Clone)]
pub struct Rerun(pub rerun::RecordingStream);

impl Rerun {
    /// Stamps what is logged next with frame `frame` and the wall clock (the `time` timeline).
    pub fn at_frame(&self, frame: u64) {
        self.0.set_time_sequence(paths::FRAME_TIMELINE, frame as i64);
        self.0
            .set_time(paths::WALL_CLOCK_TIMELINE, std::time::SystemTime::now());
    }
}

/// Warns (naming the entity path) when logging failed; a recording never stops the map.
pub(crate) fn warn_on_error<E: std::fmt::Display>(result: Result<(), E>, path: &str) {
    if let Err(e) = result {
        tracing::warn!(path, error = %e, "Rerun logging failed");
    }
}
