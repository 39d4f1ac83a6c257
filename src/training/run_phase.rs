//! The phases of a run as data: which phase a tick belongs to, how many training steps it
//! queues, and which phase follows it. The mapper keeps the phase as ECS state and gates its
//! systems by it; these pure functions are the whole of the decisions.
//!
//! A run streams frames ([`RunPhase::Stream`]), trains what is due once the stream has ended
//! ([`RunPhase::AfterStream`]: the offline training, the paper's refinement, or the fast
//! schedule's phase of every field), creates the category fields from the registered
//! subcategories and trains them ([`RunPhase::CategorySetup`], [`RunPhase::Categories`]: the
//! paper's category phase), meshes every field ([`RunPhase::Meshing`]) and is done.

use crate::config::{AfterStream, FirstPhase};

use super::PhaseEnd;

/// Training steps per tick of the phases after the stream under step counts (progress and
/// checkpoints happen between ticks).
pub const CHUNK_STEPS: u64 = 50;

/// The phases of a run, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RunPhase {
    /// Frames stream in; every frame queues its training steps.
    Stream,
    /// The training due once the stream has ended ([`AfterStream`]'s first phase).
    AfterStream,
    /// One tick that creates the category fields from the registered subcategories, before
    /// the category phase trains them.
    CategorySetup,
    /// The category phase (`category_fields.enabled`, unless the fast schedule trained the
    /// category fields in the phase before).
    Categories,
    /// Every field is meshed at final resolution.
    Meshing,
    /// The map is complete.
    Done,
}

/// Steps one tick queues for the object batch and for the category fields.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TickSteps {
    /// Steps of the per-object fields.
    pub objects: u64,
    /// Steps of the category fields.
    pub categories: u64,
}

/// How a tick's steps are counted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TickBudget {
    /// Deterministic replay: `fields.steps_per_frame` per frame ingested while streaming,
    /// [`CHUNK_STEPS`] per tick after it.
    Steps {
        /// Frames ingested this tick.
        frames: u64,
        /// `fields.steps_per_frame`.
        steps_per_frame: u64,
    },
    /// Live: as many steps as fit in `steps` (from the clock, see
    /// [`super::live_budget::LiveClock::tick_steps`]), whether or not a frame came.
    Clock {
        /// Steps that fit in the tick's time.
        steps: u64,
    },
}

/// What the training of one run does after its stream, and how it trains while streaming.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PhasePlan {
    /// The phases after the stream (`MapperConfig::after_stream`).
    pub after_stream: AfterStream,
    /// Whether fields train while frames stream in (`fields.enabled` and not offline).
    pub trains_online: bool,
    /// Whether category fields exist (`category_fields.enabled`).
    pub categories: bool,
}

impl PhasePlan {
    /// The steps a tick of `phase` queues, `done` steps of that phase having run.
    pub fn tick_steps(&self, phase: RunPhase, done: u64, budget: TickBudget) -> TickSteps {
        let both = |n| TickSteps {
            objects: n,
            categories: n,
        };
        let after = |cap: u64| match budget {
            TickBudget::Steps { .. } => CHUNK_STEPS.min(cap.saturating_sub(done)),
            TickBudget::Clock { steps } => steps.min(cap.saturating_sub(done)),
        };
        match phase {
            RunPhase::Stream if self.trains_online => {
                let n = match budget {
                    TickBudget::Steps {
                        frames,
                        steps_per_frame,
                    } => frames * steps_per_frame,
                    TickBudget::Clock { steps } => steps,
                };
                TickSteps {
                    objects: n,
                    categories: if self.categories { n } else { 0 },
                }
            }
            RunPhase::AfterStream => {
                let n = after(self.after_stream.first_cap);
                match self.after_stream.first {
                    FirstPhase::ObjectFields => TickSteps {
                        objects: n,
                        categories: 0,
                    },
                    FirstPhase::ObjectAndCategoryFields => both(n),
                }
            }
            RunPhase::Categories => both(after(self.after_stream.category_cap.unwrap_or(0))),
            RunPhase::Stream | RunPhase::CategorySetup | RunPhase::Meshing | RunPhase::Done => TickSteps::default(),
        }
    }

    /// Whether the category fields follow the registrations in a tick of `phase`: while
    /// streaming when they train online, in the fast schedule's phase after the stream, and
    /// in the tick that creates them for the category phase.
    pub fn category_fields_follow(&self, phase: RunPhase) -> bool {
        match phase {
            RunPhase::Stream => self.categories && self.trains_online,
            RunPhase::AfterStream => self.after_stream.first == FirstPhase::ObjectAndCategoryFields,
            RunPhase::CategorySetup => true,
            RunPhase::Categories | RunPhase::Meshing | RunPhase::Done => false,
        }
    }

    /// The step cap of the phase after the stream that `phase` is (`None` for the others).
    pub fn cap(&self, phase: RunPhase) -> Option<u64> {
        match phase {
            RunPhase::AfterStream => Some(self.after_stream.first_cap),
            RunPhase::Categories => self.after_stream.category_cap,
            _ => None,
        }
    }

    /// Why a phase after the stream ends after a tick that brought it to `done` steps, the
    /// latest plans having trained `planned` (object fields, category fields) (`None`: it goes
    /// on). The fast schedule's phases also end on convergence (no field of the phase planned);
    /// a live run's end when its finishing time is spent.
    pub fn phase_end(
        &self,
        phase: RunPhase,
        done: u64,
        (objects, categories): (usize, usize),
        clock: FinishClock,
    ) -> Option<PhaseEnd> {
        let cap = self.cap(phase)?;
        let objects_alone = phase == RunPhase::AfterStream && self.after_stream.first == FirstPhase::ObjectFields;
        let planned = match (self.after_stream.ends_on_convergence, objects_alone) {
            (false, _) => usize::MAX,
            (true, true) => objects,
            (true, false) => objects + categories,
        };
        PhaseEnd::of(done, cap, planned).or((clock == FinishClock::Spent).then_some(PhaseEnd::FinishTime))
    }

    /// The phase after a tick of `phase`: `stream_ended` once the end of the stream was taken,
    /// `ended` once the phase after the stream that ran ended.
    pub fn after_tick(&self, phase: RunPhase, stream_ended: bool, ended: Option<PhaseEnd>) -> RunPhase {
        let after_first = if self.after_stream.category_cap.is_some() {
            RunPhase::CategorySetup
        } else {
            RunPhase::Meshing
        };
        match phase {
            RunPhase::Stream if stream_ended => RunPhase::AfterStream,
            RunPhase::AfterStream if ended.is_some() => after_first,
            RunPhase::CategorySetup => RunPhase::Categories,
            RunPhase::Categories if ended.is_some() => RunPhase::Meshing,
            RunPhase::Meshing | RunPhase::Done => RunPhase::Done,
            _ => phase,
        }
    }

    /// The phase a mapper restored from a checkpoint continues in: the stream until it ended,
    /// then the first phase after it and the category phase until each recorded its end
    /// (`category_steps` tells whether the category fields were created), then the meshing.
    pub fn resumed(
        &self,
        stream_ended: bool,
        after_stream_end: Option<PhaseEnd>,
        category: (u64, Option<PhaseEnd>),
    ) -> RunPhase {
        let (category_steps, category_end) = category;
        if !stream_ended {
            RunPhase::Stream
        } else if after_stream_end.is_none() {
            RunPhase::AfterStream
        } else if self.after_stream.category_cap.is_none() || category_end.is_some() {
            RunPhase::Meshing
        } else if category_steps == 0 {
            RunPhase::CategorySetup
        } else {
            RunPhase::Categories
        }
    }
}

/// Whether a live run's finishing time is spent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FinishClock {
    /// Not live: the phases end on their caps (and, fast, on convergence) alone.
    Unbounded,
    /// Live, with time left.
    Running,
    /// Live, and the finishing time after the stream is spent.
    Spent,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(first: FirstPhase, category_cap: Option<u64>, ends_on_convergence: bool) -> PhasePlan {
        PhasePlan {
            after_stream: AfterStream {
                first,
                first_cap: 120,
                category_cap,
                ends_on_convergence,
            },
            trains_online: true,
            categories: true,
        }
    }

    const FRAMES: TickBudget = TickBudget::Steps {
        frames: 2,
        steps_per_frame: 10,
    };

    #[test]
    fn streaming_queues_steps_per_frame_and_after_the_stream_chunks_up_to_the_cap() {
        let fast = plan(FirstPhase::ObjectAndCategoryFields, None, true);
        let both = |n| TickSteps {
            objects: n,
            categories: n,
        };
        assert_eq!(fast.tick_steps(RunPhase::Stream, 0, FRAMES), both(20));
        assert_eq!(fast.tick_steps(RunPhase::AfterStream, 0, FRAMES), both(50));
        assert_eq!(
            fast.tick_steps(RunPhase::AfterStream, 100, FRAMES),
            both(20),
            "the cap's rest"
        );
        assert_eq!(fast.tick_steps(RunPhase::AfterStream, 120, FRAMES), both(0));
        let paper = plan(FirstPhase::ObjectFields, Some(70), false);
        let objects = paper.tick_steps(RunPhase::AfterStream, 0, FRAMES);
        assert_eq!(
            (objects.objects, objects.categories),
            (50, 0),
            "paper: object fields alone"
        );
        assert_eq!(paper.tick_steps(RunPhase::CategorySetup, 0, FRAMES), both(0));
        assert_eq!(paper.tick_steps(RunPhase::Categories, 50, FRAMES), both(20));
        let offline = PhasePlan {
            trains_online: false,
            ..paper
        };
        assert_eq!(
            offline.tick_steps(RunPhase::Stream, 0, FRAMES),
            both(0),
            "offline: read first"
        );
    }

    #[test]
    fn a_live_tick_queues_what_its_clock_allows_within_the_cap() {
        let fast = plan(FirstPhase::ObjectAndCategoryFields, None, true);
        let clock = TickBudget::Clock { steps: 7 };
        assert_eq!(
            fast.tick_steps(RunPhase::Stream, 0, clock).objects,
            7,
            "with or without a frame"
        );
        assert_eq!(fast.tick_steps(RunPhase::AfterStream, 0, clock).objects, 7);
        assert_eq!(fast.tick_steps(RunPhase::AfterStream, 117, clock).objects, 3);
    }

    #[test]
    fn phases_follow_each_other_in_order_and_skip_the_category_phase_when_there_is_none() {
        let paper = plan(FirstPhase::ObjectFields, Some(70), false);
        let end = Some(PhaseEnd::StepCap);
        assert_eq!(paper.after_tick(RunPhase::Stream, false, None), RunPhase::Stream);
        assert_eq!(paper.after_tick(RunPhase::Stream, true, None), RunPhase::AfterStream);
        assert_eq!(
            paper.after_tick(RunPhase::AfterStream, true, None),
            RunPhase::AfterStream
        );
        assert_eq!(
            paper.after_tick(RunPhase::AfterStream, true, end),
            RunPhase::CategorySetup
        );
        assert_eq!(
            paper.after_tick(RunPhase::CategorySetup, true, None),
            RunPhase::Categories
        );
        assert_eq!(paper.after_tick(RunPhase::Categories, true, end), RunPhase::Meshing);
        assert_eq!(paper.after_tick(RunPhase::Meshing, true, None), RunPhase::Done);
        let fast = plan(FirstPhase::ObjectAndCategoryFields, None, true);
        assert_eq!(fast.after_tick(RunPhase::AfterStream, true, end), RunPhase::Meshing);
    }

    #[test]
    fn a_phase_ends_at_its_cap_on_convergence_when_fast_and_when_live_time_is_spent() {
        let fast = plan(FirstPhase::ObjectAndCategoryFields, None, true);
        let running = FinishClock::Running;
        assert_eq!(fast.phase_end(RunPhase::AfterStream, 50, (3, 0), running), None);
        assert_eq!(
            fast.phase_end(RunPhase::AfterStream, 50, (0, 2), running),
            None,
            "categories train"
        );
        assert_eq!(
            fast.phase_end(RunPhase::AfterStream, 50, (0, 0), running),
            Some(PhaseEnd::Converged)
        );
        let paper = plan(FirstPhase::ObjectFields, Some(70), false);
        assert_eq!(
            paper.phase_end(RunPhase::AfterStream, 50, (0, 0), running),
            None,
            "paper runs its steps"
        );
        assert_eq!(
            paper.phase_end(RunPhase::AfterStream, 120, (3, 0), running),
            Some(PhaseEnd::StepCap)
        );
        assert_eq!(
            paper.phase_end(RunPhase::Categories, 70, (3, 3), running),
            Some(PhaseEnd::StepCap)
        );
        assert_eq!(
            paper.phase_end(RunPhase::AfterStream, 50, (3, 0), FinishClock::Spent),
            Some(PhaseEnd::FinishTime)
        );
        let instance = plan(FirstPhase::ObjectFields, None, true);
        assert_eq!(
            instance.phase_end(RunPhase::AfterStream, 50, (0, 4), running),
            Some(PhaseEnd::Converged),
            "objects alone: a stale category plan does not count"
        );
        assert_eq!(
            fast.phase_end(RunPhase::Stream, 50, (0, 0), running),
            None,
            "the stream has no cap"
        );
    }

    #[test]
    fn category_fields_follow_registrations_only_where_the_schedule_trains_them() {
        let fast = plan(FirstPhase::ObjectAndCategoryFields, None, true);
        let paper = plan(FirstPhase::ObjectFields, Some(70), false);
        assert!(fast.category_fields_follow(RunPhase::Stream));
        assert!(fast.category_fields_follow(RunPhase::AfterStream));
        assert!(paper.category_fields_follow(RunPhase::Stream), "online category mode");
        assert!(
            !paper.category_fields_follow(RunPhase::AfterStream),
            "paper refines objects first"
        );
        assert!(paper.category_fields_follow(RunPhase::CategorySetup));
        assert!(!paper.category_fields_follow(RunPhase::Categories));
        let instance = PhasePlan {
            categories: false,
            ..fast
        };
        assert!(!instance.category_fields_follow(RunPhase::Stream));
    }

    #[test]
    fn a_restored_run_continues_in_the_phase_its_progress_names() {
        let paper = plan(FirstPhase::ObjectFields, Some(70), false);
        let end = Some(PhaseEnd::StepCap);
        assert_eq!(paper.resumed(false, None, (0, None)), RunPhase::Stream);
        assert_eq!(paper.resumed(true, None, (0, None)), RunPhase::AfterStream);
        assert_eq!(paper.resumed(true, end, (0, None)), RunPhase::CategorySetup);
        assert_eq!(paper.resumed(true, end, (50, None)), RunPhase::Categories);
        assert_eq!(paper.resumed(true, end, (70, end)), RunPhase::Meshing);
        let fast = plan(FirstPhase::ObjectAndCategoryFields, None, true);
        assert_eq!(fast.resumed(true, end, (0, None)), RunPhase::Meshing);
    }
}
