//! The phases of `catmap run` — stream, training after the stream, category fields, outputs —
//! with a checkpoint every few frames, steps or seconds and on Ctrl-C, and `--resume` from the
//! latest one.

use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::Context as _;
use catmap::CatmapError;
use catmap::checkpoint::RunCount;
use catmap::config::{CheckpointConfig, FirstPhase};
use catmap::dataset::FrameSource;
use catmap::dataset::stream::{FrameStream, stream_positions};
use catmap_systems::{Mapper, RunOutcome, RunPhase, RunProgress, SavedMapper};

use crate::cli::progress::bar;
use crate::cli::run_plan::RunPlan;

/// Exit code of a run stopped by Ctrl-C after saving its checkpoint (128 + SIGINT).
const INTERRUPTED_EXIT: i32 = 130;

/// How a run starts: fresh from a configuration, or from a checkpoint.
pub enum Start {
    /// A new run.
    Fresh(Box<catmap::MapperConfig>),
    /// A run continued from its checkpoint.
    Resumed(Box<SavedMapper>),
}

/// Continues the run whose output folder is `out` from its checkpoint.
pub fn resume(out: &Path) -> anyhow::Result<()> {
    let started = Instant::now();
    let dir = out.join("checkpoint");
    let saved = SavedMapper::load(&dir)
        .with_context(|| format!("cannot resume from {} (no usable checkpoint)", dir.display()))?;
    let plan: RunPlan = serde_json::from_str(saved.extra())
        .with_context(|| format!("{}: the run plan is unreadable", dir.display()))?;
    anyhow::ensure!(
        !saved.config().stream.live.enabled,
        "{}: a live run cannot be resumed (the clock chose its frames); start it again",
        dir.display()
    );
    tracing::info!(checkpoint = %dir.display(), at = saved.label(), "resuming");
    let source = plan.open_source(saved.config())?;
    drive(Start::Resumed(Box::new(saved)), plan, source, started)
}

/// Builds the mapper (fresh or resumed) fed by a reader thread from where its stream stopped,
/// runs every remaining phase with checkpoints between steps, and writes the outputs.
pub fn drive(start: Start, plan: RunPlan, source: Arc<dyn FrameSource>, started: Instant) -> anyhow::Result<()> {
    let config = match &start {
        Start::Fresh(config) => (**config).clone(),
        Start::Resumed(saved) => saved.config().clone(),
    };
    config.validate()?;
    let positions = stream_positions(source.len(), config.stream.stride, config.stream.max_frames);
    anyhow::ensure!(!positions.is_empty(), "{} has no frames to map", source.name());
    let (consumed, ended) = match &start {
        Start::Fresh(_) => (0, false),
        Start::Resumed(saved) => (saved.positions_consumed().min(positions.len()), saved.stream_ended()),
    };
    let live = &config.stream.live;
    let stream = (!ended).then(|| {
        let rest = positions[consumed..].to_vec();
        if live.enabled {
            let fps = live.fps();
            tracing::info!(dataset = %source.name(), frames = positions.len(), fps, "mapping live");
            FrameStream::spawn_live(Arc::clone(&source), rest, fps)
        } else {
            tracing::info!(dataset = %source.name(), frames = positions.len(), from = consumed, "mapping");
            FrameStream::spawn(Arc::clone(&source), rest, config.stream.channel_capacity)
        }
    });
    let inbox = stream
        .as_ref()
        .map_or_else(crossbeam_channel::never, |s| s.receiver.clone());
    let mut mapper = match start {
        Start::Fresh(config) => Mapper::with_inbox(*config, inbox)?,
        Start::Resumed(saved) => Mapper::from_checkpoint(*saved, inbox)?,
    };
    mapper.set_class_names(source.class_names());
    let dropped = stream.as_ref().map(|s| Arc::clone(&s.dropped));
    if let Some(dropped) = &dropped {
        mapper.count_drops_from(Arc::clone(dropped));
    }
    let mut checkpoints = Checkpoints::new(&plan, config.checkpoint.clone(), started, live.enabled);
    if let Some(recording) = plan.open_recording(positions.len(), &config.rerun)? {
        if let Some(choice) = &plan.sensor {
            catmap_systems::stages::log_rerun::log_sensor(&recording, &choice.markdown());
        }
        mapper.set_recording(recording);
    }
    let mut bars = PhaseBars::new(&config, positions.len() as u64, dropped);
    let mut last_stream_tick = Instant::now();
    while let RunOutcome::Paused(at) = mapper
        .run(|progress| {
            if progress.phase == RunPhase::Stream {
                last_stream_tick = Instant::now();
            }
            bars.show(progress);
            checkpoints.break_if(progress)
        })
        .with_context(|| checkpoints.after_failure())?
    {
        let label = match at.phase {
            RunPhase::Stream => format!("frame {} of {}", mapper.positions_consumed(), positions.len()),
            RunPhase::AfterStream => format!("{}, {} steps", bars.after_stream, mapper.training_steps()),
            _ => "category fields".to_owned(),
        };
        checkpoints.save(&mut mapper, &label)?;
    }
    bars.finish();
    let after_stream = last_stream_tick.elapsed().as_secs_f64();
    let live = live.enabled.then(|| catmap_systems::summary::LiveSummary {
        fps: live.fps(),
        frames_taken: mapper.stream_stats().map_or(0, |s| s.frames_sent),
        frames_dropped: mapper.stream_stats().map_or(0, |s| s.frames_dropped),
        seconds_after_stream: after_stream,
    });
    if let Some(live) = &live {
        tracing::info!(
            "live at {} frames/s: {} frames taken, {} dropped; final meshes {:.1} s after the stream's end",
            live.fps,
            live.frames_taken,
            live.frames_dropped,
            live.seconds_after_stream
        );
    }
    if let Some(stream) = stream {
        stream.join();
    }
    if config.category_fields.enabled {
        tracing::info!(
            category_fields = mapper.category_field_count(),
            "category fields trained"
        );
    }
    crate::cli::run_outputs::write_outputs(mapper, &plan, source.name(), started, live)?;
    checkpoints.remove_after_success();
    Ok(())
}

/// One progress bar per phase of the run, and one log line when a phase ends (what it did, how
/// long it took, at what rate) — the line stays in a log file, where bars are not drawn.
struct PhaseBars {
    /// The phase running and its bar.
    current: Option<PhaseBar>,
    /// Stream positions.
    frames: u64,
    /// What the phase after the stream is called.
    after_stream: &'static str,
    /// A live replay's dropped frames so far (the stream's bar counts frames taken or dropped).
    dropped: Option<Arc<std::sync::atomic::AtomicU64>>,
}

/// The bar of the phase running.
struct PhaseBar {
    phase: RunPhase,
    bar: indicatif::ProgressBar,
    /// When the bar started, and where the phase stood then (a resumed phase continues).
    started: Instant,
    from: u64,
    /// Frames or steps done.
    done: u64,
}

impl PhaseBars {
    fn new(config: &catmap::MapperConfig, frames: u64, dropped: Option<Arc<std::sync::atomic::AtomicU64>>) -> Self {
        let after_stream = match (config.fields.offline, config.after_stream().first) {
            (true, _) => "training",
            (false, FirstPhase::ObjectFields) => "refining",
            (false, FirstPhase::ObjectAndCategoryFields) => "refining (objects and categories)",
        };
        Self {
            current: None,
            frames,
            after_stream,
            dropped: dropped.filter(|_| config.stream.live.enabled),
        }
    }

    /// Frames the live replay dropped so far (0 when not live).
    fn dropped(&self) -> u64 {
        self.dropped
            .as_ref()
            .map_or(0, |d| d.load(std::sync::atomic::Ordering::Relaxed))
    }

    /// Shows `progress`, starting its phase's bar when the phase changed.
    fn show(&mut self, progress: RunProgress) {
        if self
            .current
            .as_ref()
            .is_none_or(|current| current.phase != progress.phase)
        {
            self.finish();
            let cap = match progress.phase {
                RunPhase::Stream => self.frames,
                _ => progress.cap.unwrap_or(0),
            };
            let what = self.name(progress.phase);
            self.current = Some(PhaseBar {
                phase: progress.phase,
                bar: bar(cap, what),
                started: Instant::now(),
                from: progress.done,
                done: progress.done,
            });
        }
        let dropped = if progress.phase == RunPhase::Stream {
            self.dropped()
        } else {
            0
        };
        if let Some(current) = &mut self.current {
            current.bar.set_position(progress.done + dropped);
            current.done = progress.done;
        }
    }

    /// What a phase is called on its bar and its line.
    fn name(&self, phase: RunPhase) -> &'static str {
        match phase {
            RunPhase::Stream => "mapping",
            RunPhase::AfterStream => self.after_stream,
            _ => "category fields",
        }
    }

    /// Clears the bar shown and logs what its phase did (the rate counts what ran since the phase
    /// started here).
    fn finish(&mut self) {
        if let Some(PhaseBar {
            phase,
            bar,
            started,
            from,
            done,
        }) = self.current.take()
        {
            bar.finish_and_clear();
            let seconds = started.elapsed().as_secs_f64();
            let rate = done.saturating_sub(from) as f64 / seconds.max(1e-9);
            let what = self.name(phase);
            match (phase, &self.dropped) {
                (RunPhase::Stream, None) => {
                    tracing::info!("{what}: {done} frames in {seconds:.1} s ({rate:.1} frames/s)")
                }
                (RunPhase::Stream, Some(_)) => {
                    let dropped = self.dropped();
                    let share = 100.0 * dropped as f64 / (done + dropped).max(1) as f64;
                    tracing::info!(
                        "{what}: {done} frames taken in {seconds:.1} s ({rate:.1} frames/s), {dropped} dropped ({share:.0} %)"
                    );
                }
                _ => tracing::info!("{what}: {done} steps in {seconds:.1} s ({rate:.1} steps/s)"),
            }
        }
    }
}

/// When and where checkpoints are written, and whether Ctrl-C was pressed.
struct Checkpoints {
    plan: RunPlan,
    cfg: CheckpointConfig,
    started: Instant,
    /// When the last checkpoint was written (or the run or its resume started).
    last: Instant,
    interrupted: Arc<AtomicBool>,
    /// Whether the run is live (no checkpoint: a live run cannot be resumed).
    live: bool,
}

impl Checkpoints {
    fn new(plan: &RunPlan, cfg: CheckpointConfig, started: Instant, live: bool) -> Self {
        let interrupted = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&interrupted);
        // A first Ctrl-C asks for a checkpoint at the next step; a second one quits at once.
        let installed = ctrlc::set_handler(move || {
            if flag.swap(true, Ordering::SeqCst) {
                std::process::exit(INTERRUPTED_EXIT);
            }
        });
        if let Err(e) = installed {
            tracing::warn!(error = %e, "Ctrl-C will not save a checkpoint");
        }
        Self {
            plan: plan.clone(),
            cfg,
            started,
            last: Instant::now(),
            interrupted,
            live,
        }
    }

    /// Break when a checkpoint is due after `progress` (`CheckpointConfig::is_due`: by frames,
    /// steps or the clock) or Ctrl-C was pressed.
    fn break_if(&self, progress: RunProgress) -> ControlFlow<()> {
        let count = match progress.phase {
            RunPhase::Stream => RunCount::Frames(progress.done),
            _ => RunCount::Steps {
                done: progress.done,
                chunk: catmap_systems::mapper::CHUNK_STEPS,
            },
        };
        let due = !self.live && self.cfg.is_due(count, self.last.elapsed().as_secs_f64());
        if due || self.interrupted.load(Ordering::SeqCst) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    /// Writes a checkpoint (when enabled); after Ctrl-C, exits.
    fn save(&mut self, mapper: &mut Mapper, label: &str) -> anyhow::Result<()> {
        let interrupted = self.interrupted.load(Ordering::SeqCst);
        if self.live {
            tracing::warn!(at = label, "interrupted; a live run keeps no checkpoint");
            std::process::exit(INTERRUPTED_EXIT);
        }
        if self.cfg.enabled || interrupted {
            let dir = self.plan.checkpoint_dir();
            let plan = RunPlan {
                seconds_before: self.plan.seconds_before + self.started.elapsed().as_secs_f64(),
                ..self.plan.clone()
            };
            let extra = serde_json::to_string(&plan).context("cannot encode the run plan")?;
            let started = Instant::now();
            mapper
                .save_checkpoint(&dir, label, extra)
                .with_context(|| format!("cannot write a checkpoint to {}", dir.display()))?;
            tracing::debug!(
                at = label,
                seconds = started.elapsed().as_secs_f64(),
                "checkpoint written"
            );
            self.last = Instant::now();
        }
        if interrupted {
            tracing::warn!(
                at = label,
                "interrupted; continue with: catmap run --resume {}",
                self.plan.out.display()
            );
            std::process::exit(INTERRUPTED_EXIT);
        }
        Ok(())
    }

    /// What a run that stopped at a failed step leaves: the checkpoint written before it, or none.
    fn after_failure(&self) -> String {
        let dir = self.plan.checkpoint_dir();
        if dir.exists() {
            format!(
                "the run stopped; its last checkpoint, {}, is kept (catmap run --resume {})",
                dir.display(),
                self.plan.out.display()
            )
        } else {
            "the run stopped before its first checkpoint".to_owned()
        }
    }

    /// Deletes the checkpoint once the run has completed, unless `checkpoint.keep`.
    fn remove_after_success(&self) {
        let dir = self.plan.checkpoint_dir();
        if self.cfg.keep || !dir.exists() {
            return;
        }
        if let Err(e) = std::fs::remove_dir_all(&dir) {
            tracing::warn!(dir = %dir.display(), error = %CatmapError::io(&dir, e), "cannot remove the checkpoint");
        }
    }
}
