//! [`AfterStream`]: the training phases once the stream has ended, resolved from the config.

use crate::training::SchedulePolicy;

use super::MapperConfig;

/// Which fields train in the phase right after the stream.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstPhase {
    /// The per-object fields only (offline training, or the paper's refinement).
    ObjectFields,
    /// The per-object fields and the category fields together (fast schedule, online).
    ObjectAndCategoryFields,
}

/// The training once the stream has ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AfterStream {
    /// What the first phase trains.
    pub first: FirstPhase,
    /// Most steps of the first phase.
    pub first_cap: u64,
    /// Most steps of the category phase that follows (`None`: no category phase).
    pub category_cap: Option<u64>,
    /// Whether a phase ends early once no field gains from more steps (the fast schedule).
    pub ends_on_convergence: bool,
}

impl MapperConfig {
    /// The schedule that applies: `schedule.policy`, except that the offline protocol is the
    /// paper's fixed one (its classes are registered on the finished per-object fields).
    pub fn training_policy(&self) -> SchedulePolicy {
        if self.fields.offline {
            SchedulePolicy::Paper
        } else {
            self.schedule.policy
        }
    }

    /// The phases after the stream: the paper's fixed protocol (`fields.final_steps` or
    /// `fields.offline_iterations`, then `category_fields.iterations`), or the fast schedule's
    /// (online only: one phase of every field up to `schedule.max_steps_after_stream`, ending
    /// early once no field gains from more steps).
    pub fn after_stream(&self) -> AfterStream {
        let fast = self.training_policy() == SchedulePolicy::Fast;
        let categories = self.category_fields.enabled;
        let merged = fast && categories && self.fields.enabled;
        let first_cap = if fast && self.fields.enabled {
            self.schedule.max_steps_after_stream
        } else {
            self.fields.steps_after_stream()
        };
        AfterStream {
            first: if merged {
                FirstPhase::ObjectAndCategoryFields
            } else {
                FirstPhase::ObjectFields
            },
            first_cap: first_cap as u64,
            category_cap: (categories && !merged).then_some(self.category_fields.iterations as u64),
            ends_on_convergence: fast,
        }
    }

    /// The run's phases: the training after the stream, and whether fields and category fields
    /// train while streaming (`catmap::training::run_phase`).
    pub fn phase_plan(&self) -> crate::training::PhasePlan {
        crate::training::PhasePlan {
            after_stream: self.after_stream(),
            trains_online: self.fields.enabled && !self.fields.offline,
            categories: self.category_fields.enabled,
        }
    }

    /// The step counts this config sets away from their defaults that its schedule never runs:
    /// the fast schedule (online) ends the training after the stream on convergence or at
    /// `schedule.max_steps_after_stream`, in one phase that trains the category fields too, so
    /// `fields.final_steps` and `category_fields.iterations` are not used there. `catmap run`
    /// (any [`MapperConfig`] given to a mapper) warns about each, naming the key.
    pub fn unused_step_counts(&self) -> Vec<&'static str> {
        let defaults = MapperConfig::default();
        let phases = self.after_stream();
        let mut unused = Vec::new();
        if !phases.ends_on_convergence {
            return unused;
        }
        if self.fields.final_steps != defaults.fields.final_steps {
            unused.push("fields.final_steps");
        }
        if phases.category_cap.is_none() && self.category_fields.iterations != defaults.category_fields.iterations {
            unused.push("category_fields.iterations");
        }
        unused
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::training::ScheduleConfig;

    /// How the per-object fields train.
    enum Protocol {
        Online,
        Offline,
    }

    /// Which fields make the meshes.
    enum Fields {
        Category,
        Instance,
    }

    fn config(policy: SchedulePolicy, protocol: Protocol, fields: Fields) -> MapperConfig {
        let mut c = MapperConfig {
            schedule: ScheduleConfig {
                policy,
                max_steps_after_stream: 4_000,
                ..ScheduleConfig::default()
            },
            ..MapperConfig::default()
        };
        c.fields.offline = matches!(protocol, Protocol::Offline);
        c.category_fields.enabled = matches!(fields, Fields::Category);
        c
    }

    #[test]
    fn the_fast_schedule_online_trains_every_field_in_one_phase() {
        let phases = config(SchedulePolicy::Fast, Protocol::Online, Fields::Category).after_stream();
        assert_eq!(
            phases,
            AfterStream {
                first: FirstPhase::ObjectAndCategoryFields,
                first_cap: 4_000,
                category_cap: None,
                ends_on_convergence: true,
            }
        );
        let instance = config(SchedulePolicy::Fast, Protocol::Online, Fields::Instance).after_stream();
        assert_eq!(
            (instance.first, instance.category_cap),
            (FirstPhase::ObjectFields, None)
        );
    }

    #[test]
    fn the_paper_schedule_and_the_offline_protocol_keep_their_step_counts() {
        let paper = config(SchedulePolicy::Paper, Protocol::Online, Fields::Category).after_stream();
        assert_eq!(
            paper,
            AfterStream {
                first: FirstPhase::ObjectFields,
                first_cap: 3_000,
                category_cap: Some(10_000),
                ends_on_convergence: false,
            }
        );
        let offline = config(SchedulePolicy::Fast, Protocol::Offline, Fields::Category);
        assert_eq!(
            offline.training_policy(),
            SchedulePolicy::Paper,
            "offline is a fixed protocol"
        );
        let offline = offline.after_stream();
        assert_eq!(
            (offline.first_cap, offline.category_cap, offline.ends_on_convergence),
            (15_000, Some(10_000), false)
        );
    }

    #[test]
    fn step_counts_the_fast_schedule_never_runs_are_named() {
        let mut fast = config(SchedulePolicy::Fast, Protocol::Online, Fields::Category);
        assert!(fast.unused_step_counts().is_empty(), "the defaults warn about nothing");
        fast.fields.final_steps = 100;
        fast.category_fields.iterations = 100;
        assert_eq!(
            fast.unused_step_counts(),
            ["fields.final_steps", "category_fields.iterations"]
        );
        let mut paper = fast.clone();
        paper.schedule.policy = SchedulePolicy::Paper;
        assert!(paper.unused_step_counts().is_empty(), "the paper schedule runs both");
        let mut offline = fast.clone();
        offline.fields.offline = true;
        assert!(
            offline.unused_step_counts().is_empty(),
            "offline is the paper's protocol"
        );
    }
}
