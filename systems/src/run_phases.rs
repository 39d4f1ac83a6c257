//! The phases of `catmap run` — stream, training after the stream, category fields, outputs —
//! with a checkpoint every few frames or steps and on Ctrl-C, and `--resume` from the latest one.

use std::ops::ControlFlow;
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::Context as _;
use catmap::CatmapError;
use catmap::config::{CheckpointConfig, FirstPhase};
use catmap::dataset::FrameSource;
use catmap::dataset::stream::{FrameStream, stream_positions};
use catmap_systems::Mapper;

use crate::progress::bar;
use crate::run_plan::RunPlan;

/// Exit code of a run stopped by Ctrl-C after saving its checkpoint (128 + SIGINT).
const INTERRUPTED_EXIT: i32 = 130;

/// Continues the run whose output folder is `out` from its checkpoint.
pub fn resume(out: &Path) -> anyhow::Result<()> {
    let started = Instant::now();
    let dir = out.join("checkpoint");
    let (mapper, extra) = Mapper::resume(&dir, None)
        .with_context(|| format!("cannot resume from {} (no usable checkpoint)", dir.display()))?;
    let plan: RunPlan =
        serde_json::from_str(&extra).with_context(|| format!("{}: the run plan is unreadable", dir.display()))?;
    let manifest = catmap::checkpoint::read_manifest(&dir)?;
    tracing::info!(checkpoint = %dir.display(), at = %manifest.label, "resuming");
    let source = plan.open_source(mapper.config())?;
    drive(mapper, plan, source, started)
}

/// Runs every remaining phase of `mapper` (fresh or resumed) and writes the outputs.
pub fn drive(mut mapper: Mapper, plan: RunPlan, source: Arc<dyn FrameSource>, started: Instant) -> anyhow::Result<()> {
    let config = mapper.config().clone();
    let positions = stream_positions(source.len(), config.stream.stride, config.stream.max_frames);
    anyhow::ensure!(!positions.is_empty(), "{} has no frames to map", source.name());
    let mut checkpoints = Checkpoints::new(&plan, config.checkpoint.clone(), started);
    if let Some(recording) = plan.open_recording(positions.len(), &config.rerun)? {
        mapper.set_recording(recording);
    }

    let consumed = mapper.positions_consumed().min(positions.len());
    let stream = (!mapper.stream_ended()).then(|| {
        tracing::info!(dataset = %source.name(), frames = positions.len(), from = consumed, "mapping");
        let stream = FrameStream::spawn(
            Arc::clone(&source),
            positions[consumed..].to_vec(),
            config.stream.channel_capacity,
        );
        mapper.attach_inbox(stream.receiver.clone());
        stream
    });
    let progress = bar(positions.len() as u64, "mapping");
    progress.set_position(consumed as u64);
    let every_frames = checkpoints.every_frames();
    while !mapper.run_until(|frames| {
        progress.set_position(frames);
        checkpoints.break_if(frames.is_multiple_of(every_frames))
    }) {
        let label = format!("frame {} of {}", mapper.positions_consumed(), positions.len());
        checkpoints.save(&mut mapper, &label)?;
    }
    progress.finish_and_clear();
    if let Some(stream) = stream {
        stream.join();
    }

    let phases = config.after_stream();
    let every_steps = checkpoints.every_steps();
    if phases.first_cap > 0 {
        let what = match (config.fields.offline, phases.first) {
            (true, _) => "training",
            (false, FirstPhase::ObjectFields) => "refining",
            (false, FirstPhase::ObjectAndCategoryFields) => "refining (objects and categories)",
        };
        let progress = bar(phases.first_cap, what);
        while !mapper.train_after_stream_until(|done, _| {
            progress.set_position(done);
            checkpoints.break_if(done.is_multiple_of(every_steps))
        }) {
            let label = format!("{what}, {} steps", mapper.training_steps());
            checkpoints.save(&mut mapper, &label)?;
        }
        progress.finish_and_clear();
    }
    if let Some(cap) = phases.category_cap {
        let progress = bar(cap, "category fields");
        while !mapper.train_categories_until(|done, _| {
            progress.set_position(done);
            checkpoints.break_if(done.is_multiple_of(every_steps))
        }) {
            checkpoints.save(&mut mapper, "category fields")?;
        }
        progress.finish_and_clear();
    }
    if config.category_fields.enabled {
        tracing::info!(
            category_fields = mapper.category_field_count(),
            "category fields trained"
        );
    }
    crate::run_outputs::write_outputs(mapper, &plan, source.name(), started)?;
    checkpoints.remove_after_success();
    Ok(())
}

/// When and where checkpoints are written, and whether Ctrl-C was pressed.
struct Checkpoints {
    plan: RunPlan,
    cfg: CheckpointConfig,
    started: Instant,
    interrupted: Arc<AtomicBool>,
}

impl Checkpoints {
    fn new(plan: &RunPlan, cfg: CheckpointConfig, started: Instant) -> Self {
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
            interrupted,
        }
    }

    /// Frames between checkpoints (`u64::MAX` when disabled).
    fn every_frames(&self) -> u64 {
        if self.cfg.enabled && self.cfg.every_frames > 0 {
            self.cfg.every_frames
        } else {
            u64::MAX
        }
    }

    /// Steps between checkpoints, rounded up to whole chunks (`u64::MAX` when disabled).
    fn every_steps(&self) -> u64 {
        let chunk = catmap_systems::mapper::CHUNK_STEPS;
        if self.cfg.enabled && self.cfg.every_steps > 0 {
            self.cfg.every_steps.div_ceil(chunk) * chunk
        } else {
            u64::MAX
        }
    }

    /// Break when a checkpoint is due or Ctrl-C was pressed.
    fn break_if(&self, due: bool) -> ControlFlow<()> {
        if due || self.interrupted.load(Ordering::SeqCst) {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    }

    /// Writes a checkpoint (when enabled); after Ctrl-C, exits.
    fn save(&mut self, mapper: &mut Mapper, label: &str) -> anyhow::Result<()> {
        let interrupted = self.interrupted.load(Ordering::SeqCst);
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
