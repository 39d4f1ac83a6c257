//! The one path through a run: the stream, then the training due after it, then the category
//! phase — each resumable where it stopped (after a checkpoint, or in a restored mapper).

use std::ops::ControlFlow;
use std::time::Duration;

use super::Mapper;
use crate::resources::{FrameInbox, StreamProgress};

/// The phases of a run, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum RunPhase {
    /// Frames stream in; every frame queues its training steps.
    Stream,
    /// The training due once the stream has ended (`MapperConfig::after_stream`: the offline
    /// training, the paper's refinement, or the fast schedule's one phase of every field).
    AfterStream,
    /// The category phase (`category_fields.enabled`, unless the fast schedule trained the
    /// category fields in the phase before).
    Categories,
}

/// How far a run has come, reported after every step of the stream and every chunk of
/// [`super::CHUNK_STEPS`] training steps after it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunProgress {
    /// The phase running.
    pub phase: RunPhase,
    /// Frames ingested (stream), or steps of the phase done.
    pub done: u64,
    /// The phase's most steps (`None` for the stream, whose length the reader knows).
    pub cap: Option<u64>,
}

/// How [`Mapper::run`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunOutcome {
    /// Every phase has run: the map is ready for its final meshes.
    Complete,
    /// The callback asked to pause here (e.g. for a checkpoint); `run` continues from it.
    Paused(RunProgress),
}

impl Mapper {
    /// Runs the remaining phases — the stream until its end, the training after it, the
    /// category phase — calling `on_progress` after every step of the stream and every chunk of
    /// training; pauses when it breaks. A paused (or restored) mapper continues where it was.
    pub fn run(&mut self, mut on_progress: impl FnMut(RunProgress) -> ControlFlow<()>) -> RunOutcome {
        let mut paused = None;
        let mut report = |progress: RunProgress| {
            let flow = on_progress(progress);
            if flow.is_break() {
                paused = Some(progress);
            }
            flow
        };
        let complete = self.stream_until(&mut report)
            && self.after_stream_until(&mut report)
            && self.categories_until(&mut report);
        match (complete, paused) {
            (false, Some(progress)) => RunOutcome::Paused(progress),
            _ => RunOutcome::Complete,
        }
    }

    /// Steps until the stream ends or `on_step` breaks; returns whether the stream has ended.
    fn stream_until(&mut self, on_step: &mut impl FnMut(RunProgress) -> ControlFlow<()>) -> bool {
        while !self.stream_ended() {
            let inbox = self.world.resource::<FrameInbox>().0.clone();
            if inbox.is_empty() {
                // Wait for the reader instead of spinning; the timeout keeps the loop responsive.
                let mut select = crossbeam_channel::Select::new();
                select.recv(&inbox);
                let ready = select.ready_timeout(Duration::from_millis(100)).is_ok();
                if !ready || !inbox.is_empty() {
                    continue;
                }
                // Ready yet empty: the reader hung up without its end; a step lets ingest end the stream.
            }
            self.step();
            let progress = RunProgress {
                phase: RunPhase::Stream,
                done: self.world.resource::<StreamProgress>().frames_ingested,
                cap: None,
            };
            if on_step(progress).is_break() {
                break;
            }
        }
        self.stream_ended()
    }
}
