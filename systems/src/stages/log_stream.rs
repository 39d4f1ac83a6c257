//! Live stream report: once a second, the frames taken per second and the frames dropped, as a
//! log line and (recording) as scalars.

use std::sync::atomic::Ordering;

use bevy_ecs::prelude::*;

use crate::recording::{Rerun, warn_on_error};
use crate::rerun_paths as paths;
use crate::resources::StreamProgress;
use crate::run_state::LiveTicks;

/// Reports the live stream once a second (`catmap::dataset::live_replay::ReportWindow`).
pub fn log_live_stream(mut live: ResMut<LiveTicks>, progress: Res<StreamProgress>, rerun: Option<Res<Rerun>>) {
    let now = live.started.elapsed().as_secs_f64();
    let dropped = live.dropped.load(Ordering::Relaxed);
    let Some(report) = live.report.report(now, progress.frames_ingested, dropped) else {
        return;
    };
    tracing::info!(
        "live: {} frames taken, {:.1} frames/s; {} dropped ({:.0} % of the last second's)",
        report.frames_taken,
        report.frames_per_second,
        report.frames_dropped,
        100.0 * report.drop_share
    );
    if let Some(rerun) = rerun {
        if let Some(frame) = progress.last_frame {
            rerun.at_frame(frame.0);
        }
        let rate = rerun::Scalars::single(report.frames_per_second);
        warn_on_error(rerun.0.log(paths::STREAM_RATE, &rate), paths::STREAM_RATE);
        let dropped = rerun::Scalars::single(report.frames_dropped as f64);
        warn_on_error(rerun.0.log(paths::STREAM_DROPPED, &dropped), paths::STREAM_DROPPED);
    }
}
