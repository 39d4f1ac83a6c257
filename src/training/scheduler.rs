//! [`StepScheduler`]: which fields take the next training steps.
//!
//! Every step of the batched model costs in proportion to the fields it trains, so the fast
//! schedule trains only the fields that gain from a step:
//! - a field seen in this tick's frames (its newest keyframe slot holds a new view) trains;
//! - a new keyframe also restarts its convergence test (the data changed);
//! - otherwise a field trains while its loss still falls ([`LossWindow`]) and stops once it
//!   has plateaued;
//! - a category member's own field, while its category field makes its mesh
//!   ([`FieldRole::Supporting`]), trains only on a new keyframe, at a low rate, to keep its
//!   uncertainty and re-registration current; a [`FieldRole::Frozen`] field never trains.
//!
//! The paper's schedule ([`SchedulePolicy::Paper`]) trains every field on every step, as the
//! fixed protocol does. The scheduler is pure: the mapper hands it the facts (roles,
//! sightings, losses) and applies its plans; the same facts give the same plans.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::plateau::{LossWindow, PlateauConfig};
use crate::ids::{FrameIndex, ObjectId};

/// A field the scheduler plans for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub enum FieldKey {
    /// An object's own occupancy field.
    Object(ObjectId),
    /// A category field, by its creation number (stable while its membership changes).
    Category(u32),
    /// The background field.
    Background,
}

/// What a field is for at the moment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum FieldRole {
    /// Its own mesh comes from it: it trains while it gains from steps.
    Learning,
    /// A category member's own field while the stream lasts: the category field makes the mesh;
    /// it trains only on a new keyframe (uncertainty and re-registration read it).
    Supporting,
    /// It gets no steps.
    Frozen,
}

/// What this tick's frames showed of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Sighting {
    /// Not in this tick's frames.
    Unseen,
    /// In a frame of this tick (its live keyframe slot changed).
    Seen,
    /// In a frame of this tick that became one of its keyframes.
    NewKeyframe,
}

impl Sighting {
    /// What the frames of this tick (`this_tick`) showed of an object last seen in frame
    /// `last.frame` (`last.keyframe`: that frame became one of its keyframes).
    pub fn of(last: Option<LastSeen>, this_tick: &[FrameIndex]) -> Self {
        match last {
            Some(seen) if this_tick.contains(&seen.frame) => {
                if seen.keyframe {
                    Self::NewKeyframe
                } else {
                    Self::Seen
                }
            }
            _ => Self::Unseen,
        }
    }

    /// The strongest of two sightings (a category field is seen when any member is).
    pub fn max(self, other: Self) -> Self {
        let rank = |s: Self| match s {
            Self::Unseen => 0,
            Self::Seen => 1,
            Self::NewKeyframe => 2,
        };
        if rank(other) > rank(self) { other } else { self }
    }
}

/// The latest frame an object was seen in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct LastSeen {
    /// The frame.
    pub frame: FrameIndex,
    /// Whether it became one of the object's keyframes.
    pub keyframe: bool,
}

/// Whose mesh an object's own field makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshSource {
    /// Its own field.
    OwnField,
    /// Its category field (it is a member of one).
    CategoryField,
}

/// Whether frames are still streaming in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamPhase {
    /// Frames arrive.
    Streaming,
    /// The stream has ended.
    Ended,
}

impl FieldRole {
    /// The role of an object's own field: learning while it makes the object's mesh; once a
    /// category field makes it, supporting while the stream lasts (uncertainty and
    /// re-registration read it) and frozen after.
    pub fn of_object_field(mesh: MeshSource, phase: StreamPhase) -> Self {
        match (mesh, phase) {
            (MeshSource::OwnField, _) => Self::Learning,
            (MeshSource::CategoryField, StreamPhase::Streaming) => Self::Supporting,
            (MeshSource::CategoryField, StreamPhase::Ended) => Self::Frozen,
        }
    }
}

/// The facts about one field that a plan depends on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldFacts {
    /// Which field.
    pub key: FieldKey,
    /// What it is for.
    pub role: FieldRole,
    /// What this tick's frames showed of it.
    pub sighting: Sighting,
}

/// The facts of object `id`'s own field.
pub fn object_field_facts(
    id: ObjectId,
    last_seen: Option<LastSeen>,
    mesh: MeshSource,
    phase: StreamPhase,
    this_tick: &[FrameIndex],
) -> FieldFacts {
    FieldFacts {
        key: FieldKey::Object(id),
        role: FieldRole::of_object_field(mesh, phase),
        sighting: Sighting::of(last_seen, this_tick),
    }
}

/// The facts of category field `id` (its creation number): always learning, seen as its most
/// recently seen member.
pub fn category_field_facts(
    id: u32,
    members_last_seen: impl IntoIterator<Item = Option<LastSeen>>,
    this_tick: &[FrameIndex],
) -> FieldFacts {
    let sighting = members_last_seen
        .into_iter()
        .map(|last| Sighting::of(last, this_tick))
        .fold(Sighting::Unseen, Sighting::max);
    FieldFacts {
        key: FieldKey::Category(id),
        role: FieldRole::Learning,
        sighting,
    }
}

/// Why a training phase ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhaseEnd {
    /// No field gained from more steps (every one converged or frozen).
    Converged,
    /// The phase's step cap was reached.
    StepCap,
}

impl PhaseEnd {
    /// Whether a phase that has run `done` of at most `cap` steps ends, given how many fields
    /// its latest plan trained (`planned`; none = nothing gains from more steps).
    pub fn of(done: u64, cap: u64, planned: usize) -> Option<Self> {
        if planned == 0 {
            Some(Self::Converged)
        } else if done >= cap {
            Some(Self::StepCap)
        } else {
            None
        }
    }
}

/// How steps are given out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SchedulePolicy {
    /// Train what changes the map: seen, still improving; stop converged and replaced fields.
    Fast,
    /// The paper's fixed protocol: every field on every step.
    Paper,
}

/// Why a field is (not) training, as of the latest plan.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FieldState {
    /// It takes steps.
    Training,
    /// Its loss stopped falling.
    Converged,
    /// A supporting member's field between keyframes.
    Waiting,
    /// Frozen.
    Frozen,
}

/// What the scheduler knows of one field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldProgress {
    /// Steps it has taken.
    pub steps: u64,
    /// Its state after the latest plan.
    pub state: FieldState,
    /// Steps it had taken when it last converged.
    pub converged_at: Option<u64>,
    window: LossWindow,
}

impl Default for FieldProgress {
    fn default() -> Self {
        Self {
            steps: 0,
            state: FieldState::Training,
            converged_at: None,
            window: LossWindow::default(),
        }
    }
}

/// Plans training steps field by field (see the module doc).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct StepScheduler {
    fields: BTreeMap<FieldKey, FieldProgress>,
}

impl StepScheduler {
    /// The fields that take the next steps, in key order, given this tick's `facts`. Fields
    /// missing from `facts` are not planned (their progress is kept).
    pub fn plan(&mut self, facts: &[FieldFacts], policy: SchedulePolicy, plateau: &PlateauConfig) -> Vec<FieldKey> {
        let mut planned: Vec<FieldKey> = facts
            .iter()
            .filter(|f| {
                let progress = self.fields.entry(f.key).or_default();
                let state = match policy {
                    SchedulePolicy::Paper => FieldState::Training,
                    SchedulePolicy::Fast => next_state(progress, f, plateau),
                };
                if state == FieldState::Converged && progress.state != FieldState::Converged {
                    progress.converged_at = Some(progress.steps);
                }
                progress.state = state;
                state == FieldState::Training
            })
            .map(|f| f.key)
            .collect();
        planned.sort_unstable();
        planned.dedup();
        planned
    }

    /// [`StepScheduler::plan`] for fields that sit at batch indices: `facts` pairs each field's
    /// index with its facts; returns the planned fields as (index, key), ascending by index —
    /// what a batched step takes.
    pub fn plan_batch(
        &mut self,
        facts: &[(usize, FieldFacts)],
        policy: SchedulePolicy,
        plateau: &PlateauConfig,
    ) -> Vec<(usize, FieldKey)> {
        let plain: Vec<FieldFacts> = facts.iter().map(|(_, f)| *f).collect();
        let plan = self.plan(&plain, policy, plateau);
        let mut planned: Vec<(usize, FieldKey)> = facts
            .iter()
            .filter(|(_, f)| plan.binary_search(&f.key).is_ok())
            .map(|(index, f)| (*index, f.key))
            .collect();
        planned.sort_unstable();
        planned
    }

    /// Records that `key` took one step with total loss `loss`.
    pub fn record(&mut self, key: FieldKey, loss: f32, plateau: &PlateauConfig) {
        let progress = self.fields.entry(key).or_default();
        progress.steps += 1;
        progress.window.push(loss, plateau);
    }

    /// Every field's progress, in key order.
    pub fn progress(&self) -> &BTreeMap<FieldKey, FieldProgress> {
        &self.fields
    }

    /// Forgets a field that no longer exists.
    pub fn forget(&mut self, key: FieldKey) {
        self.fields.remove(&key);
    }
}

/// The state of a field under the fast policy (a new keyframe also restarts its window).
fn next_state(progress: &mut FieldProgress, facts: &FieldFacts, plateau: &PlateauConfig) -> FieldState {
    if facts.sighting == Sighting::NewKeyframe {
        progress.window.clear();
    }
    match (facts.role, facts.sighting) {
        (FieldRole::Frozen, _) => FieldState::Frozen,
        (FieldRole::Supporting, Sighting::NewKeyframe) => FieldState::Training,
        (FieldRole::Supporting, _) => FieldState::Waiting,
        (FieldRole::Learning, Sighting::Seen | Sighting::NewKeyframe) => FieldState::Training,
        (FieldRole::Learning, Sighting::Unseen) if progress.window.has_plateaued(plateau) => FieldState::Converged,
        (FieldRole::Learning, Sighting::Unseen) => FieldState::Training,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PLATEAU: PlateauConfig = PlateauConfig {
        window_steps: 3,
        min_relative_drop: 0.05,
    };

    fn object(id: u32, role: FieldRole, sighting: Sighting) -> FieldFacts {
        FieldFacts {
            key: FieldKey::Object(ObjectId(id)),
            role,
            sighting,
        }
    }

    /// Plans and records a step of loss `loss` for every planned field, `steps` times.
    fn train(scheduler: &mut StepScheduler, facts: &[FieldFacts], steps: usize, loss: impl Fn(usize) -> f32) {
        for step in 0..steps {
            for key in scheduler.plan(facts, SchedulePolicy::Fast, &PLATEAU) {
                scheduler.record(key, loss(step), &PLATEAU);
            }
        }
    }

    #[test]
    fn a_converged_field_gets_no_steps_until_it_is_seen_again() {
        let mut scheduler = StepScheduler::default();
        let unseen = [object(1, FieldRole::Learning, Sighting::Unseen)];
        train(&mut scheduler, &unseen, 20, |_| 1.0);
        let progress = &scheduler.progress()[&FieldKey::Object(ObjectId(1))];
        assert_eq!(progress.steps, 6, "two windows of a flat loss, then it stops");
        assert_eq!(
            (progress.state, progress.converged_at),
            (FieldState::Converged, Some(6))
        );
        assert!(scheduler.plan(&unseen, SchedulePolicy::Fast, &PLATEAU).is_empty());
        let seen = [object(1, FieldRole::Learning, Sighting::Seen)];
        assert_eq!(
            scheduler.plan(&seen, SchedulePolicy::Fast, &PLATEAU),
            [FieldKey::Object(ObjectId(1))],
            "seen in the new frame: it trains again"
        );
    }

    #[test]
    fn a_field_whose_loss_still_falls_keeps_training() {
        let mut scheduler = StepScheduler::default();
        let facts = [object(2, FieldRole::Learning, Sighting::Unseen)];
        train(&mut scheduler, &facts, 30, |step| 0.8f32.powi(step as i32));
        let progress = &scheduler.progress()[&FieldKey::Object(ObjectId(2))];
        assert_eq!((progress.steps, progress.state), (30, FieldState::Training));
    }

    #[test]
    fn a_new_keyframe_restarts_the_convergence_test() {
        let mut scheduler = StepScheduler::default();
        train(
            &mut scheduler,
            &[object(3, FieldRole::Learning, Sighting::Unseen)],
            10,
            |_| 1.0,
        );
        let keyframe = [object(3, FieldRole::Learning, Sighting::NewKeyframe)];
        train(&mut scheduler, &keyframe, 1, |_| 1.0);
        train(
            &mut scheduler,
            &[object(3, FieldRole::Learning, Sighting::Unseen)],
            10,
            |_| 1.0,
        );
        let progress = &scheduler.progress()[&FieldKey::Object(ObjectId(3))];
        assert_eq!(
            progress.steps,
            6 + 1 + 5,
            "the window restarts: six more steps to converge again"
        );
    }

    #[test]
    fn an_object_seen_in_the_new_frame_gets_steps_and_an_unseen_converged_one_does_not() {
        let mut scheduler = StepScheduler::default();
        let both = [
            object(1, FieldRole::Learning, Sighting::Unseen),
            object(2, FieldRole::Learning, Sighting::Unseen),
        ];
        train(&mut scheduler, &both, 10, |_| 1.0);
        let facts = [
            object(1, FieldRole::Learning, Sighting::Seen),
            object(2, FieldRole::Learning, Sighting::Unseen),
        ];
        assert_eq!(
            scheduler.plan(&facts, SchedulePolicy::Fast, &PLATEAU),
            [FieldKey::Object(ObjectId(1))]
        );
    }

    #[test]
    fn frozen_fields_never_train_and_supporting_ones_only_on_a_new_keyframe() {
        let mut scheduler = StepScheduler::default();
        let facts = [
            object(1, FieldRole::Frozen, Sighting::NewKeyframe),
            object(2, FieldRole::Supporting, Sighting::Seen),
            object(3, FieldRole::Supporting, Sighting::NewKeyframe),
        ];
        assert_eq!(
            scheduler.plan(&facts, SchedulePolicy::Fast, &PLATEAU),
            [FieldKey::Object(ObjectId(3))]
        );
        let states: Vec<FieldState> = scheduler.progress().values().map(|p| p.state).collect();
        assert_eq!(states, [FieldState::Frozen, FieldState::Waiting, FieldState::Training]);
    }

    #[test]
    fn the_paper_policy_trains_every_field_on_every_step() {
        let mut scheduler = StepScheduler::default();
        let facts = [
            object(1, FieldRole::Frozen, Sighting::Unseen),
            FieldFacts {
                key: FieldKey::Category(0),
                role: FieldRole::Learning,
                sighting: Sighting::Unseen,
            },
        ];
        for _ in 0..20 {
            let plan = scheduler.plan(&facts, SchedulePolicy::Paper, &PLATEAU);
            assert_eq!(plan.len(), 2);
            for key in plan {
                scheduler.record(key, 1.0, &PLATEAU);
            }
        }
    }

    #[test]
    fn the_same_facts_and_losses_give_the_same_plans() {
        let run = || {
            let mut scheduler = StepScheduler::default();
            let mut plans = Vec::new();
            for tick in 0..40u32 {
                let facts: Vec<FieldFacts> = (0..4)
                    .map(|id| {
                        let sighting = if (tick + id) % 7 == 0 {
                            Sighting::Seen
                        } else {
                            Sighting::Unseen
                        };
                        object(id, FieldRole::Learning, sighting)
                    })
                    .collect();
                let plan = scheduler.plan(&facts, SchedulePolicy::Fast, &PLATEAU);
                for key in &plan {
                    let loss = 1.0 + 0.1 * ((tick * 31) % 5) as f32;
                    scheduler.record(*key, loss, &PLATEAU);
                }
                plans.push(plan);
            }
            (plans, scheduler)
        };
        let (first, second) = (run(), run());
        assert_eq!(first, second);
        assert!(
            first.0.iter().any(Vec::is_empty) || first.0.iter().any(|p| p.len() < 4),
            "some fields rested"
        );
    }

    #[test]
    fn sightings_come_from_the_latest_frame_an_object_was_seen_in() {
        let tick = [FrameIndex(7), FrameIndex(8)];
        let seen = |frame, keyframe| {
            Some(LastSeen {
                frame: FrameIndex(frame),
                keyframe,
            })
        };
        assert_eq!(Sighting::of(seen(8, false), &tick), Sighting::Seen);
        assert_eq!(Sighting::of(seen(7, true), &tick), Sighting::NewKeyframe);
        assert_eq!(
            Sighting::of(seen(6, true), &tick),
            Sighting::Unseen,
            "seen in an earlier tick"
        );
        assert_eq!(Sighting::of(None, &tick), Sighting::Unseen);
        assert_eq!(Sighting::Seen.max(Sighting::NewKeyframe), Sighting::NewKeyframe);
        assert_eq!(Sighting::Seen.max(Sighting::Unseen), Sighting::Seen);
    }

    #[test]
    fn a_category_member_supports_while_streaming_and_freezes_after() {
        use FieldRole::*;
        let role = FieldRole::of_object_field;
        assert_eq!(role(MeshSource::OwnField, StreamPhase::Streaming), Learning);
        assert_eq!(role(MeshSource::OwnField, StreamPhase::Ended), Learning);
        assert_eq!(role(MeshSource::CategoryField, StreamPhase::Streaming), Supporting);
        assert_eq!(role(MeshSource::CategoryField, StreamPhase::Ended), Frozen);
    }

    #[test]
    fn a_category_field_is_seen_when_any_member_is() {
        let tick = [FrameIndex(5)];
        let seen = |frame, keyframe| {
            Some(LastSeen {
                frame: FrameIndex(frame),
                keyframe,
            })
        };
        let facts = category_field_facts(2, [seen(3, true), seen(5, false), None], &tick);
        assert_eq!(
            facts,
            FieldFacts {
                key: FieldKey::Category(2),
                role: FieldRole::Learning,
                sighting: Sighting::Seen,
            }
        );
        let facts = object_field_facts(
            ObjectId(4),
            seen(5, true),
            MeshSource::CategoryField,
            StreamPhase::Streaming,
            &tick,
        );
        assert_eq!(
            (facts.role, facts.sighting),
            (FieldRole::Supporting, Sighting::NewKeyframe)
        );
    }

    #[test]
    fn a_phase_ends_when_nothing_trains_or_at_its_cap() {
        assert_eq!(PhaseEnd::of(50, 100, 3), None);
        assert_eq!(PhaseEnd::of(100, 100, 3), Some(PhaseEnd::StepCap));
        assert_eq!(PhaseEnd::of(50, 100, 0), Some(PhaseEnd::Converged));
    }

    #[test]
    fn a_batch_plan_lists_the_planned_fields_by_batch_index() {
        let mut scheduler = StepScheduler::default();
        let facts = [
            (2, object(7, FieldRole::Learning, Sighting::Seen)),
            (0, object(9, FieldRole::Frozen, Sighting::Seen)),
            (1, object(8, FieldRole::Learning, Sighting::Unseen)),
        ];
        assert_eq!(
            scheduler.plan_batch(&facts, SchedulePolicy::Fast, &PLATEAU),
            [(1, FieldKey::Object(ObjectId(8))), (2, FieldKey::Object(ObjectId(7)))]
        );
    }
}
