//! Unit tests of [`super::StepScheduler`].

use super::*;
use crate::ids::ObjectId;
use crate::training::facts::{ClassShare, FieldRole, Sighting, StreamPhase};

const PLATEAU: PlateauConfig = PlateauConfig {
    window_steps: 3,
    min_relative_drop: 0.05,
    learning_rate_decays: 0,
    learning_rate_decay: 1.0,
    min_steps_alone: 0,
};

fn object(id: u32, role: FieldRole, sighting: Sighting) -> FieldFacts {
    FieldFacts {
        key: FieldKey::Object(ObjectId(id)),
        role,
        sighting,
        phase: StreamPhase::Streaming,
        class: ClassShare::Shared,
    }
}

/// `facts` once the stream has ended.
fn after_stream(facts: FieldFacts) -> FieldFacts {
    FieldFacts {
        phase: StreamPhase::Ended,
        ..facts
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
fn the_field_of_an_object_alone_in_its_class_does_not_converge_before_its_minimum_steps() {
    let plateau = PlateauConfig {
        min_steps_alone: 15,
        ..PLATEAU
    };
    let steps_of = |class| {
        let mut scheduler = StepScheduler::default();
        let unseen = [FieldFacts {
            class,
            ..object(1, FieldRole::Learning, Sighting::Unseen)
        }];
        for _ in 0..40 {
            for key in scheduler.plan(&unseen, SchedulePolicy::Fast, &plateau) {
                scheduler.record(key, 1.0, &plateau);
            }
        }
        let progress = &scheduler.progress()[&FieldKey::Object(ObjectId(1))];
        (progress.steps, progress.state, progress.converged_at)
    };
    assert_eq!(
        steps_of(ClassShare::Alone),
        (15, FieldState::Converged, Some(15)),
        "a flat loss plateaus after 6 steps; alone in its class, the field trains on to 15"
    );
    assert_eq!(
        steps_of(ClassShare::Shared),
        (6, FieldState::Converged, Some(6)),
        "with twins it converges at its first plateau"
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
            phase: StreamPhase::Ended,
            class: ClassShare::Shared,
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
fn the_order_of_the_facts_does_not_change_the_plans() {
    // The mapper gathers facts in query order, which is not the key order: plans, learning
    // rates and the progress kept must not depend on it.
    let run = |rotation: usize| {
        let mut scheduler = StepScheduler::default();
        let mut plans = Vec::new();
        for tick in 0..40u32 {
            let mut facts: Vec<(usize, FieldFacts)> = (0..5)
                .map(|id| {
                    let sighting = if (tick + id) % 7 == 0 {
                        Sighting::Seen
                    } else {
                        Sighting::Unseen
                    };
                    (4 - id as usize, object(id, FieldRole::Learning, sighting))
                })
                .collect();
            let n = facts.len();
            facts.rotate_left((rotation + tick as usize) % n);
            if rotation % 2 == 1 {
                facts.reverse();
            }
            let plan = scheduler.plan_batch(&facts, SchedulePolicy::Fast, &PLATEAU);
            let losses: Vec<f32> = plan
                .keys
                .iter()
                .map(|key| {
                    let FieldKey::Object(id) = key else {
                        unreachable!("object facts only")
                    };
                    1.0 + 0.1 * ((tick * 31 + id.0 * 7) % 5) as f32
                })
                .collect();
            scheduler.record_step(&plan.keys, &losses, &PLATEAU);
            plans.push(plan);
        }
        (plans, scheduler)
    };
    let first = run(0);
    for rotation in 1..4 {
        assert_eq!(run(rotation), first, "facts rotated by {rotation} give other plans");
    }
    assert!(
        first.0.iter().any(|p| p.indices.len() < 5),
        "some fields rested, so the plans could differ"
    );
    assert!(
        first.0.iter().all(|p| p.indices.is_sorted()),
        "plans list fields by batch index"
    );
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
        BatchPlan {
            indices: vec![1, 2],
            keys: vec![FieldKey::Object(ObjectId(8)), FieldKey::Object(ObjectId(7))],
            learning_rate_scales: vec![1.0, 1.0],
        }
    );
}
#[test]
fn after_the_stream_a_plateau_decays_the_learning_rate_before_the_field_converges() {
    let plateau = PlateauConfig {
        learning_rate_decays: 2,
        learning_rate_decay: 0.5,
        ..PLATEAU
    };
    let key = FieldKey::Object(ObjectId(1));
    let mut scheduler = StepScheduler::default();
    let run = |scheduler: &mut StepScheduler, facts: &[FieldFacts], steps: usize| {
        for _ in 0..steps {
            for key in scheduler.plan(facts, SchedulePolicy::Fast, &plateau) {
                scheduler.record(key, 1.0, &plateau);
            }
        }
    };
    let streaming = [object(1, FieldRole::Learning, Sighting::Unseen)];
    run(&mut scheduler, &streaming, 20);
    assert_eq!(
        (scheduler.progress()[&key].steps, scheduler.progress()[&key].state),
        (6, FieldState::Converged),
        "while streaming, a plateau rests the field at its full rate"
    );
    assert_eq!(scheduler.learning_rate_scale(key, &plateau), 1.0);
    let ended = [after_stream(streaming[0])];
    run(&mut scheduler, &ended, 20);
    let progress = &scheduler.progress()[&key];
    assert_eq!(
        (progress.steps, progress.decays, progress.state),
        (6 + 6 + 6, 2, FieldState::Converged),
        "two more plateaus, at half and a quarter of the rate"
    );
    assert_eq!(scheduler.learning_rate_scale(key, &plateau), 0.25);
    let keyframe = [object(1, FieldRole::Learning, Sighting::NewKeyframe)];
    run(&mut scheduler, &keyframe, 1);
    assert_eq!(
        scheduler.learning_rate_scale(key, &plateau),
        1.0,
        "new data: the full rate again"
    );
    assert_eq!(
        scheduler.learning_rate_scale(FieldKey::Category(9), &plateau),
        1.0,
        "an unknown field trains at the full rate"
    );
}
