//! The `Mapper` facade: a `World` with the mapper's resources and schedule, fed frame by frame.

use std::collections::BTreeMap;
use std::path::Path;

use bevy_ecs::prelude::*;
use catmap::dataset::stream::{StreamMessage, StreamStats};
use catmap::meshing::MapMeshes;
use catmap::objects::keyframes::KeyframeWindow;
use catmap::objects::observed_cloud::ObservedCloud;
use catmap::rng::{RngStream, seeded_rng};
use catmap::{MapperConfig, RgbdFrame};
use crossbeam_channel::{Receiver, Sender, TrySendError, bounded};

use crate::checkpoint::SavedMapper;
use crate::components::{
    Background, Category, FieldLoss, FieldSlot, Keyframes, Object, ObjectCloud, ObjectRng, VisibleFrames,
};
use crate::failed_step::{FailedStep, StepFailure};
use crate::recording::Rerun;
use crate::resources::CategoryFields;
use crate::resources::{
    Association, BorderHistory, CategoryIndex, DatasetClasses, Fields, FinalMeshes, FrameInbox, ObjectIndex, Settings,
    SmallInstances, StageTimes, StreamProgress, TrainingQueue, TrainingSchedule,
};
use crate::run_state::{CurrentPhase, LiveTicks, PhaseProgress, TickRecord};
use crate::schedule::build_schedule;
use crate::snapshot::MapSnapshot;
use crate::stages::log_rerun::log_world_setup;

mod run;

pub use catmap::training::{CHUNK_STEPS, RunPhase};
pub use run::{RunOutcome, RunProgress};

/// Errors of the mapper facade.
#[derive(Debug, thiserror::Error)]
pub enum MapperError {
    /// The configuration is invalid, or a checkpoint cannot be written or used.
    #[error(transparent)]
    Config(#[from] catmap::CatmapError),
    /// A pushed frame is malformed.
    #[error("frame {index}: {reason}")]
    BadFrame {
        /// The frame's index.
        index: u64,
        /// What is wrong.
        reason: String,
    },
    /// `push` was called on a mapper fed by a reader thread, or after the end of the stream.
    #[error("this mapper does not accept pushed frames: {0}")]
    NotAccepting(&'static str),
    /// A training step failed on a broken invariant: the run stops at the tick it failed in (a
    /// checkpoint written before it is left to resume from).
    #[error("{0}")]
    StepFailed(Box<StepFailure>),
    /// The mapper was stepped, or asked for a checkpoint, after a step failed.
    #[error("the run stopped at a failed training step")]
    Stopped,
}

/// A streaming mapper: push frames (or attach a reader thread), step, and read the map.
pub struct Mapper {
    world: World,
    schedule: Schedule,
    /// Sending end for `push`; `None` when a reader thread feeds the inbox, or after `end_stream`.
    pusher: Option<Sender<StreamMessage>>,
    /// Whether a step failed ([`MapperError::StepFailed`]): the mapper runs no more ticks.
    failed: bool,
}

impl Mapper {
    /// A mapper fed by [`Mapper::push`].
    pub fn new(config: MapperConfig) -> Result<Self, MapperError> {
        let (sender, receiver) = bounded(config.stream.channel_capacity.max(1));
        let mut mapper = Self::with_inbox(config, receiver)?;
        mapper.pusher = Some(sender);
        Ok(mapper)
    }

    /// A mapper fed by a reader thread's channel (see `catmap::dataset::stream::FrameStream`).
    pub fn with_inbox(config: MapperConfig, inbox: Receiver<StreamMessage>) -> Result<Self, MapperError> {
        config.validate()?;
        for key in config.unused_step_counts() {
            tracing::warn!(
                "{key} is not used by the fast schedule: it trains after the stream until every field converges, at most schedule.max_steps_after_stream = {} steps (`--schedule paper` runs {key})",
                config.schedule.max_steps_after_stream
            );
        }
        let mut world = World::new();
        world.spawn((
            Background,
            Keyframes(KeyframeWindow::default()),
            VisibleFrames::default(),
            ObjectCloud(ObservedCloud::new(config.objects.background_voxel_m)),
            ObjectRng(seeded_rng(config.seed, RngStream::Background)),
        ));
        world.insert_resource(Fields::new(config.fields.optimiser()));
        world.insert_resource(CategoryFields::new(config.fields.optimiser()));
        world.init_resource::<TrainingQueue>();
        world.init_resource::<TrainingSchedule>();
        world.insert_resource(Settings(config));
        world.insert_resource(FrameInbox(inbox));
        world.init_resource::<StreamProgress>();
        world.init_resource::<ObjectIndex>();
        world.init_resource::<DatasetClasses>();
        world.init_resource::<Association>();
        world.init_resource::<BorderHistory>();
        world.init_resource::<CategoryIndex>();
        world.init_resource::<StageTimes>();
        world.init_resource::<SmallInstances>();
        world.init_resource::<PhaseProgress>();
        world.insert_resource(CurrentPhase(RunPhase::Stream));
        world.init_resource::<TickRecord>();
        world.init_resource::<FinalMeshes>();
        if world.resource::<Settings>().0.stream.live.enabled {
            world.insert_resource(LiveTicks::new(std::sync::Arc::default()));
        }
        world.init_resource::<FailedStep>();
        Ok(Self {
            world,
            schedule: build_schedule(),
            pusher: None,
            failed: false,
        })
    }

    /// The configuration the mapper runs with.
    pub fn config(&self) -> &MapperConfig {
        &self.world.resource::<Settings>().0
    }

    /// A live mapper (`stream.live.enabled`) reads the reader's dropped frames from `dropped`
    /// (`FrameStream::dropped`) for its once-a-second report.
    pub fn count_drops_from(&mut self, dropped: std::sync::Arc<std::sync::atomic::AtomicU64>) {
        if let Some(mut live) = self.world.get_resource_mut::<LiveTicks>() {
            live.dropped = dropped;
        }
    }

    /// Names classes with `names` from now on (summary, Rerun labels, `categories.json`).
    pub fn set_class_names(&mut self, names: catmap::dataset::class_names::ClassNames) {
        self.world.insert_resource(DatasetClasses(names));
    }

    /// Logs to `recording` from now on (the `Log` stage only runs with a recording).
    pub fn set_recording(&mut self, recording: rerun::RecordingStream) {
        crate::blueprint::send_mapper_blueprint(&recording);
        log_world_setup(&recording);
        self.world.insert_resource(Rerun(recording));
    }

    /// Queues one frame. When the inbox is full the mapper steps until there is room, so no
    /// frame is ever dropped.
    pub fn push(&mut self, frame: RgbdFrame) -> Result<(), MapperError> {
        frame.validate().map_err(|reason| MapperError::BadFrame {
            index: frame.index.0,
            reason,
        })?;
        let mut message = StreamMessage::Frame(std::sync::Arc::new(frame));
        loop {
            let sender = self.pusher.as_ref().ok_or(MapperError::NotAccepting("no push inbox"))?;
            match sender.try_send(message) {
                Ok(()) => return Ok(()),
                Err(TrySendError::Full(returned)) => {
                    message = returned;
                    self.step()?;
                }
                Err(TrySendError::Disconnected(_)) => return Err(MapperError::NotAccepting("inbox closed")),
            }
        }
    }

    /// Tells a push-fed mapper that no more frames will come.
    pub fn end_stream(&mut self) -> Result<(), MapperError> {
        if let Some(sender) = self.pusher.take() {
            // The receiver lives in the world, so the channel is open; a full one is drained first.
            let mut message = StreamMessage::End(StreamStats::default());
            loop {
                match sender.try_send(message) {
                    Ok(()) | Err(TrySendError::Disconnected(_)) => break,
                    Err(TrySendError::Full(returned)) => {
                        message = returned;
                        self.step()?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Runs every stage once. Errors when a training step failed in this tick (once; later
    /// calls return [`MapperError::Stopped`]).
    pub fn step(&mut self) -> Result<(), MapperError> {
        if self.failed {
            return Err(MapperError::Stopped);
        }
        self.schedule.run(&mut self.world);
        match self.world.resource_mut::<FailedStep>().0.take() {
            Some(failure) => {
                self.failed = true;
                Err(MapperError::StepFailed(Box::new(failure)))
            }
            None => Ok(()),
        }
    }

    /// The reader's statistics, once the stream has ended.
    pub fn stream_stats(&self) -> Option<StreamStats> {
        self.world.resource::<StreamProgress>().ended
    }

    /// Whether the end-of-stream message has been ingested.
    pub fn stream_ended(&self) -> bool {
        self.world.resource::<StreamProgress>().ended.is_some()
    }

    /// Stream positions consumed so far (frames ingested plus frames the reader skipped): a
    /// resumed run's reader starts here.
    pub fn positions_consumed(&self) -> usize {
        let progress = self.world.resource::<StreamProgress>();
        (progress.frames_ingested + progress.frames_skipped) as usize
    }

    /// Writes the mapper's whole state to the checkpoint folder `dir` (a new generation; see
    /// `catmap::checkpoint`), with `extra` (the caller's own JSON) beside it. Refused after a
    /// failed step, so that the checkpoint written before it is kept.
    pub fn save_checkpoint(&mut self, dir: &Path, label: &str, extra: String) -> Result<(), MapperError> {
        if self.failed {
            return Err(MapperError::Stopped);
        }
        let (state, tensors) = crate::checkpoint::capture(&mut self.world, extra)?;
        catmap::checkpoint::write_checkpoint(dir, &state, &tensors, label)?;
        Ok(())
    }

    /// A mapper restored from `saved`, fed by `inbox` from [`SavedMapper::positions_consumed`]
    /// on (`crossbeam_channel::never()` when [`SavedMapper::stream_ended`]).
    pub fn from_checkpoint(saved: SavedMapper, inbox: Receiver<StreamMessage>) -> Result<Self, MapperError> {
        let mut mapper = Self::with_inbox(saved.config().clone(), inbox)?;
        let (state, tensors, file) = saved.into_parts();
        crate::checkpoint::restore(&mut mapper.world, state, tensors, &file)?;
        let progress = *mapper.world.resource::<PhaseProgress>();
        let phase = mapper.config().phase_plan().resumed(
            mapper.stream_ended(),
            progress.after_stream_end,
            (progress.category_steps, progress.category_end),
        );
        mapper.world.insert_resource(CurrentPhase(phase));
        Ok(mapper)
    }

    /// How the fields have trained so far: the schedule, each field's steps, state and carving
    /// counts, and why the phases after the stream ended.
    pub fn training_report(&mut self) -> crate::summary::TrainingReport {
        use catmap::training::FieldKey;
        let mut carving = std::collections::BTreeMap::new();
        let mut owners = self.world.query::<(Option<&Object>, &FieldLoss)>();
        for (object, loss) in owners.iter(&self.world) {
            let key = object.map_or(FieldKey::Background, |o| FieldKey::Object(o.id));
            carving.insert(key, loss.carve);
        }
        let priors = self.prior_cells();
        let categories = self.world.resource::<CategoryFields>();
        for (id, counts) in categories.ids.iter().zip(&categories.carve) {
            carving.insert(FieldKey::Category(*id), *counts);
        }
        crate::summary::TrainingReport::new(
            self.world.resource::<Settings>().0.training_policy(),
            &self.world.resource::<TrainingSchedule>().scheduler,
            self.world.resource::<PhaseProgress>(),
            &carving,
            &priors,
            crate::summary::CategoryHistory {
                retired: &categories.retired,
                frames_replaced: categories.frames_replaced,
            },
        )
    }

    /// Per object field that takes the priors of objects alone in their class, the cells they
    /// last drew from.
    fn prior_cells(&mut self) -> BTreeMap<catmap::training::FieldKey, catmap::objects::hidden_space::PriorCells> {
        let mut classes = self.world.query::<&Category>();
        let class_sizes = catmap::training::class_sizes(classes.iter(&self.world).map(|c| &c.members[..]));
        let mut owners = self.world.query::<(&Object, &FieldSlot)>();
        let caches = &self.world.resource::<Fields>().hidden_spaces;
        owners
            .iter(&self.world)
            .filter(|(object, _)| catmap::training::takes_shape_priors(class_sizes.of(object.id)))
            .filter_map(|(object, slot)| {
                let space = caches.get(slot.index)?.latest()?;
                Some((catmap::training::FieldKey::Object(object.id), space.cells()))
            })
            .collect()
    }

    /// Number of category fields created so far.
    pub fn category_field_count(&self) -> usize {
        self.world.resource::<CategoryFields>().members.len()
    }

    /// Training steps run so far (object batch).
    pub fn training_steps(&self) -> u64 {
        self.world.resource::<TrainingQueue>().steps_done
    }

    /// The final meshes (every field at final resolution, logged to Rerun when recording; a
    /// warning names every object left without a mesh), taken from the map: those the run's
    /// meshing phase made, or — for a mapper fed by `push` whose run did not get there — made now,
    /// the run ending here. Empty without fields, and for a second call.
    pub fn extract_final_meshes(&mut self) -> Result<MapMeshes, MapperError> {
        if self.phase() < RunPhase::Meshing {
            self.world.insert_resource(CurrentPhase(RunPhase::Meshing));
        }
        if self.phase() == RunPhase::Meshing {
            self.step()?;
        }
        Ok(self.world.resource_mut::<FinalMeshes>().take_map().unwrap_or_default())
    }

    /// Every class's subcategories as registered so far (see `categories.json`).
    pub fn category_records(&mut self) -> Vec<crate::categories_report::ClassRecord> {
        crate::categories_report::category_records(&mut self.world)
    }

    /// A read-only view of the map as it is now.
    pub fn snapshot(&mut self) -> MapSnapshot {
        MapSnapshot::of(&mut self.world)
    }

    /// Ends the run: flushes the recording and returns the final map.
    pub fn finish(mut self) -> MapSnapshot {
        let snapshot = self.snapshot();
        if let Some(rerun) = self.world.get_resource::<Rerun>()
            && let Err(e) = rerun.0.flush_blocking()
        {
            tracing::warn!(error = %e, "flushing the Rerun recording failed");
        }
        snapshot
    }

    /// Seconds spent per stage so far.
    pub fn stage_seconds(&self) -> BTreeMap<String, f64> {
        self.world
            .resource::<StageTimes>()
            .0
            .iter()
            .map(|(k, v)| (k.clone(), v.as_secs_f64()))
            .collect()
    }

    /// The ECS world, for inspection in tests and tools.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The ECS world, mutable (queries need `&mut World`).
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }
}
