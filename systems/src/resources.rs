//! Resources: configuration, the frame inbox, indices and run statistics.

use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use catmap::categories::field_set::CategoryFieldSet;
use catmap::dataset::class_names::ClassNames;
use catmap::dataset::stream::{StreamMessage, StreamStats};
use catmap::field::AdamWConfig;
use catmap::sensor::frame::SharedFrame;
use catmap::training::{FieldKey, PlateauConfig, StreamPhase};
use catmap::{ClassId, FrameIndex, MapperConfig, ObjectId};
use crossbeam_channel::{Receiver, TryRecvError};

/// The mapper's configuration.
#[derive(Resource, Debug, Clone)]
pub struct Settings(pub MapperConfig);

/// The names of the dataset's classes (Replica's, which the synthetic scenes use, unless the
/// source names its own).
#[derive(Resource, Debug, Clone)]
pub struct DatasetClasses(pub ClassNames);

impl Default for DatasetClasses {
    fn default() -> Self {
        Self(ClassNames::replica())
    }
}

/// The association of per-frame masks into objects (`objects.association.instances =
/// "per-frame"`).
#[derive(Resource, Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Association(pub catmap::objects::instance_association::InstanceTracker);

/// The last frames' mask labels, which decide the pixels of the next frames' mask borders
/// (`objects.border_votes`; empty when it is off).
#[derive(Resource, Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BorderHistory(pub catmap::objects::border_votes::LabelHistory);

/// The receiving end of the frame stream.
#[derive(Resource, Debug)]
pub struct FrameInbox(pub Receiver<StreamMessage>);

/// How far the stream has come.
#[derive(Resource, Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
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

impl StreamProgress {
    /// Counts one message from the stream (a skipped frame is logged); returns the frame it
    /// carries, if any.
    pub fn record(&mut self, message: StreamMessage) -> Option<SharedFrame> {
        match message {
            StreamMessage::Frame(frame) => {
                tracing::trace!(frame = %frame.index, "ingest");
                self.frames_ingested += 1;
                self.last_frame = Some(frame.index);
                return Some(frame);
            }
            StreamMessage::Skipped { position, reason } => {
                tracing::warn!(position, %reason, "skipping frame");
                self.frames_skipped += 1;
            }
            StreamMessage::End(stats) => {
                tracing::debug!(?stats, "end of stream");
                self.ended = Some(stats);
            }
        }
        None
    }

    /// Takes at most `cap` messages from `inbox` and counts them; returns the frames they carry.
    /// A reader gone without its end message (it died) ends the stream once the inbox is empty.
    /// Every message received is counted: none is taken only to test the channel.
    pub fn take_from(&mut self, inbox: &Receiver<StreamMessage>, cap: usize) -> Vec<SharedFrame> {
        let mut frames = Vec::new();
        for _ in 0..cap {
            if self.ended.is_some() {
                break;
            }
            match inbox.try_recv() {
                Ok(message) => frames.extend(self.record(message)),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => self.end_without_message(),
            }
        }
        frames
    }

    /// Ends a stream whose reader is gone without its end message (it died): what was mapped
    /// is kept.
    pub fn end_without_message(&mut self) {
        tracing::warn!(
            frames = self.frames_ingested,
            "the stream stopped without its end; finishing"
        );
        self.ended = Some(StreamStats {
            frames_sent: self.frames_ingested,
            frames_skipped: self.frames_skipped,
            ..StreamStats::default()
        });
    }

    /// Whether frames still stream in.
    pub fn phase(&self) -> StreamPhase {
        if self.ended.is_some() {
            StreamPhase::Ended
        } else {
            StreamPhase::Streaming
        }
    }
}

/// Object entities by dataset instance id.
#[derive(Resource, Debug, Clone, Default)]
pub struct ObjectIndex(pub BTreeMap<ObjectId, Entity>);

/// Category entities by class.
#[derive(Resource, Debug, Clone, Default)]
pub struct CategoryIndex(pub BTreeMap<ClassId, Entity>);

/// Instances seen with a 2D box at most `objects.min_box_side_px` wide or high, with the number of
/// frames each was ignored in (those never seen bigger are named in a warning at the end).
#[derive(Resource, Debug, Clone, Default)]
pub struct SmallInstances(pub BTreeMap<ObjectId, u32>);

/// Wall-clock time spent per stage.
#[derive(Resource, Debug, Clone, Default)]
pub struct StageTimes(pub BTreeMap<String, Duration>);

impl StageTimes {
    /// Starts timing `stage`; the time is added when the returned guard drops.
    pub fn start(&mut self, stage: &'static str) -> StageTimer<'_> {
        StageTimer {
            times: self,
            stage,
            started: Instant::now(),
        }
    }

    /// Adds `elapsed` to `stage`.
    pub fn add(&mut self, stage: &str, elapsed: Duration) {
        *self.0.entry(stage.to_owned()).or_default() += elapsed;
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
        self.times.add(self.stage, self.started.elapsed());
    }
}

/// Every field of the map: the objects' fields trained as one batch, and the background's.
#[derive(Resource, Debug)]
pub struct Fields {
    /// Object fields (H = 32), in creation order.
    pub objects: catmap::field::FieldBatch,
    /// The entity owning each object field, by batch index (none once its object was merged
    /// into another: the field stays, untrained, so that indices hold).
    pub object_owners: Vec<Option<Entity>>,
    /// The background field (H = 128), once the background has keyframes.
    pub background: catmap::field::FieldBatch,
    /// The background entity, once its field exists.
    pub background_owner: Option<Entity>,
    /// Per object field (batch index), the cells of its box no view saw into, as last computed
    /// (the solid prior's; derived from keyframes and box, so not checkpointed).
    pub hidden_spaces: Vec<catmap::objects::hidden_space::HiddenSpaceCache>,
}

impl Fields {
    /// No fields yet; both batches use `optimiser`.
    pub fn new(optimiser: catmap::field::AdamWConfig) -> Self {
        Self {
            objects: catmap::field::FieldBatch::new(optimiser),
            object_owners: Vec::new(),
            background: catmap::field::FieldBatch::new(optimiser),
            background_owner: None,
            hidden_spaces: Vec::new(),
        }
    }
}

/// Training steps waiting to run, and steps run so far.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct TrainingQueue {
    /// Steps the training system will run at its next call.
    pub pending: u64,
    /// Object-batch steps run so far.
    pub steps_done: u64,
}

/// The step scheduler (which fields take the next steps; each field's steps and losses) and
/// the size of its latest plans.
#[derive(Resource, Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrainingSchedule {
    /// The scheduler's state.
    pub scheduler: catmap::training::StepScheduler,
    /// Object fields in the latest plan.
    pub planned_objects: usize,
    /// Category fields in the latest plan.
    pub planned_categories: usize,
}

impl TrainingSchedule {
    /// Records a batched step's per-field losses (in `keys` order) with the scheduler.
    pub fn record_step(&mut self, keys: &[FieldKey], losses: &[f32], plateau: &PlateauConfig) {
        self.scheduler.record_step(keys, losses, plateau);
    }
}

/// The category fields and their members (`catmap::categories::field_set`), and the steps
/// queued for them.
#[derive(Resource, Debug)]
pub struct CategoryFields {
    /// The fields, their members and keys.
    pub set: CategoryFieldSet,
    /// Steps queued and not yet run.
    pub pending: u64,
    /// Steps run.
    pub steps_done: u64,
    /// Per object field index, the member's cells hidden in every member of its field (the
    /// members' solid prior; empty for objects that are no member).
    pub member_hidden: Vec<catmap::categories::member_hidden::MemberHiddenCache>,
}

impl CategoryFields {
    /// No fields yet.
    pub fn new(optimiser: AdamWConfig) -> Self {
        Self {
            set: CategoryFieldSet::new(optimiser),
            pending: 0,
            steps_done: 0,
            member_hidden: Vec::new(),
        }
    }
}

impl std::ops::Deref for CategoryFields {
    type Target = CategoryFieldSet;

    fn deref(&self) -> &CategoryFieldSet {
        &self.set
    }
}

impl std::ops::DerefMut for CategoryFields {
    fn deref_mut(&mut self) -> &mut CategoryFieldSet {
        &mut self.set
    }
}

/// A mesh extracted from a field, with the entity that owns it.
#[derive(Debug, Clone)]
pub struct OwnerMesh {
    /// The object's or the background's entity.
    pub entity: Entity,
    /// The object's id; `None` for the background.
    pub object: Option<ObjectId>,
    /// The mesh (world coordinates).
    pub mesh: catmap::geometry::mesh::TriangleMesh,
    /// Which field it was extracted from.
    pub source: catmap::training::MeshSource,
}

/// The final meshes, once the run's meshing phase made them (taken by
/// `Mapper::extract_final_meshes`).
#[derive(Resource, Debug, Clone, Default)]
pub struct FinalMeshes(pub Option<Vec<OwnerMesh>>);

impl FinalMeshes {
    /// Takes the meshes as the map's: objects by id, and the background's.
    pub fn take_map(&mut self) -> Option<catmap::meshing::MapMeshes> {
        let mut map = catmap::meshing::MapMeshes::default();
        for OwnerMesh { object, mesh, .. } in self.0.take()? {
            match object {
                Some(id) => {
                    map.objects.insert(id, mesh);
                }
                None => map.background = Some(mesh),
            }
        }
        Some(map)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn skipped(position: usize) -> StreamMessage {
        StreamMessage::Skipped {
            position,
            reason: format!("frame {position} unreadable"),
        }
    }

    #[test]
    fn a_tick_takes_at_most_its_cap_and_counts_every_message_it_takes() {
        let (sender, inbox) = crossbeam_channel::unbounded();
        for position in 0..5 {
            sender.send(skipped(position)).expect("open channel");
        }
        let mut progress = StreamProgress::default();
        assert!(
            progress.take_from(&inbox, 3).is_empty(),
            "skipped frames carry no frame"
        );
        assert_eq!(progress.frames_skipped, 3);
        assert_eq!(inbox.len(), 2, "the rest waits for the next tick");
        assert_eq!(progress.phase(), StreamPhase::Streaming);
    }

    #[test]
    fn a_reader_gone_without_its_end_ends_the_stream_only_after_its_last_message() {
        let (sender, inbox) = crossbeam_channel::unbounded();
        for position in 0..2 {
            sender.send(skipped(position)).expect("open channel");
        }
        drop(sender);
        let mut progress = StreamProgress::default();
        progress.take_from(&inbox, 2);
        assert_eq!(progress.frames_skipped, 2, "both messages counted");
        assert_eq!(progress.phase(), StreamPhase::Streaming, "the cap was reached first");
        progress.take_from(&inbox, 2);
        assert_eq!(progress.phase(), StreamPhase::Ended);
        assert_eq!(progress.ended.map(|s| s.frames_skipped), Some(2));
    }

    #[test]
    fn nothing_after_the_end_message_is_taken() {
        let (sender, inbox) = crossbeam_channel::unbounded();
        sender.send(skipped(0)).expect("open channel");
        sender
            .send(StreamMessage::End(StreamStats::default()))
            .expect("open channel");
        sender.send(skipped(1)).expect("open channel");
        let mut progress = StreamProgress::default();
        progress.take_from(&inbox, 10);
        assert_eq!(progress.phase(), StreamPhase::Ended);
        assert_eq!((progress.frames_skipped, inbox.len()), (1, 1));
    }
}
