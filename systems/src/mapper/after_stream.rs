//! The training phases after the stream: the per-object (and, online under the fast schedule,
//! category) fields' phase, then the category phase, each in chunks of [`super::CHUNK_STEPS`].

use std::ops::ControlFlow;

use catmap::config::FirstPhase;

use super::Mapper;
use super::phase_chunks::PhaseChunks;
use crate::resources::{AfterStreamPhase, CategoryFields, PhaseProgress, Settings, TrainingQueue, TrainingSchedule};

impl Mapper {
    /// The training due once the stream has ended (`MapperConfig::after_stream`: the offline
    /// training, the paper's refinement, or the fast schedule's one phase of every field), in
    /// chunks of 50; `on_progress` gets (done, cap).
    pub fn train_after_stream(&mut self, mut on_progress: impl FnMut(u64, u64)) {
        self.train_after_stream_until(|done, total| {
            on_progress(done, total);
            ControlFlow::Continue(())
        });
    }

    /// Like [`Mapper::train_after_stream`], continuing from the steps already done (after a
    /// resume) and stopping early when `on_chunk` breaks; returns whether the phase is complete.
    /// Under the fast schedule the phase also ends once no field gains from more steps.
    pub fn train_after_stream_until(&mut self, on_chunk: impl FnMut(u64, u64) -> ControlFlow<()>) -> bool {
        let phases = self.world.resource::<Settings>().0.after_stream();
        let first = phases.first;
        let chunks = PhaseChunks {
            phase: AfterStreamPhase::First,
            cap: phases.first_cap,
            ends_on_convergence: phases.ends_on_convergence,
            runs_once_at_least: false,
        };
        self.run_phase_chunks(chunks, on_chunk, |mapper, n| {
            mapper.world.resource_mut::<TrainingQueue>().pending += n;
            match first {
                FirstPhase::ObjectFields => {
                    mapper.training.run(&mut mapper.world);
                    mapper.world.resource::<TrainingSchedule>().planned_objects
                }
                FirstPhase::ObjectAndCategoryFields => {
                    mapper.world.resource_mut::<CategoryFields>().pending += n;
                    mapper.after_stream.run(&mut mapper.world);
                    let schedule = mapper.world.resource::<TrainingSchedule>();
                    schedule.planned_objects + schedule.planned_categories
                }
            }
        })
    }

    /// Runs `iterations` training steps on the keyframes gathered so far (the offline protocol,
    /// or extra refinement), in chunks of `chunk` steps; `on_progress` gets the steps done.
    pub fn train(&mut self, iterations: u64, chunk: u64, mut on_progress: impl FnMut(u64)) {
        let mut done = 0;
        while done < iterations {
            let n = chunk.max(1).min(iterations - done);
            self.world.resource_mut::<TrainingQueue>().pending += n;
            self.training.run(&mut self.world);
            done += n;
            on_progress(done);
        }
    }

    /// The category phase (`category_fields.enabled`): creates the category fields from the
    /// registered subcategories and runs `category_fields.iterations` steps in chunks of 50 (each
    /// also a step of the per-object fields, which serve the objects outside category fields);
    /// `on_progress` gets (done, total). Returns the number of category fields.
    pub fn train_categories(&mut self, mut on_progress: impl FnMut(u64, u64)) -> usize {
        self.train_categories_until(|done, total| {
            on_progress(done, total);
            ControlFlow::Continue(())
        });
        self.category_field_count()
    }

    /// Like [`Mapper::train_categories`], continuing from the steps already done (after a
    /// resume) and stopping early when `on_chunk` breaks; returns whether the phase is complete.
    /// Under the fast schedule the phase also ends once no field gains from more steps; online,
    /// the fast schedule has no category phase (the category fields trained in the phase before).
    pub fn train_categories_until(&mut self, on_chunk: impl FnMut(u64, u64) -> ControlFlow<()>) -> bool {
        let phases = self.world.resource::<Settings>().0.after_stream();
        let Some(cap) = phases.category_cap else {
            return true;
        };
        let started = self.category_phase_started || self.world.resource::<PhaseProgress>().category_steps > 0;
        let chunks = PhaseChunks {
            phase: AfterStreamPhase::Category,
            cap,
            ends_on_convergence: phases.ends_on_convergence,
            // The first chunk runs even for zero iterations: it creates the category fields.
            runs_once_at_least: !started,
        };
        self.run_phase_chunks(chunks, on_chunk, |mapper, n| {
            mapper.category_phase_started = true;
            mapper.world.resource_mut::<CategoryFields>().pending += n;
            mapper.world.resource_mut::<TrainingQueue>().pending += n;
            mapper.category_training.run(&mut mapper.world);
            let schedule = mapper.world.resource::<TrainingSchedule>();
            schedule.planned_objects + schedule.planned_categories
        })
    }
}
