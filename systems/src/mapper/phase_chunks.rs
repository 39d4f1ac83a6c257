//! The chunk loop shared by the phases after the stream.

use std::ops::ControlFlow;

use catmap::training::PhaseEnd;

use super::{CHUNK_STEPS, Mapper};
use crate::resources::{AfterStreamPhase, PhaseProgress};

/// How one phase after the stream runs its chunks.
#[derive(Debug, Clone, Copy)]
pub(super) struct PhaseChunks {
    /// Which phase (where its progress is kept).
    pub phase: AfterStreamPhase,
    /// Most steps.
    pub cap: u64,
    /// Whether it also ends once its plan trains no field.
    pub ends_on_convergence: bool,
    /// Whether one chunk runs even when the cap is 0.
    pub runs_once_at_least: bool,
}

impl Mapper {
    /// Runs a phase after the stream in chunks of [`CHUNK_STEPS`] until it ends (its cap, or no
    /// planned field when it ends on convergence) or `on_chunk` (done, cap) breaks; `run_chunk`
    /// trains `n` steps and returns how many fields its plan trained. Returns whether the phase
    /// is complete.
    pub(super) fn run_phase_chunks(
        &mut self,
        chunks: PhaseChunks,
        mut on_chunk: impl FnMut(u64, u64) -> ControlFlow<()>,
        mut run_chunk: impl FnMut(&mut Self, u64) -> usize,
    ) -> bool {
        let mut must_run = chunks.runs_once_at_least;
        loop {
            let (done, ended) = self.world.resource::<PhaseProgress>().of(chunks.phase);
            if ended.is_some() || (done >= chunks.cap && !must_run) {
                return true;
            }
            must_run = false;
            let n = CHUNK_STEPS.min(chunks.cap.saturating_sub(done));
            let planned = run_chunk(self, n);
            let planned = if chunks.ends_on_convergence {
                planned
            } else {
                usize::MAX
            };
            let end = PhaseEnd::of(done + n, chunks.cap, planned);
            self.world.resource_mut::<PhaseProgress>().advance(chunks.phase, n, end);
            if on_chunk(done + n, chunks.cap).is_break() {
                return end.is_some();
            }
        }
    }
}
