//! The one path through a run: ticks of the one schedule until the run's phase
//! ([`CurrentPhase`]) is done — the stream, the training due after it, the category phase, the
//! final meshes — resumable where it stopped (after a checkpoint, or in a restored mapper).

use std::ops::ControlFlow;
use std::time::Duration;

use catmap::training::RunPhase;
use catmap::training::live_clock::IDLE_TICK_SECONDS;

use super::Mapper;
use crate::resources::{Fields, FrameInbox, Settings, StreamProgress, TrainingSchedule};
use crate::run_state::{CurrentPhase, LiveTicks, PhaseProgress};

/// How far a run has come, reported after every tick of the stream and of the phases after it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunProgress {
    /// The phase that ran: [`RunPhase::Stream`], [`RunPhase::AfterStream`] or
    /// [`RunPhase::Categories`] (its setup tick included).
    pub phase: RunPhase,
    /// Frames ingested (stream), or steps of the phase done.
    pub done: u64,
    /// The phase's most steps (`None` for the stream, whose length the reader knows).
    pub cap: Option<u64>,
}

/// How [`Mapper::run`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunOutcome {
    /// Every phase has run, the final meshing included (see [`Mapper::extract_final_meshes`]).
    Complete,
    /// The callback asked to pause here (e.g. for a checkpoint); `run` continues from it.
    Paused(RunProgress),
}

impl Mapper {
    /// Runs the remaining phases — the stream until its end, the training after it, the
    /// category phase, the final meshing — calling `on_progress` after every tick but the
    /// meshing's; pauses when it breaks. A paused (or restored) mapper continues where it was.
    /// Errors when a training step fails ([`super::MapperError::StepFailed`]).
    pub fn run(
        &mut self,
        mut on_progress: impl FnMut(RunProgress) -> ControlFlow<()>,
    ) -> Result<RunOutcome, super::MapperError> {
        loop {
            let phase = self.phase();
            if phase == RunPhase::Done {
                return Ok(RunOutcome::Complete);
            }
            if phase == RunPhase::Stream && !self.frame_or_tick_due() {
                continue;
            }
            self.step()?;
            if let Some(progress) = self.progress_of(phase)
                && on_progress(progress).is_break()
                && self.phase() != RunPhase::Done
            {
                return Ok(RunOutcome::Paused(progress));
            }
        }
    }

    /// The phase the next tick belongs to.
    pub fn phase(&self) -> RunPhase {
        self.world.resource::<CurrentPhase>().0
    }

    /// While streaming: whether a tick is due, waiting up to 100 ms for the reader otherwise. A
    /// tick is due when a message waits (or the reader hung up without its end, which a tick's
    /// ingest then records). Live, a tick is also due when there is training to do: the mapper
    /// trains while it waits for frames; with nothing to train it waits up to
    /// [`IDLE_TICK_SECONDS`] for a frame, then ticks anyway.
    fn frame_or_tick_due(&self) -> bool {
        let inbox = self.world.resource::<FrameInbox>().0.clone();
        if !inbox.is_empty() {
            return true;
        }
        let live = self.world.contains_resource::<LiveTicks>();
        if live && self.has_training_to_do() {
            return true;
        }
        let wait = if live {
            Duration::from_secs_f64(IDLE_TICK_SECONDS)
        } else {
            Duration::from_millis(100)
        };
        let mut select = crossbeam_channel::Select::new();
        select.recv(&inbox);
        // Ready yet empty: the reader hung up without its end; a tick lets ingest end the stream.
        select.ready_timeout(wait).is_ok() || live
    }

    /// Whether fields exist and the latest plan trained some.
    fn has_training_to_do(&self) -> bool {
        let schedule = self.world.resource::<TrainingSchedule>();
        !self.world.resource::<Fields>().objects.is_empty()
            && schedule.planned_objects + schedule.planned_categories > 0
    }

    /// The progress after a tick of `phase` (none for the meshing).
    fn progress_of(&self, phase: RunPhase) -> Option<RunProgress> {
        let plan = self.world.resource::<Settings>().0.phase_plan();
        let reported = match phase {
            RunPhase::Stream => {
                return Some(RunProgress {
                    phase,
                    done: self.world.resource::<StreamProgress>().frames_ingested,
                    cap: None,
                });
            }
            RunPhase::AfterStream => RunPhase::AfterStream,
            RunPhase::CategorySetup | RunPhase::Categories => RunPhase::Categories,
            RunPhase::Meshing | RunPhase::Done => return None,
        };
        Some(RunProgress {
            phase: reported,
            done: self.world.resource::<PhaseProgress>().of(reported).0,
            cap: plan.cap(reported),
        })
    }
}
