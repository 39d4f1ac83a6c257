//! Resources: configuration, the frame inbox, indices and run statistics.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use catmap::stream::{StreamMessage, StreamStats};
use catmap::{ClassId, FrameIndex, MapperConfig, ObjectId};
use crossbeam_channel::Receiver;

/// The mapper's configuration.
#[derive(Resource, Debug, Clone)]
pub struct Settings(pub MapperConfig);

/// The receiving end of the frame stream.
#[derive(Resource, Debug)]
pub struct FrameInbox(pub Receiver<StreamMessage>);

/// How far the stream has come.
#[derive(Resource, Debug, Clone, Default, PartialEq)]
pub struct StreamProgress {
    /// Frames taken from the inbox.
    pub frames_ingested: u64,
    /// Frames the reader could not decode.
    pub frames_skipped: u64,
    /// Index of the newest frame.
    pub last_frame: Option<FrameIndex>,
    /// Set when the end-of-stream message arrived, with the reader's statistics.
    pub ended: Option<StreamStats>,
}

/// Object entities by dataset instance id.
#[derive(Resource, Debug, Clone, Default)]
pub struct ObjectIndex(pub BTreeMap<ObjectId, Entity>);

/// Category entities by class.
#[derive(Resource, Debug, Clone, Default)]
pub struct CategoryIndex(pub BTreeMap<ClassId, Entity>);

/// Wall-clock time spent per stage.
#[derive(Resource, Debug, Clone, Default)]
pub struct StageTimes(pub BTreeMap<&'static str, Duration>);

impl StageTimes {
    /// Starts timing `stage`; the time is added when the returned guard drops.
    pub fn start(&mut self, stage: &'static str) -> StageTimer<'_> {
        StageTimer {
            times: self,
            stage,
            started: Instant::now(),
        }
    }
}

/// Adds the time since its creation to a stage when dropped.
pub struct StageTimer<'a> {
    times: &'a mut StageTimes,
    stage: &'static str,
    started: Instant,
}

impl Drop for StageTimer<'_> {
    fn drop(&mut self) {
        *self.times.0.entry(self.stage).or_default() += self.started.elapsed();
    }
}
