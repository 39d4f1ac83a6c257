//! The training phases after the stream: the per-object (and, online under the fast schedule,
//! category) fields' phase, then the category phase, each in chunks of [`super::CHUNK_STEPS`].

use std::ops::ControlFlow;

use catmap::config::FirstPhase;

use super::Mapper;
use super::phase_chunks::PhaseChunks;
use super::run::{RunPhase, RunProgress};
use crate::resources::{AfterStreamPhase, CategoryFields, PhaseProgress, Settings, TrainingQueue, TrainingSchedule};

impl Mapper {
    /// The training due once the stream has ended (`MapperConfig::after_stream`), continuing
    /// from the steps already done and stopping early when `on_chunk` breaks; returns whether
    /// the phase is complete. Under the fast schedule the phase also ends once no field gains
    /// from more steps.
    pub(super) fn after_stream_until(&mut self, on_chunk: &mut impl FnMut(RunProgress) -> ControlFlow<()>) -> bool {
        let phases = self.world.resource::<Settings>().0.after_stream();
        let first = phases.first;
        let chunks = PhaseChunks {
            phase: AfterStreamPhase::First,
            cap: phases.first_cap,
            ends_on_convergence: phases.ends_on_convergence,
            runs_once_at_least: false,
        };
        let report = |done, cap| {
            on_chunk(RunProgress {
                phase: RunPhase::AfterStream,
                done,
                cap: Some(cap),
            })
        };
        self.run_phase_chunks(chunks, report, |mapper, n| {
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

    /// The category phase (`category_fields.enabled`): creates the category fields from the
    /// registered subcategories and runs `category_fields.iterations` steps (each also a step of
    /// the per-object fields, which serve the objects outside category fields), continuing from
    /// the steps already done and stopping early when `on_chunk` breaks; returns whether the
    /// phase is complete. Under the fast schedule the phase also ends once no field gains from
    /// more steps; online, the fast schedule has no category phase (the category fields trained
    /// in the phase before).
    pub(super) fn categories_until(&mut self, on_chunk: &mut impl FnMut(RunProgress) -> ControlFlow<()>) -> bool {
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
        let report = |done, cap| {
            on_chunk(RunProgress {
                phase: RunPhase::Categories,
                done,
                cap: Some(cap),
            })
        };
        self.run_phase_chunks(chunks, report, |mapper, n| {
            mapper.category_phase_started = true;
            mapper.world.resource_mut::<CategoryFields>().pending += n;
            mapper.world.resource_mut::<TrainingQueue>().pending += n;
            mapper.category_training.run(&mut mapper.world);
            let schedule = mapper.world.resource::<TrainingSchedule>();
            schedule.planned_objects + schedule.planned_categories
        })
    }
}
