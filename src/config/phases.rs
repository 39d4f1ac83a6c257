//! [`AfterStream`]: the training phases once the stream has ended, resolved from the config.

use crate::categories::class_registration::CategoryConfig;
use crate::categories::subcategories::SubcategoryAssignment;
use crate::field::RaySamplerConfig;
use crate::objects::config::{BoxFit, ObjectConfig};
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
    /// Box samples per ray of the `fast` schedule's object sampler (`fields.object_rays.box_free_samples`
    /// unset).
    pub const CARVING_SAMPLES: usize = 3;

    /// Solid-prior, seen-free-prior and support-prior rays per step of the `fast` schedule's
    /// object sampler (`fields.object_rays.hidden_solid_rays` / `seen_free_rays` /
    /// `below_support_rays` unset), for objects alone in their class.
    pub const PRIOR_RAYS: usize = 8;

    /// Mirrored rays per step of the `fast` schedule's object sampler
    /// (`fields.object_rays.mirror_rays` unset), for objects alone in their class whose cloud has
    /// a vertical mirror plane.
    pub const MIRROR_RAYS: usize = 24;

    /// Pixels per keyframe drawn among the object's own pixels by the `fast` schedule's object
    /// sampler (`fields.object_rays.own_pixel_draws` unset): a third of the 24.
    pub const OWN_PIXEL_DRAWS: usize = 8;

    /// The schedule that applies: `schedule.policy`, except that the offline protocol is the
    /// paper's fixed one (its classes are registered on the finished per-object fields).
    pub fn training_policy(&self) -> SchedulePolicy {
        if self.fields.offline {
            SchedulePolicy::Paper
        } else {
            self.schedule.policy
        }
    }

    /// The object sampler the run uses: `fields.object_rays`, its unset `box_free_samples`,
    /// prior and mirrored ray counts and own-pixel draws set by the schedule —
    /// [`Self::CARVING_SAMPLES`], [`Self::PRIOR_RAYS`], [`Self::MIRROR_RAYS`] and
    /// [`Self::OWN_PIXEL_DRAWS`] under `fast`, none (vMAP's sampler, no priors) under `paper`.
    pub fn object_rays(&self) -> RaySamplerConfig {
        let (carving, priors, mirror, own) = match self.training_policy() {
            SchedulePolicy::Fast => (
                Self::CARVING_SAMPLES,
                Self::PRIOR_RAYS,
                Self::MIRROR_RAYS,
                Self::OWN_PIXEL_DRAWS,
            ),
            SchedulePolicy::Paper => (0, 0, 0, 0),
        };
        self.fields
            .object_rays
            .with_default_carving(carving)
            .with_default_priors([priors; 3])
            .with_default_mirror_rays(mirror)
            .with_default_own_pixel_draws(own)
    }

    /// Solid-prior rays per category member and step in the cells no member of its field saw
    /// into: `category_fields.hidden_solid_rays`, unset [`Self::PRIOR_RAYS`] under `fast` and
    /// none under `paper`.
    pub fn member_solid_rays(&self) -> usize {
        let scheduled = match self.training_policy() {
            SchedulePolicy::Fast => Self::PRIOR_RAYS,
            SchedulePolicy::Paper => 0,
        };
        self.category_fields.hidden_solid_rays.unwrap_or(scheduled)
    }

    /// The class registration the run uses: `categories`, its unset subcategory assignment set
    /// by the schedule — the best explanation under `fast`, the paper's first acceptance under
    /// `paper`.
    pub fn category_registration(&self) -> CategoryConfig {
        let mut cfg = self.categories.clone();
        cfg.subcategories
            .assignment
            .get_or_insert(match self.training_policy() {
                SchedulePolicy::Fast => SubcategoryAssignment::Best,
                SchedulePolicy::Paper => SubcategoryAssignment::First,
            });
        cfg
    }

    /// The object settings the run uses: `objects`, its unset `box_fit` set by the schedule —
    /// upright boxes turned as the observed faces under `fast`, the paper's minimum-volume boxes
    /// under `paper`.
    pub fn object_settings(&self) -> ObjectConfig {
        let mut cfg = self.objects.clone();
        cfg.box_fit.get_or_insert(match self.training_policy() {
            SchedulePolicy::Fast => BoxFit::UprightOnFaces,
            SchedulePolicy::Paper => BoxFit::MinimumVolume,
        });
        cfg
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
    fn the_schedule_sets_the_unset_box_samples_and_priors_and_the_config_wins() {
        let sampler = |policy| {
            let rays = config(policy, Protocol::Online, Fields::Category).object_rays();
            (
                rays.carving_samples(),
                rays.solid_prior_rays(),
                rays.seen_free_rays(),
                rays.below_support_rays(),
                rays.own_pixel_draws(),
            )
        };
        assert_eq!(sampler(SchedulePolicy::Fast), (3, 8, 8, 8, 8));
        assert_eq!(
            sampler(SchedulePolicy::Paper),
            (0, 0, 0, 0, 0),
            "the paper's sampler, no priors"
        );
        let mut off = config(SchedulePolicy::Fast, Protocol::Online, Fields::Category);
        off.fields.object_rays.hidden_solid_rays = Some(0);
        off.fields.object_rays.seen_free_rays = Some(2);
        off.fields.object_rays.below_support_rays = Some(0);
        let rays = off.object_rays();
        assert_eq!(
            (
                rays.solid_prior_rays(),
                rays.seen_free_rays(),
                rays.below_support_rays()
            ),
            (0, 2, 0)
        );
        let offline = config(SchedulePolicy::Fast, Protocol::Offline, Fields::Category).object_rays();
        assert_eq!(offline.solid_prior_rays(), 0, "offline runs the paper's protocol");
        assert_eq!(offline.own_pixel_draws(), 0);
    }

    #[test]
    fn the_schedule_sets_the_members_unset_solid_prior_and_the_config_wins() {
        let members = |c: &MapperConfig| c.member_solid_rays();
        let mut fast = config(SchedulePolicy::Fast, Protocol::Online, Fields::Category);
        assert_eq!(members(&fast), MapperConfig::PRIOR_RAYS);
        let paper = config(SchedulePolicy::Paper, Protocol::Online, Fields::Category);
        assert_eq!(members(&paper), 0, "the paper's category fields take no prior");
        let offline = config(SchedulePolicy::Fast, Protocol::Offline, Fields::Category);
        assert_eq!(members(&offline), 0);
        fast.category_fields.hidden_solid_rays = Some(3);
        assert_eq!(members(&fast), 3);
    }

    #[test]
    fn the_schedule_sets_the_unset_box_fit_and_the_config_wins() {
        let fit = |c: &MapperConfig| c.object_settings().box_fit;
        let mut fast = config(SchedulePolicy::Fast, Protocol::Online, Fields::Category);
        assert_eq!(fit(&fast), Some(BoxFit::UprightOnFaces));
        let paper = config(SchedulePolicy::Paper, Protocol::Online, Fields::Category);
        assert_eq!(fit(&paper), Some(BoxFit::MinimumVolume));
        fast.objects.box_fit = Some(BoxFit::MinimumVolume);
        assert_eq!(fit(&fast), Some(BoxFit::MinimumVolume));
    }

    #[test]
    fn the_schedule_sets_the_unset_subcategory_assignment_and_the_config_wins() {
        let assignment = |c: &MapperConfig| c.category_registration().subcategories.assignment;
        let mut fast = config(SchedulePolicy::Fast, Protocol::Online, Fields::Category);
        assert_eq!(assignment(&fast), Some(SubcategoryAssignment::Best));
        let paper = config(SchedulePolicy::Paper, Protocol::Online, Fields::Category);
        assert_eq!(
            assignment(&paper),
            Some(SubcategoryAssignment::First),
            "the paper's greedy rule"
        );
        fast.categories.subcategories.assignment = Some(SubcategoryAssignment::First);
        assert_eq!(assignment(&fast), Some(SubcategoryAssignment::First));
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
