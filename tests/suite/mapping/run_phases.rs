//! The run's phases as ECS state: one schedule, stepped tick by tick, moves a mapper through
//! every phase in order — the stream, the training after it, the category fields' setup and
//! phase (the paper's schedule), the final meshing — each phase doing its own work only.

use catmap::MapperConfig;
use catmap::config::FieldConfig;
use catmap::dataset::FrameSource;
use catmap::synth::{Preset, SyntheticScene};
use catmap::training::{PhaseEnd, SchedulePolicy};
use catmap_systems::{Mapper, RunPhase};

fn config(policy: SchedulePolicy) -> MapperConfig {
    let mut config = MapperConfig {
        seed: 3,
        fields: FieldConfig {
            steps_per_frame: 3,
            final_steps: 60,
            ..FieldConfig::default()
        },
        ..MapperConfig::profile(policy)
    };
    config.schedule.max_steps_after_stream = 60;
    config.categories.min_field_steps = 20;
    config.category_fields.iterations = 60;
    config.meshes.object.voxel_size_m = 0.04;
    config.meshes.background_voxel_m = 0.1;
    config
}

/// Pushes every third frame of the small scene and ends the stream; then steps the mapper one
/// tick at a time until it is done, recording the phase of every tick with the steps and
/// category fields there were after it.
fn step_through(policy: SchedulePolicy) -> (Mapper, Vec<(RunPhase, u64, usize)>) {
    let scene = SyntheticScene::generate(4, Preset::Small).expect("small scene");
    let mut mapper = Mapper::new(config(policy)).expect("valid config");
    for position in (0..scene.len()).step_by(3) {
        assert_eq!(mapper.phase(), RunPhase::Stream);
        mapper
            .push(scene.read_frame(position).expect("frame renders"))
            .expect("valid frame");
        mapper.step().expect("a tick");
    }
    mapper.end_stream().expect("a tick");
    let mut ticks = Vec::new();
    while mapper.phase() != RunPhase::Done {
        assert!(ticks.len() < 100, "the run ends: {ticks:?}");
        let phase = mapper.phase();
        mapper.step().expect("a tick");
        ticks.push((phase, mapper.training_steps(), mapper.category_field_count()));
    }
    (mapper, ticks)
}

/// The phases of `ticks` in the order they ran, each once.
fn phases(ticks: &[(RunPhase, u64, usize)]) -> Vec<RunPhase> {
    let mut order: Vec<RunPhase> = ticks.iter().map(|t| t.0).collect();
    order.dedup();
    order
}

#[test]
fn the_paper_schedule_steps_through_every_phase_in_order() {
    let (mut mapper, ticks) = step_through(SchedulePolicy::Paper);
    assert_eq!(
        phases(&ticks),
        [
            RunPhase::Stream,
            RunPhase::AfterStream,
            RunPhase::CategorySetup,
            RunPhase::Categories,
            RunPhase::Meshing
        ]
    );
    let steps_in = |phase| -> u64 {
        let mut before = None;
        let mut sum = 0;
        for &(p, steps, _) in &ticks {
            if p == phase {
                sum += steps - before.unwrap_or(steps);
            }
            before = Some(steps);
        }
        sum
    };
    assert_eq!(steps_in(RunPhase::AfterStream), 60, "fields.final_steps, in chunks");
    assert_eq!(
        steps_in(RunPhase::CategorySetup),
        0,
        "the setup tick only creates the fields"
    );
    assert_eq!(steps_in(RunPhase::Categories), 60, "category_fields.iterations");
    assert_eq!(steps_in(RunPhase::Meshing), 0, "meshing trains nothing");
    let setup = ticks
        .iter()
        .find(|t| t.0 == RunPhase::CategorySetup)
        .expect("a setup tick");
    assert!(setup.2 > 0, "category fields exist after the setup tick: {ticks:?}");
    let report = mapper.training_report();
    assert_eq!(
        (report.after_stream_end, report.category_end),
        (Some(PhaseEnd::StepCap), Some(PhaseEnd::StepCap)),
        "the paper's phases run their fixed steps"
    );
    let meshes = mapper.extract_final_meshes().expect("final meshes");
    assert!(
        meshes.objects.len() >= 5,
        "the meshing phase meshed the objects: {}",
        meshes.objects.len()
    );
    let steps = mapper.training_steps();
    mapper.step().expect("a tick");
    assert_eq!(
        (mapper.phase(), mapper.training_steps()),
        (RunPhase::Done, steps),
        "a done mapper's tick does nothing"
    );
}

#[test]
fn the_fast_schedule_has_no_category_phase_and_ends_its_training_on_convergence_or_cap() {
    let (mut mapper, ticks) = step_through(SchedulePolicy::Fast);
    assert_eq!(
        phases(&ticks),
        [RunPhase::Stream, RunPhase::AfterStream, RunPhase::Meshing]
    );
    let after = ticks.iter().filter(|t| t.0 == RunPhase::AfterStream).count();
    assert_eq!(after, 2, "60 steps at most, in chunks of 50");
    let report = mapper.training_report();
    assert_eq!(
        (report.after_stream_end, report.category_end),
        (Some(PhaseEnd::StepCap), None),
        "the fast schedule's training after the stream ends at its cap here, and it has no category phase"
    );
    assert!(!mapper.extract_final_meshes().expect("final meshes").objects.is_empty());
}
