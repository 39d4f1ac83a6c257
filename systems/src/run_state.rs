//! The run's phase as ECS state: which phase the ticks belong to (the schedule's run conditions
//! read it), what the current tick queued, how far the phases after the stream have come, and
//! a live run's clock.

use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use std::time::Instant;

use catmap::dataset::live_replay::ReportWindow;

use bevy_ecs::prelude::*;
use catmap::training::{LiveClock, PhaseEnd, RunPhase, TickKind, TickSteps};

/// The phase the next tick belongs to.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct CurrentPhase(pub RunPhase);

/// What the current tick queued, and whether it took a frame.
#[derive(Resource, Debug, Clone, Copy, PartialEq, Eq)]
pub struct TickRecord {
    /// Steps queued for the object batch and the category fields.
    pub steps: TickSteps,
    /// Whether a frame was taken.
    pub kind: TickKind,
}

impl Default for TickRecord {
    fn default() -> Self {
        Self {
            steps: TickSteps::default(),
            kind: TickKind::Idle,
        }
    }
}

/// How far the phases after the stream have come, so that a resumed run continues where it
/// stopped.
#[derive(Resource, Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct PhaseProgress {
    /// Steps of the training after the stream (offline training or online refinement) done.
    pub after_stream_steps: u64,
    /// Steps of the category phase done.
    pub category_steps: u64,
    /// Why the training after the stream ended, once it has.
    #[serde(default)]
    pub after_stream_end: Option<PhaseEnd>,
    /// Why the category phase ended, once it has.
    #[serde(default)]
    pub category_end: Option<PhaseEnd>,
}

impl PhaseProgress {
    /// Steps done in `phase` and why it ended (the phases after the stream; none for the others).
    pub fn of(&self, phase: RunPhase) -> (u64, Option<PhaseEnd>) {
        match phase {
            RunPhase::AfterStream => (self.after_stream_steps, self.after_stream_end),
            RunPhase::CategorySetup | RunPhase::Categories => (self.category_steps, self.category_end),
            RunPhase::Stream | RunPhase::Meshing | RunPhase::Done => (0, None),
        }
    }

    /// Records `steps` more steps of `phase`, and why it ended (`None`: it goes on).
    pub fn advance(&mut self, phase: RunPhase, steps: u64, end: Option<PhaseEnd>) {
        let (done, ended) = match phase {
            RunPhase::AfterStream => (&mut self.after_stream_steps, &mut self.after_stream_end),
            RunPhase::Categories => (&mut self.category_steps, &mut self.category_end),
            RunPhase::Stream | RunPhase::CategorySetup | RunPhase::Meshing | RunPhase::Done => return,
        };
        *done += steps;
        *ended = end;
    }
}

/// A live run's clock (present only with `stream.live.enabled`): the running means that size
/// each tick's training, and the instants the current tick measures.
#[derive(Resource, Debug, Clone)]
pub struct LiveTicks {
    /// Step and mapping durations so far.
    pub clock: LiveClock,
    /// When the current tick started.
    pub tick_started: Instant,
    /// When the current tick's training started, and how long it took.
    pub train_started: Instant,
    /// Seconds the current tick trained.
    pub train_seconds: f64,
    /// When the finishing time after the stream is spent (set when the stream ends).
    pub finish_deadline: Option<Instant>,
    /// When the run started (the clock of the reports).
    pub started: Instant,
    /// The frames the reader has dropped so far.
    pub dropped: Arc<AtomicU64>,
    /// The window of the next once-a-second report.
    pub report: ReportWindow,
}

impl LiveTicks {
    /// A live run's ticks, reading the reader's drops from `dropped`.
    pub fn new(dropped: Arc<AtomicU64>) -> Self {
        let now = Instant::now();
        Self {
            clock: LiveClock::default(),
            tick_started: now,
            train_started: now,
            train_seconds: 0.0,
            finish_deadline: None,
            started: now,
            dropped,
            report: ReportWindow::default(),
        }
    }
}
