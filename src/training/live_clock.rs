//! A live run's clock: how many training steps fit in a tick.
//!
//! A camera does not wait for the mapper. A tick that takes a frame first maps it (masks,
//! objects, clouds; afterwards registration, previews and logging), and trains in what is
//! left of the frame's interval `1 / fps`, but at least `min_train_share` of the interval: when
//! the frames come faster than the mapper can map them, training keeps its share, and the frames
//! that arrive meanwhile are dropped by the reader (the mapper always takes the newest). The
//! floor is a share of the interval, not of the mapping time: a registration that took seconds
//! does not make the next ticks train for seconds. A tick without a new frame trains for a
//! short slice and looks again. After the stream the ticks train in slices until the finishing
//! time is spent.
//!
//! The step's and the mapping's durations are running means of what earlier ticks measured (a
//! step's per kind of tick: a tick with a frame trains more fields, those seen in it), so the
//! clock needs no calibration; until a step of the kind is measured a tick trains one step.

use super::RunPhase;
use crate::config::LiveConfig;

/// Weight of the newest measurement in the running means.
const NEWEST_WEIGHT: f64 = 0.2;

/// Seconds a tick without a new frame trains before it looks for one again (at most the
/// frame interval).
pub const IDLE_TICK_SECONDS: f64 = 0.05;

/// Seconds a tick after the stream trains before progress is reported.
pub const FINISH_TICK_SECONDS: f64 = 0.5;

/// Most steps of one tick.
pub const MAX_TICK_STEPS: u64 = 500;

/// Whether a tick took a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TickKind {
    /// A frame was taken: it is mapped before the tick trains.
    Frame,
    /// No new frame had arrived (or the stream has ended).
    Idle,
}

/// Running means of a live run's step and mapping durations.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LiveClock {
    /// Seconds per training step (object batch and category fields together) in ticks that
    /// took a frame.
    pub seconds_per_frame_step: Option<f64>,
    /// Seconds per training step in ticks without a frame.
    pub seconds_per_idle_step: Option<f64>,
    /// Seconds a tick that takes a frame spends outside training.
    pub mapping_seconds: Option<f64>,
}

impl LiveClock {
    /// Records a tick: its kind, the steps it trained in `train_seconds`, and the seconds it
    /// spent on everything else.
    pub fn observe(&mut self, kind: TickKind, steps: u64, train_seconds: f64, other_seconds: f64) {
        if steps > 0 && train_seconds.is_finite() {
            mean_in(self.step_mean(kind), train_seconds / steps as f64);
        }
        if kind == TickKind::Frame && other_seconds.is_finite() {
            mean_in(&mut self.mapping_seconds, other_seconds.max(0.0));
        }
    }

    /// Seconds a tick of `phase` trains: see the module doc. `finish_left` is the finishing
    /// time left after the stream.
    pub fn tick_seconds(&self, phase: RunPhase, kind: TickKind, cfg: &LiveConfig, finish_left: f64) -> f64 {
        let interval = 1.0 / cfg.fps();
        match (phase, kind) {
            (RunPhase::Stream, TickKind::Frame) => {
                let mapping = self.mapping_seconds.unwrap_or(0.0);
                (interval - mapping).max(cfg.min_train_share * interval)
            }
            (RunPhase::Stream, TickKind::Idle) => IDLE_TICK_SECONDS.min(interval),
            (RunPhase::AfterStream | RunPhase::Categories, _) => FINISH_TICK_SECONDS.min(finish_left.max(0.0)),
            (RunPhase::CategorySetup | RunPhase::Meshing | RunPhase::Done, _) => 0.0,
        }
    }

    /// Steps of a `kind` tick that fit in `seconds`: at least one, at most [`MAX_TICK_STEPS`];
    /// one until a step of the kind has been measured.
    pub fn tick_steps(&self, kind: TickKind, seconds: f64) -> u64 {
        let step = match kind {
            TickKind::Frame => self.seconds_per_frame_step,
            TickKind::Idle => self.seconds_per_idle_step,
        };
        match step {
            Some(step) if step > 0.0 => ((seconds / step).floor() as u64).clamp(1, MAX_TICK_STEPS),
            _ => 1,
        }
    }

    /// The running mean of a step's seconds in `kind` ticks.
    fn step_mean(&mut self, kind: TickKind) -> &mut Option<f64> {
        match kind {
            TickKind::Frame => &mut self.seconds_per_frame_step,
            TickKind::Idle => &mut self.seconds_per_idle_step,
        }
    }
}

/// Folds `value` into the running mean `mean`.
fn mean_in(mean: &mut Option<f64>, value: f64) {
    *mean = Some(match *mean {
        Some(m) => m + NEWEST_WEIGHT * (value - m),
        None => value,
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    fn live(fps: f64) -> LiveConfig {
        LiveConfig {
            enabled: true,
            fps: Some(fps),
            ..LiveConfig::default()
        }
    }

    fn measured(step: f64, mapping: f64) -> LiveClock {
        LiveClock {
            seconds_per_frame_step: Some(step),
            seconds_per_idle_step: Some(step / 2.0),
            mapping_seconds: Some(mapping),
        }
    }

    #[test]
    fn a_frame_tick_trains_in_the_rest_of_its_interval() {
        let clock = measured(0.01, 0.08);
        let seconds = clock.tick_seconds(RunPhase::Stream, TickKind::Frame, &live(5.0), 10.0);
        assert!((seconds - 0.12).abs() < 1e-9, "{seconds}");
        assert_eq!(clock.tick_steps(TickKind::Frame, seconds), 12);
        assert_eq!(
            clock.tick_steps(TickKind::Idle, seconds),
            24,
            "idle steps train fewer fields"
        );
    }

    #[test]
    fn frames_faster_than_the_mapper_still_leave_training_its_share_of_the_interval() {
        let clock = measured(0.01, 0.08);
        let seconds = clock.tick_seconds(RunPhase::Stream, TickKind::Frame, &live(10.0), 10.0);
        assert!((seconds - 0.05).abs() < 1e-9, "half of the interval trains: {seconds}");
        let slow = measured(0.01, 2.0);
        let seconds = slow.tick_seconds(RunPhase::Stream, TickKind::Frame, &live(2.0), 10.0);
        assert!(
            (seconds - 0.25).abs() < 1e-9,
            "a long registration does not make training long: {seconds}"
        );
    }

    #[test]
    fn idle_and_finishing_ticks_train_in_short_slices_within_the_time_left() {
        let clock = measured(0.01, 0.08);
        let cfg = live(5.0);
        assert_eq!(
            clock.tick_seconds(RunPhase::Stream, TickKind::Idle, &cfg, 10.0),
            IDLE_TICK_SECONDS
        );
        assert_eq!(
            clock.tick_seconds(RunPhase::Stream, TickKind::Idle, &live(100.0), 10.0),
            0.01
        );
        assert_eq!(
            clock.tick_seconds(RunPhase::AfterStream, TickKind::Idle, &cfg, 10.0),
            FINISH_TICK_SECONDS
        );
        assert_eq!(
            clock.tick_seconds(RunPhase::AfterStream, TickKind::Idle, &cfg, 0.2),
            0.2
        );
        assert_eq!(
            clock.tick_seconds(RunPhase::Categories, TickKind::Idle, &cfg, -1.0),
            0.0
        );
        assert_eq!(clock.tick_seconds(RunPhase::Meshing, TickKind::Idle, &cfg, 5.0), 0.0);
    }

    #[test]
    fn steps_fit_the_time_between_one_and_the_cap_and_one_until_measured() {
        assert_eq!(
            LiveClock::default().tick_steps(TickKind::Frame, 1.0),
            1,
            "nothing measured yet"
        );
        let clock = measured(0.01, 0.0);
        assert_eq!(clock.tick_steps(TickKind::Frame, 0.0), 1);
        assert_eq!(clock.tick_steps(TickKind::Frame, 0.055), 5);
        assert_eq!(clock.tick_steps(TickKind::Frame, 1e6), MAX_TICK_STEPS);
    }

    #[test]
    fn the_means_follow_the_measurements() {
        let mut clock = LiveClock::default();
        clock.observe(TickKind::Frame, 10, 0.1, 0.05);
        assert_eq!(
            clock.seconds_per_frame_step,
            Some(0.01),
            "the first measurement is the mean"
        );
        assert_eq!(clock.mapping_seconds, Some(0.05));
        assert_eq!(clock.seconds_per_idle_step, None, "no idle tick yet");
        clock.observe(TickKind::Frame, 10, 0.2, 0.5);
        let step = clock.seconds_per_frame_step.expect("measured");
        assert!((step - 0.012).abs() < 1e-12, "{step}");
        clock.observe(TickKind::Idle, 10, 0.05, 3.0);
        assert_eq!(clock.seconds_per_idle_step, Some(0.005));
        let mapping = clock.mapping_seconds.expect("measured");
        assert!((mapping - 0.14).abs() < 1e-12, "an idle tick maps nothing: {mapping}");
        clock.observe(TickKind::Frame, 0, 0.0, 0.1);
        assert_eq!(clock.seconds_per_frame_step, Some(step), "no step, no step time");
    }
}
