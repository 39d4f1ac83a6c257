//! [`FieldBatch`]: many independent occupancy fields trained together in one fused step
//! ([`super::FusedBatch`] with the occupancy MLP). Fields may differ in hidden width (objects
//! H = 32, background H = 128) and in rays and samples per ray.

use std::ops::Range;

use super::adamw::AdamWConfig;
use super::fused_batch::{FieldStep, FusedBatch, FusedModel};
use super::loss::FieldLosses;
use super::object_field::OccupancyField;
use super::occupancy::{OccupancyNet, OccupancyScratch};
use super::samples::RaySamples;
use crate::error::Result;

/// Independent occupancy fields with per-field AdamW state, trained in one batched step on one
/// [`RaySamples`] per field.
pub type FieldBatch = FusedBatch<OccupancyModel>;

/// The per-object occupancy field as a [`FusedModel`]: packed weights are all a step prepares;
/// a field's gradient is the sum of its tasks' packed gradients, unpacked.
#[derive(Debug)]
pub struct OccupancyModel;

impl FusedModel for OccupancyModel {
    type Field = OccupancyField;
    type Net = OccupancyNet;
    type Scratch = OccupancyScratch;
    type Samples = RaySamples;
    type Prepared = Vec<f32>;
    type Gradients = Vec<f32>;
    type Losses = FieldLosses;
    const NOUN: &'static str = "fields";

    fn fits(net: &OccupancyNet, field: &OccupancyField) -> bool {
        net.hidden == field.hidden()
    }

    fn net_of(field: &OccupancyField) -> OccupancyNet {
        OccupancyNet::new(field.hidden())
    }

    fn rays(samples: &RaySamples) -> &RaySamples {
        samples
    }

    fn validate(samples: &RaySamples, _: &OccupancyField) -> Result<()> {
        samples.validate()
    }

    fn param_count(field: &OccupancyField) -> usize {
        field.params().len()
    }

    fn task_grad_len(net: &OccupancyNet, _: &OccupancyField) -> usize {
        net.grad_len
    }

    fn prepare(net: &OccupancyNet, field: &OccupancyField, packed: &mut Self::Prepared) {
        packed.resize(net.packed_len, 0.0);
        net.pack(field.params(), packed);
    }

    fn train_chunk(
        step: FieldStep<'_, Self>,
        rays: Range<usize>,
        scratch: &mut OccupancyScratch,
        grad: &mut [f32],
    ) -> FieldLosses {
        let field = step.field;
        step.net.train_chunk(
            step.backend,
            field.params(),
            step.prepared,
            field.scale(),
            step.samples,
            rays,
            step.norm,
            scratch,
            grad,
        )
    }

    fn reduce(
        step: FieldStep<'_, Self>,
        task_grads: &[&[f32]],
        out: &mut Self::Gradients,
        rendering: FieldLosses,
    ) -> FieldLosses {
        out.clear();
        out.resize(step.field.params().len(), 0.0);
        for g in task_grads {
            step.net.unpack_grad(g, out);
        }
        rendering
    }

    fn update(optim: &AdamWConfig, field: &mut OccupancyField, grad: &Self::Gradients) {
        let (params, state) = field.params_and_state_mut();
        state.update(optim, params, grad);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::CatmapError;
    use crate::field::RaySamples;
    use crate::rng::{RngStream, seeded_rng};
    use crate::{ObjectId, field::OBJECT_HIDDEN};

    fn batch_of(n: usize) -> FieldBatch {
        let mut batch = FieldBatch::new(AdamWConfig::default());
        for i in 0..n {
            let mut rng = seeded_rng(3, RngStream::ObjectField(ObjectId(i as u32)));
            batch.push(OccupancyField::new(OBJECT_HIDDEN, 2.0, &mut rng));
        }
        batch
    }

    fn rays(seed: u64, n: usize) -> Vec<RaySamples> {
        let mut rng = seeded_rng(seed, RngStream::Background);
        (0..n).map(|_| RaySamples::random(&mut rng, 24, 10, 0.5, 0.1)).collect()
    }

    #[test]
    fn a_field_outside_the_step_keeps_its_weights_and_moments_bit_for_bit() {
        let mut batch = batch_of(3);
        let before = batch.field(1).expect("three fields").clone();
        for step in 0..3 {
            let samples = rays(step, 2);
            batch.train_step_of(&[0, 2], &samples).expect("valid step");
        }
        assert_eq!(
            batch.field(1),
            Some(&before),
            "field 1 took no step: no update, no weight decay"
        );
        assert_eq!(batch.field(0).expect("field 0").optimiser_state().step, 3);
        assert_ne!(batch.field(2).expect("field 2").params(), before.params());
    }

    #[test]
    fn a_subset_step_equals_the_same_fields_trained_alone() {
        let (mut both, mut alone) = (batch_of(3), batch_of(3));
        let samples = rays(9, 3);
        both.train_step(&samples).expect("valid step");
        let losses = alone.train_step_of(&[2], &[samples[2].clone()]).expect("valid step");
        assert_eq!(losses.len(), 1, "one loss per trained field");
        assert_eq!(
            alone.field(2),
            both.field(2),
            "fields train independently: the subset step is the full step's restriction"
        );
    }

    #[test]
    fn indices_that_do_not_ascend_or_do_not_exist_are_refused() {
        let mut batch = batch_of(2);
        for active in [vec![1, 0], vec![0, 2], vec![1, 1]] {
            let samples = rays(1, active.len());
            let err = batch.train_step_of(&active, &samples).expect_err("bad indices");
            assert!(
                matches!(&err, CatmapError::ShapeMismatch { what, .. } if what.starts_with("indices")),
                "{active:?}: {err}"
            );
        }
        let err = batch
            .train_step_of(&[0, 1], &rays(1, 1))
            .expect_err("one sample set for two fields");
        assert!(
            matches!(&err, CatmapError::ShapeMismatch { what, expected, found }
                if what.starts_with("samples") && expected == "2" && found == "1"),
            "{err}"
        );
    }

    #[test]
    fn a_scaled_step_trains_each_field_at_its_own_learning_rate() {
        let samples = rays(4, 2);
        let mut scaled = batch_of(2);
        scaled
            .train_step_scaled(&[0, 1], &[0.5, 1.0], &samples.clone())
            .expect("valid step");
        let mut halved = FieldBatch::new(AdamWConfig {
            lr: AdamWConfig::default().lr * 0.5,
            ..AdamWConfig::default()
        });
        for field in batch_of(2).fields() {
            halved.push(field.clone());
        }
        halved.train_step(&samples).expect("valid step");
        let mut full = batch_of(2);
        full.train_step(&samples).expect("valid step");
        assert_eq!(scaled.field(0), halved.field(0), "field 0 at half the rate");
        assert_eq!(scaled.field(1), full.field(1), "field 1 at the full rate");
        assert_ne!(scaled.field(0), full.field(0));
        for bad in [vec![1.0], vec![1.0, 0.0], vec![f32::NAN, 1.0]] {
            let err = scaled
                .train_step_scaled(&[0, 1], &bad, &rays(5, 2))
                .expect_err("bad scales");
            assert!(err.to_string().contains("scale"), "{bad:?}: {err}");
        }
    }
}
