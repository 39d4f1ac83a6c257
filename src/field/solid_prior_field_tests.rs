//! A field trained on a constructed bed with the priors: what the open cells' free draws do to
//! its occupancy in the gap under the frame.

use nalgebra::Point3;

use super::*;
use crate::ObjectId;
use crate::field::{AdamWConfig, FieldBatch, OBJECT_HIDDEN, OccupancyField, RaySamplerConfig, sample_training_rays};
use crate::objects::hidden_space::{CellRules, FreeCells, HiddenCells, UnseenCells};
use crate::objects::view_fixtures::{bed_on_the_floor, bed_views};
use crate::rng::{RngStream, seeded_rng};

/// Steps of training.
const STEPS: usize = 400;

/// The bed's field after [`STEPS`] steps on its three views, with 8 solid-prior and 8 seen-free
/// rays per step drawn by `free`'s rule and `below_support` support-prior rays; the field's
/// origin.
fn trained(free: FreeCells, below_support: usize) -> (OccupancyField, Point3<f32>) {
    let (scene, bed_box) = bed_on_the_floor();
    let views = bed_views(&scene);
    let views: Vec<&ObjectView> = views.iter().collect();
    let rules = CellRules {
        hidden: HiddenCells::Enclosed,
        unseen: UnseenCells::Unknown,
        free,
    };
    let space = HiddenSpace::of_views(&views, &bed_box, None, rules);
    let origin = bed_box.center();
    let mut rng = seeded_rng(2, RngStream::ObjectField(ObjectId(1)));
    let mut batch = FieldBatch::new(AdamWConfig::default());
    batch.push(OccupancyField::new(OBJECT_HIDDEN, 2.0, &mut rng));
    let cfg = RaySamplerConfig {
        box_free_samples: 3,
        ..RaySamplerConfig::OBJECT
    };
    let counts = PriorRays {
        hidden_solid: 8,
        below_support,
        seen_free: 8,
        weight: 1.0,
    };
    for _ in 0..STEPS {
        let mut rays = sample_training_rays(&views, &[1, 2], &origin, Some(&bed_box), &cfg, &mut rng);
        append_prior_rays(&mut rays, &space, &views, counts, &origin, &mut rng);
        batch.train_step(&[rays]).expect("a step");
    }
    (batch.field(0).expect("one field").clone(), origin)
}

/// Mean occupancy of `field` over `points` (world).
fn mean_occupancy(field: &OccupancyField, origin: &Point3<f32>, points: &[Point3<f32>]) -> f32 {
    field.eval_occupancy_world(origin, points).iter().sum::<f32>() / points.len() as f32
}

#[test]
fn the_open_cells_free_draws_empty_the_gap_under_a_bed_and_keep_its_frame() {
    let grid = |z: f32| -> Vec<Point3<f32>> {
        (0..11)
            .flat_map(|i| (0..13).map(move |j| Point3::new(-0.5 + 0.1 * i as f32, 1.4 + 0.1 * j as f32, z)))
            .collect()
    };
    let gap: Vec<Point3<f32>> = [0.04, 0.08].into_iter().flat_map(grid).collect();
    let frame = grid(0.3);
    let (seen, origin) = trained(FreeCells::Seen, 0);
    let (open, _) = trained(FreeCells::SeenAndOpen, 0);
    let (gap_seen, gap_open) = (
        mean_occupancy(&seen, &origin, &gap),
        mean_occupancy(&open, &origin, &gap),
    );
    let (frame_seen, frame_open) = (
        mean_occupancy(&seen, &origin, &frame),
        mean_occupancy(&open, &origin, &frame),
    );
    assert!(
        gap_open < 0.5 * gap_seen,
        "occupancy in the gap under the frame: {gap_seen} with the cells seen free, {gap_open} with the open cells too"
    );
    assert!(
        frame_open > 0.8,
        "the frame's inside stays solid: {frame_seen} with the cells seen free, {frame_open} with the open cells too"
    );
}

#[test]
fn the_support_prior_empties_the_floor_under_a_bed_that_no_ray_reaches() {
    // Under the bed's footprint, 2–5 cm below the floor's surface (z = 0): every view's ray
    // stops at the frame or at the floor beside it, so only the support prior speaks of it.
    let below: Vec<Point3<f32>> = [-0.02, -0.035, -0.05]
        .into_iter()
        .flat_map(|z| {
            (0..11)
                .flat_map(move |i| (0..15).map(move |j| Point3::new(-0.6 + 0.12 * i as f32, 1.2 + 0.11 * j as f32, z)))
        })
        .collect();
    let (without, origin) = trained(FreeCells::SeenAndOpen, 0);
    let (with, _) = trained(FreeCells::SeenAndOpen, 8);
    let (o_without, o_with) = (
        mean_occupancy(&without, &origin, &below),
        mean_occupancy(&with, &origin, &below),
    );
    println!("occupancy under the floor: {o_without} without the support prior, {o_with} with it");
    assert!(
        o_with < 0.5 * o_without && o_with < 0.2,
        "occupancy under the floor: {o_without} without the support prior, {o_with} with it"
    );
}
