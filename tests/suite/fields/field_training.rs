//! Per-object fields in the streaming mapper: fields appear with boxes, online and offline
//! schedules queue the right number of steps, losses fall, meshes come out in world coordinates
//! near the ground truth, and the same seed gives bit-identical meshes.

use std::ops::ControlFlow;

use catmap::config::FieldConfig;
use catmap::dataset::FrameSource;
use catmap::meshing::MapMeshes;
use catmap::metrics::{Crop, evaluate_dirs};
use catmap::synth::{Preset, SyntheticScene, write_replica_layout};
use catmap::{MapperConfig, ObjectId};
use catmap_systems::components::{FieldLoss, FieldSlot, Object, ObjectBounds};
use catmap_systems::{Mapper, RunOutcome, RunPhase};

const SEED: u64 = 11;

/// A cheap training configuration: few steps per frame and `after_stream` steps after the
/// stream, coarse meshes.
fn cheap_config(steps_per_frame: usize, after_stream: usize) -> MapperConfig {
    let mut config = MapperConfig {
        seed: SEED,
        fields: FieldConfig {
            steps_per_frame,
            final_steps: after_stream,
            offline_iterations: after_stream,
            ..FieldConfig::default()
        },
        ..MapperConfig::paper()
    };
    config.category_fields.enabled = false; // the per-object fields alone
    config.meshes.preview_every_frames = 0;
    config.meshes.object.voxel_size_m = 0.02;
    config.meshes.background_voxel_m = 0.2;
    config
}

fn stream_scene(mapper: &mut Mapper, scene: &SyntheticScene) {
    for position in 0..scene.len() {
        mapper.push(scene.read_frame(position).expect("frame")).expect("push");
        mapper.step().expect("a tick");
    }
    mapper.end_stream().expect("a tick");
    mapper.step().expect("a tick");
}

/// Mean total loss of the object fields at their latest step.
fn mean_object_loss(mapper: &mut Mapper) -> f32 {
    let world = mapper.world_mut();
    let losses: Vec<f32> = world
        .query::<(&Object, &FieldLoss)>()
        .iter(world)
        .map(|(_, l)| l.latest.total)
        .collect();
    losses.iter().sum::<f32>() / losses.len() as f32
}

#[test]
fn every_object_with_a_box_trains_online_and_its_loss_falls() {
    let scene = SyntheticScene::generate(SEED, Preset::Small).expect("scene");
    let mut mapper = Mapper::new(cheap_config(2, 150)).expect("config");
    stream_scene(&mut mapper, &scene);
    assert_eq!(mapper.training_steps(), 2 * scene.len() as u64, "2 steps per frame");

    let world = mapper.world_mut();
    let mut rows: Vec<(ObjectId, bool, Option<usize>, u64)> = world
        .query::<(&Object, Option<&ObjectBounds>, Option<&FieldSlot>, Option<&FieldLoss>)>()
        .iter(world)
        .map(|(o, b, s, l)| (o.id, b.is_some(), s.map(|s| s.index), l.map_or(0, |l| l.steps)))
        .collect();
    rows.sort();
    assert!(rows.len() >= 4, "the small scene has several objects");
    let mut indices: Vec<usize> = rows.iter().filter_map(|r| r.2).collect();
    indices.sort_unstable();
    assert_eq!(
        indices,
        (0..indices.len()).collect::<Vec<_>>(),
        "batch indices are 0..n"
    );
    for (id, has_box, slot, steps) in &rows {
        assert_eq!(
            has_box,
            &slot.is_some(),
            "object {id}: a field exactly when it has a box"
        );
        if slot.is_some() {
            assert!(*steps > 0, "object {id} trained");
        }
    }

    let before = mean_object_loss(&mut mapper);
    assert_eq!(
        mapper.run(|_| ControlFlow::Continue(())).expect("the run"),
        RunOutcome::Complete
    );
    let after = mean_object_loss(&mut mapper);
    assert_eq!(mapper.training_steps(), 2 * scene.len() as u64 + 150);
    assert!(after < 0.7 * before, "loss falls with training: {before} → {after}");
}

#[test]
fn the_offline_protocol_trains_only_after_the_stream() {
    let scene = SyntheticScene::generate(SEED, Preset::Small).expect("scene");
    let mut config = cheap_config(20, 120);
    config.fields.offline = true;
    let mut mapper = Mapper::new(config).expect("config");
    stream_scene(&mut mapper, &scene);
    assert_eq!(mapper.training_steps(), 0, "no step while streaming");
    let mut reported = Vec::new();
    let outcome = mapper
        .run(|progress| {
            reported.push((progress.phase, progress.done));
            ControlFlow::Continue(())
        })
        .expect("the run");
    assert_eq!(outcome, RunOutcome::Complete);
    let reported: Vec<u64> = reported
        .iter()
        .map(|&(phase, done)| {
            assert_eq!(phase, RunPhase::AfterStream);
            done
        })
        .collect();
    assert_eq!(reported, [50, 100, 120]);
    assert_eq!(mapper.training_steps(), 120);
}

/// Streams the small scene, trains offline and returns the final meshes.
fn final_meshes(offline_steps: usize) -> MapMeshes {
    let scene = SyntheticScene::generate(SEED, Preset::Small).expect("scene");
    let mut config = cheap_config(1, offline_steps);
    config.fields.offline = true;
    // The background field is off by default; these meshes include it.
    config.fields.background_every = 10;
    let mut mapper = Mapper::new(config).expect("config");
    stream_scene(&mut mapper, &scene);
    assert_eq!(
        mapper.run(|_| ControlFlow::Continue(())).expect("the run"),
        RunOutcome::Complete
    );
    mapper.extract_final_meshes().expect("final meshes")
}

#[test]
fn meshes_are_written_per_object_near_the_ground_truth_and_repeat_bit_for_bit() {
    let meshes = final_meshes(150);
    let scene = SyntheticScene::generate(SEED, Preset::Small).expect("scene");
    assert_eq!(meshes.objects.len(), scene.objects().len(), "a mesh for every object");
    assert!(
        meshes.background.as_ref().is_some_and(|m| !m.is_empty()),
        "the background is meshed"
    );

    let dir = tempfile::tempdir().expect("temp dir");
    let gt = dir.path().join("scene");
    write_replica_layout(&scene, &gt, |_, _| {}).expect("write the scene");
    let pred = dir.path().join("meshes");
    let written = meshes.write_dir(&pred).expect("write meshes");
    assert!(written >= scene.objects().len(), "objects, background and scene files");
    assert!(pred.join("scene.ply").is_file() && pred.join("background.ply").is_file());
    let report = evaluate_dirs(&pred, &gt, Crop::Paper, 0).expect("evaluate");
    assert_eq!(report.mean.missing, 0, "every ground-truth object has a mesh");
    // 150 steps of the paper's protocol is a short run: it measures accuracy 5.05 cm,
    // completion 4.60 cm and 76.8 % of the surface within 5 cm (converged runs reach 1.4–3 cm).
    // The bounds leave ~20 % of that, so a regression in training or meshing fails here.
    let mean = &report.mean;
    let (accuracy, completion) = (
        mean.accuracy_cm.expect("accuracy"),
        mean.completion_cm.expect("completion"),
    );
    println!("mean over objects: {mean:?}");
    assert!(
        accuracy < 6.0 && completion < 5.5 && mean.completion_ratio_5cm_pct > 70.0,
        "the meshes are near the ground truth: {mean:?}"
    );

    let again = final_meshes(150);
    assert_eq!(meshes, again, "the same seed gives bit-identical meshes");
}
