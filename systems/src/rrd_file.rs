//! Saving a recording to an .rrd file, with or without Rerun's chunk index.
//!
//! Rerun's file sink ends a file with a footer that indexes every chunk (for random access) and
//! builds that index in memory until the file is closed: a few KiB per chunk, ≈ 15 MiB per 1 000
//! frames of this mapper's logging, so a long stream would grow the process without bound
//! (rerun-io/rerun#12623, measured with `examples/bench_long_stream.rs`). Streams longer than
//! `rerun.rrd_footer_max_frames` are therefore saved without it; `rerun rrd optimize` adds it
//! afterwards.

use std::path::Path;

use catmap::config::RerunConfig;

/// Whether a saved recording ends with Rerun's chunk index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RrdFooter {
    /// Index every chunk; the index grows in memory with the recording.
    Indexed,
    /// No index: memory stays flat however long the stream runs.
    Omitted,
}

impl RrdFooter {
    /// The footer of a recording of a stream of `frames` frames (`None`: unknown length).
    pub fn for_stream(frames: Option<u64>, config: &RerunConfig) -> Self {
        match frames {
            Some(n) if n <= config.rrd_footer_max_frames => Self::Indexed,
            _ => Self::Omitted,
        }
    }
}

/// A recording stream that saves to `path`, ending the file with `footer`.
pub fn save_rrd(
    builder: rerun::RecordingStreamBuilder,
    path: &Path,
    footer: RrdFooter,
) -> rerun::RecordingStreamResult<rerun::RecordingStream> {
    let options = rerun::sink::FileSinkOptions {
        write_footer: footer == RrdFooter::Indexed,
    };
    let sink = rerun::sink::FileSink::with_options(path, options)?;
    builder.set_sinks((sink,))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_streams_of_known_bounded_length_keep_the_chunk_index() {
        let config = RerunConfig {
            rrd_footer_max_frames: 2_000,
            ..RerunConfig::default()
        };
        assert_eq!(RrdFooter::for_stream(Some(240), &config), RrdFooter::Indexed);
        assert_eq!(RrdFooter::for_stream(Some(2_000), &config), RrdFooter::Indexed);
        assert_eq!(
            RrdFooter::for_stream(Some(10_000), &config),
            RrdFooter::Omitted,
            "a long stream must not grow an index in memory"
        );
        assert_eq!(
            RrdFooter::for_stream(None, &config),
            RrdFooter::Omitted,
            "an endless stream must not either"
        );
        let never = RerunConfig {
            rrd_footer_max_frames: 0,
            ..RerunConfig::default()
        };
        assert_eq!(RrdFooter::for_stream(Some(1), &never), RrdFooter::Omitted);
    }
}
