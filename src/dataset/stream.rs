//! The frame stream: a reader thread decodes frames from a [`FrameSource`] and sends them over a
//! bounded channel, so decoding overlaps mapping and the reader never runs more than
//! `capacity` frames ahead (the channel applies backpressure; nothing is dropped). A live replay
//! at a sensor's rate, which drops what the mapper cannot take, is [`super::live_replay`].

use std::sync::Arc;
use std::sync::atomic::AtomicU64;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, Sender, bounded};

use crate::dataset::FrameSource;
use crate::sensor::frame::SharedFrame;

/// One message of the stream, in order.
#[derive(Debug, Clone)]
pub enum StreamMessage {
    /// A decoded frame.
    Frame(SharedFrame),
    /// A frame that could not be decoded; the stream goes on without it.
    Skipped {
        /// Dataset position of the frame.
        position: usize,
        /// Why, naming the file.
        reason: String,
    },
    /// The end of the stream.
    End(StreamStats),
}

/// What the reader did, sent with [`StreamMessage::End`].
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StreamStats {
    /// Frames sent.
    pub frames_sent: u64,
    /// Frames skipped because they could not be decoded.
    pub frames_skipped: u64,
    /// Time spent decoding.
    pub decode_time: Duration,
    /// Time spent blocked on a full channel (the mapper was slower than the reader).
    pub blocked_time: Duration,
    /// Frames a live replay dropped unseen because a newer one arrived first
    /// ([`super::live_replay`]; 0 otherwise).
    #[serde(default)]
    pub frames_dropped: u64,
}

/// Which dataset positions to stream: every `stride`-th, at most `max_frames` of them.
pub fn stream_positions(len: usize, stride: usize, max_frames: Option<usize>) -> Vec<usize> {
    (0..len)
        .step_by(stride.max(1))
        .take(max_frames.unwrap_or(usize::MAX))
        .collect()
}

/// A running reader thread and the receiving end of its channel.
pub struct FrameStream {
    /// Messages in stream order; the last one is [`StreamMessage::End`].
    pub receiver: Receiver<StreamMessage>,
    /// Frames a live replay has dropped so far (always 0 otherwise; the end's
    /// [`StreamStats::frames_dropped`] holds the total).
    pub dropped: Arc<AtomicU64>,
    handle: Option<JoinHandle<()>>,
}

impl FrameStream {
    /// Starts a thread that decodes `positions` of `source` in order into a channel of
    /// `capacity` messages. The thread stops early when the receiver is dropped.
    pub fn spawn(source: Arc<dyn FrameSource>, positions: Vec<usize>, capacity: usize) -> Self {
        let (sender, receiver) = bounded(capacity.max(1));
        let handle = std::thread::Builder::new()
            .name("catmap-reader".to_owned())
            .spawn(move || read_into(source.as_ref(), &positions, &sender))
            .expect("the OS can start one thread");
        Self::from_parts(receiver, Arc::default(), handle)
    }

    /// Waits for the reader thread to finish (after the receiver has seen `End` or was dropped).
    pub fn join(mut self) {
        if let Some(handle) = self.handle.take() {
            let _ = handle.join();
        }
    }

    /// A stream of the reader thread `handle` sending into `receiver`'s channel.
    pub(crate) fn from_parts(
        receiver: Receiver<StreamMessage>,
        dropped: Arc<AtomicU64>,
        handle: JoinHandle<()>,
    ) -> Self {
        Self {
            receiver,
            dropped,
            handle: Some(handle),
        }
    }
}

/// Decodes the frame at `position` of `source` into its message (a frame, or a skip naming the
/// reason), counting it and the time it took in `stats`.
pub(crate) fn decode_message(source: &dyn FrameSource, position: usize, stats: &mut StreamStats) -> StreamMessage {
    let started = Instant::now();
    let message = match source.read_frame(position) {
        Ok(frame) => match frame.validate() {
            Ok(()) => {
                stats.frames_sent += 1;
                StreamMessage::Frame(Arc::new(frame))
            }
            Err(reason) => {
                stats.frames_skipped += 1;
                StreamMessage::Skipped { position, reason }
            }
        },
        Err(e) => {
            stats.frames_skipped += 1;
            StreamMessage::Skipped {
                position,
                reason: e.to_string(),
            }
        }
    };
    stats.decode_time += started.elapsed();
    message
}

/// Decodes `positions` of `source` in order and sends them; ends with `End`.
/// Returns early if the receiving side hung up.
pub fn read_into(source: &dyn FrameSource, positions: &[usize], sender: &Sender<StreamMessage>) {
    let mut stats = StreamStats::default();
    for &position in positions {
        let message = decode_message(source, position, &mut stats);
        let waiting = Instant::now();
        if sender.send(message).is_err() {
            return;
        }
        stats.blocked_time += waiting.elapsed();
    }
    let _ = sender.send(StreamMessage::End(stats));
}

#[cfg(test)]
pub(crate) mod tests {
    use nalgebra::Isometry3;

    use super::*;
    use crate::error::CatmapError;
    use crate::ids::{ClassId, FrameIndex};
    use crate::sensor::frame::{CameraIntrinsics, InstanceMask, RgbdFrame};

    /// Tiny frames; position 2 fails to decode.
    pub(crate) struct Fake(pub usize);

    impl FrameSource for Fake {
        fn len(&self) -> usize {
            self.0
        }
        fn intrinsics(&self) -> CameraIntrinsics {
            CameraIntrinsics {
                width: 2,
                height: 2,
                fx: 1.0,
                fy: 1.0,
                cx: 0.5,
                cy: 0.5,
            }
        }
        fn read_frame(&self, position: usize) -> crate::Result<RgbdFrame> {
            if position == 2 {
                return Err(CatmapError::layout("depth/depth_2.png", "corrupt"));
            }
            Ok(RgbdFrame {
                index: FrameIndex(position as u64),
                world_from_camera: Isometry3::identity(),
                intrinsics: self.intrinsics(),
                rgb: vec![[0; 3]; 4],
                depth_m: vec![1.0; 4],
                instances: InstanceMask::background(4),
                classes: vec![ClassId(0); 4],
            })
        }
        fn name(&self) -> String {
            "fake".to_owned()
        }
    }

    #[test]
    fn a_bad_frame_is_skipped_and_the_stream_ends_with_statistics() {
        let stream = FrameStream::spawn(Arc::new(Fake(4)), vec![0, 1, 2, 3], 1);
        let messages: Vec<StreamMessage> = stream.receiver.iter().collect();
        stream.join();
        assert_eq!(messages.len(), 5, "four frames and the end");
        assert!(
            matches!(&messages[2], StreamMessage::Skipped { position: 2, reason } if reason.contains("depth_2.png"))
        );
        let StreamMessage::End(stats) = &messages[4] else {
            panic!("the last message ends the stream")
        };
        assert_eq!((stats.frames_sent, stats.frames_skipped), (3, 1));
    }

    #[test]
    fn the_reader_never_runs_more_than_the_channel_capacity_ahead() {
        let stream = FrameStream::spawn(Arc::new(Fake(50)), (0..50).collect(), 3);
        let waited = Instant::now();
        while stream.receiver.len() < 3 && waited.elapsed() < Duration::from_secs(5) {
            std::thread::sleep(Duration::from_millis(5));
        }
        std::thread::sleep(Duration::from_millis(50));
        assert_eq!(stream.receiver.len(), 3, "the bounded channel holds the reader back");
        assert_eq!(
            stream.receiver.iter().count(),
            51,
            "49 frames, one skip and the end: nothing is dropped"
        );
        stream.join();
    }

    #[test]
    fn positions_honour_stride_and_limit() {
        assert_eq!(stream_positions(10, 3, None), [0, 3, 6, 9]);
        assert_eq!(stream_positions(10, 2, Some(2)), [0, 2]);
        assert!(stream_positions(0, 1, None).is_empty());
    }
}
