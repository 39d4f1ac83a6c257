//! Tick stage: the run's phase as ECS state. Each tick queues the training steps its phase
//! plans (`catmap::training::PhasePlan::tick_steps`: per frame, per chunk, or, live, as many
//! as fit in the tick's time), and at its end records the progress of a phase after the stream
//! and moves to the phase that follows (`PhasePlan::after_tick`).

use std::time::Instant;

use bevy_ecs::prelude::*;
use catmap::training::{FinishClock, RunPhase, TickBudget, TickKind};

use crate::components::CameraFrame;
use crate::resources::{CategoryFields, Settings, StreamProgress, TrainingQueue, TrainingSchedule};
use crate::run_state::{CurrentPhase, LiveTicks, PhaseProgress, TickRecord};

/// A live tick starts its clock.
pub fn start_tick_clock(mut live: ResMut<LiveTicks>) {
    live.tick_started = Instant::now();
    live.train_seconds = 0.0;
}

/// Queues the steps the phase plans for this tick: `fields.steps_per_frame` per frame taken
/// while streaming and chunks after it, or, live, what fits in the tick's time.
pub fn queue_tick_steps(
    settings: Res<Settings>,
    phase: Res<CurrentPhase>,
    phases: Res<PhaseProgress>,
    frames: Query<(), Added<CameraFrame>>,
    live: Option<ResMut<LiveTicks>>,
    mut queue: ResMut<TrainingQueue>,
    mut category: ResMut<CategoryFields>,
    mut record: ResMut<TickRecord>,
) {
    let config = &settings.0;
    let taken = frames.iter().count() as u64;
    let kind = if taken > 0 { TickKind::Frame } else { TickKind::Idle };
    let budget = match live {
        Some(mut live) => {
            let now = Instant::now();
            let finish_left = live
                .finish_deadline
                .map_or(f64::INFINITY, |d| d.saturating_duration_since(now).as_secs_f64());
            let seconds = live.clock.tick_seconds(phase.0, kind, &config.stream.live, finish_left);
            live.train_started = now;
            TickBudget::Clock {
                steps: live.clock.tick_steps(kind, seconds),
            }
        }
        None => TickBudget::Steps {
            frames: taken,
            steps_per_frame: config.fields.steps_per_frame as u64,
        },
    };
    let (done, _) = phases.of(phase.0);
    let steps = config.phase_plan().tick_steps(phase.0, done, budget);
    queue.pending += steps.objects;
    category.pending += steps.categories;
    *record = TickRecord { steps, kind };
}

/// A live tick records how long it trained.
pub fn stop_train_clock(mut live: ResMut<LiveTicks>) {
    live.train_seconds = live.train_started.elapsed().as_secs_f64();
}

/// Ends the tick: a phase after the stream records its steps and, once it ends, why; the run
/// moves to the phase that follows. A live run's clock takes in the tick's durations, and its
/// finishing time starts when the stream ends.
pub fn advance_run_phase(
    settings: Res<Settings>,
    mut phase: ResMut<CurrentPhase>,
    mut phases: ResMut<PhaseProgress>,
    record: Res<TickRecord>,
    schedule: Res<TrainingSchedule>,
    stream: Res<StreamProgress>,
    live: Option<ResMut<LiveTicks>>,
) {
    let plan = settings.0.phase_plan();
    let now = Instant::now();
    let finish = match &live {
        None => FinishClock::Unbounded,
        Some(live) if live.finish_deadline.is_some_and(|d| now >= d) => FinishClock::Spent,
        Some(_) => FinishClock::Running,
    };
    let (done, _) = phases.of(phase.0);
    let planned = (schedule.planned_objects, schedule.planned_categories);
    let end = plan.phase_end(phase.0, done + record.steps.objects, planned, finish);
    phases.advance(phase.0, record.steps.objects, end);
    let next = plan.after_tick(phase.0, stream.ended.is_some(), end);
    if let Some(mut live) = live {
        let tick = now.duration_since(live.tick_started).as_secs_f64();
        let train = live.train_seconds;
        let steps = record.steps.objects.max(record.steps.categories);
        tracing::debug!(kind = ?record.kind, steps, train, other = tick - train, "live tick");
        live.clock.observe(record.kind, steps, train, tick - train);
        if phase.0 == RunPhase::Stream && next != RunPhase::Stream {
            let finish = std::time::Duration::from_secs_f64(settings.0.stream.live.finish_seconds);
            live.finish_deadline = Some(now + finish);
        }
    }
    if next != phase.0 {
        tracing::debug!(from = ?phase.0, to = ?next, "run phase");
        phase.0 = next;
    }
}
