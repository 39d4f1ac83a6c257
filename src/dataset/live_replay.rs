//! Live replay: a dataset streamed at a sensor's rate. A camera does not wait for the mapper:
//! the reader releases frame k at k / fps seconds after the start and never blocks on the
//! mapper. The channel holds one message; a frame that arrives while the previous one is still
//! waiting replaces it, and the replaced frame is counted as dropped
//! ([`StreamStats::frames_dropped`]). So the mapper always takes the newest frame. A skip
//! notice replaced the same way is not counted. The end of the stream is never dropped: the
//! reader waits until the mapper can take it.
//!
//! Without live replay, [`FrameStream::spawn`] streams every frame and holds the reader back
//! while the mapper is busy (deterministic replay).

use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender, TrySendError, bounded};

use super::FrameSource;
use super::stream::{FrameStream, StreamMessage, StreamStats, decode_message};

/// When frame `k` of a replay at `fps` frames per second is due, from the replay's start.
pub fn release_time(k: usize, fps: f64) -> Duration {
    if fps > 0.0 && fps.is_finite() {
        Duration::from_secs_f64(k as f64 / fps)
    } else {
        Duration::ZERO
    }
}

/// Seconds between two reports of a live stream.
pub const REPORT_EVERY_SECONDS: f64 = 1.0;

/// What a live stream did over the last report's window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LiveReport {
    /// Frames the mapper has taken so far.
    pub frames_taken: u64,
    /// Frames the reader has dropped so far.
    pub frames_dropped: u64,
    /// Frames taken per second over the window.
    pub frames_per_second: f64,
    /// Share of the window's frames that were dropped (0 when none arrived).
    pub drop_share: f64,
}

/// The window of the next report: when it started and the counts then.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReportWindow {
    started_s: f64,
    taken: u64,
    dropped: u64,
}

impl ReportWindow {
    /// The report due at `now_s` (seconds on the caller's clock), given the counts so far:
    /// once [`REPORT_EVERY_SECONDS`] have passed since the window started, which then starts
    /// anew; `None` before.
    pub fn report(&mut self, now_s: f64, taken: u64, dropped: u64) -> Option<LiveReport> {
        let seconds = now_s - self.started_s;
        if seconds < REPORT_EVERY_SECONDS {
            return None;
        }
        let (new_taken, new_dropped) = (taken - self.taken.min(taken), dropped - self.dropped.min(dropped));
        let arrived = new_taken + new_dropped;
        *self = Self {
            started_s: now_s,
            taken,
            dropped,
        };
        Some(LiveReport {
            frames_taken: taken,
            frames_dropped: dropped,
            frames_per_second: new_taken as f64 / seconds,
            drop_share: if arrived == 0 {
                0.0
            } else {
                new_dropped as f64 / arrived as f64
            },
        })
    }
}

impl FrameStream {
    /// Starts a thread that replays `positions` of `source` at `fps` frames per second,
    /// replacing a frame the receiver has not taken yet by the newer one (see the module doc).
    /// The thread stops early when the receiver is dropped.
    pub fn spawn_live(source: Arc<dyn FrameSource>, positions: Vec<usize>, fps: f64) -> Self {
        let (sender, receiver) = bounded(1);
        let waiting = receiver.clone();
        let dropped = Arc::new(AtomicU64::new(0));
        let counter = Arc::clone(&dropped);
        let handle = std::thread::Builder::new()
            .name("catmap-live-reader".to_owned())
            .spawn(move || replay_into(source.as_ref(), &positions, fps, (&sender, &waiting), &counter))
            .expect("the OS can start one thread");
        Self::from_parts(receiver, dropped, handle)
    }
}

/// Replays `positions` of `source` at `fps` into `sender`, taking a message the receiver has
/// not taken yet off `waiting` (the channel's own receiving end) to make room and counting the
/// frames so dropped in `dropped`; ends with `End`.
fn replay_into(
    source: &dyn FrameSource,
    positions: &[usize],
    fps: f64,
    (sender, waiting): (&Sender<StreamMessage>, &Receiver<StreamMessage>),
    dropped: &AtomicU64,
) {
    let mut stats = StreamStats::default();
    let start = Instant::now();
    for (k, &position) in positions.iter().enumerate() {
        let mut message = decode_message(source, position, &mut stats);
        if let Some(early) = release_time(k, fps).checked_sub(start.elapsed()) {
            std::thread::sleep(early);
        }
        loop {
            match sender.try_send(message) {
                Ok(()) => break,
                Err(TrySendError::Disconnected(_)) => return,
                Err(TrySendError::Full(back)) => {
                    message = back;
                    if let Ok(StreamMessage::Frame(_)) = waiting.try_recv() {
                        stats.frames_dropped += 1;
                        stats.frames_sent -= 1;
                        dropped.fetch_add(1, Ordering::Relaxed);
                    }
                }
            }
        }
    }
    let _ = sender.send(StreamMessage::End(stats));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::stream::tests::Fake;

    #[test]
    fn a_report_comes_once_a_second_with_the_window_s_rate_and_drop_share() {
        let mut window = ReportWindow::default();
        assert_eq!(window.report(0.5, 3, 9), None, "not a second yet");
        let first = window.report(1.0, 4, 12).expect("a second passed");
        assert_eq!((first.frames_taken, first.frames_dropped), (4, 12));
        assert!((first.frames_per_second - 4.0).abs() < 1e-12);
        assert!((first.drop_share - 0.75).abs() < 1e-12);
        assert_eq!(window.report(1.9, 5, 12), None, "the window started anew");
        let second = window.report(3.0, 6, 12).expect("two seconds later");
        assert!((second.frames_per_second - 1.0).abs() < 1e-12, "2 frames in 2 s");
        assert_eq!(second.drop_share, 0.0);
    }

    #[test]
    fn frames_are_due_at_the_rate_from_the_start() {
        assert_eq!(release_time(0, 30.0), Duration::ZERO);
        assert_eq!(release_time(30, 30.0), Duration::from_secs(1));
        assert_eq!(release_time(5, 10.0), Duration::from_millis(500));
        assert_eq!(
            release_time(7, 0.0),
            Duration::ZERO,
            "no rate: as fast as decoding goes"
        );
    }

    #[test]
    fn a_slow_receiver_gets_newer_frames_in_order_and_the_drops_are_counted() {
        // 60 frames at 2 000 fps (30 ms), a receiver taking one every 10 ms: it sees a few,
        // in increasing order, the last one among them; the others are counted as dropped.
        let stream = FrameStream::spawn_live(Arc::new(Fake(60)), (0..60).collect(), 2000.0);
        let mut taken = Vec::new();
        let stats = loop {
            match stream.receiver.recv().expect("the stream ends with its end") {
                StreamMessage::Frame(f) => taken.push(f.index.0),
                StreamMessage::Skipped { .. } => {}
                StreamMessage::End(stats) => break stats,
            }
            std::thread::sleep(Duration::from_millis(10));
        };
        let counted = stream.dropped.load(Ordering::Relaxed);
        stream.join();
        assert!(taken.windows(2).all(|w| w[0] < w[1]), "in stream order: {taken:?}");
        assert!(taken.len() < 59, "a slow receiver takes few: {taken:?}");
        assert_eq!(taken.last(), Some(&59), "the newest frame is taken: {taken:?}");
        assert_eq!(stats.frames_sent, taken.len() as u64, "sent counts the frames taken");
        assert_eq!(
            stats.frames_sent + stats.frames_dropped + stats.frames_skipped,
            60,
            "every frame is taken, dropped or skipped: {stats:?}"
        );
        assert!(stats.frames_dropped > 0);
        assert_eq!(counted, stats.frames_dropped, "counted as they go");
    }
}
