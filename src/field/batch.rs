//! [`FieldBatch`]: many independent occupancy fields trained together in one fused step.
//!
//! One `train_step` does, for every field and in parallel: pack weights into GEMM panels;
//! for every chunk of whole rays (≈ [`CHUNK_SAMPLES`] samples, so activations stay in L2):
//! encode, MLP forward, sigmoid, render, loss, and the whole backward pass, accumulating the
//! gradient; then reduce each field's task gradients (in a fixed order) and apply AdamW with
//! that field's own state. Fields may differ in hidden width (objects H = 32, background
//! H = 128) and in rays and samples per ray.

use rayon::prelude::*;

use super::adamw::AdamWConfig;
use super::adamw::scaled_optimisers;
use super::loss::{FieldLosses, LossNorm};
use super::object_field::OccupancyField;
use super::occupancy::{OccupancyNet, OccupancyScratch};
use super::samples::SampleBatch;
use super::simd::Backend;
use super::tasks::{Task, TaskPool, plan_tasks, tasks_by_field, update_active};
use crate::error::{CatmapError, Result};

/// Target samples per chunk.
pub const CHUNK_SAMPLES: usize = 120;
/// Upper bound of a task's work, in sample × parameter units (≈ one object's step).
const TASK_WORK: usize = 1200 * 12_000;

/// Independent occupancy fields with per-field AdamW state, trained in one batched step.
#[derive(Debug)]
pub struct FieldBatch {
    fields: Vec<OccupancyField>,
    optim: AdamWConfig,
    backend: Backend,
    nets: Vec<OccupancyNet>,
    packed: Vec<Vec<f32>>,
    grads: Vec<Vec<f32>>,
    pool: TaskPool<OccupancyScratch>,
}

impl FieldBatch {
    /// An empty batch with optimiser settings `optim`, on the best SIMD backend of this CPU.
    pub fn new(optim: AdamWConfig) -> Self {
        Self::with_backend(optim, Backend::detect())
    }

    /// An empty batch running its kernels on `backend`.
    pub fn with_backend(optim: AdamWConfig, backend: Backend) -> Self {
        Self {
            fields: Vec::new(),
            optim,
            backend,
            nets: Vec::new(),
            packed: Vec::new(),
            grads: Vec::new(),
            pool: TaskPool::default(),
        }
    }

    /// Adds a field; returns its index. Other fields' optimiser states are untouched.
    pub fn push(&mut self, field: OccupancyField) -> usize {
        if !self.nets.iter().any(|n| n.hidden == field.hidden()) {
            self.nets.push(OccupancyNet::new(field.hidden()));
        }
        self.fields.push(field);
        self.fields.len() - 1
    }

    /// Removes and returns field `index` (later fields shift down by one).
    pub fn remove(&mut self, index: usize) -> Option<OccupancyField> {
        (index < self.fields.len()).then(|| self.fields.remove(index))
    }

    /// Number of fields.
    pub fn len(&self) -> usize {
        self.fields.len()
    }

    /// Whether the batch has no field.
    pub fn is_empty(&self) -> bool {
        self.fields.is_empty()
    }

    /// The fields, in index order.
    pub fn fields(&self) -> &[OccupancyField] {
        &self.fields
    }

    /// Field `index`.
    pub fn field(&self, index: usize) -> Option<&OccupancyField> {
        self.fields.get(index)
    }

    /// Field `index`, mutable.
    pub fn field_mut(&mut self, index: usize) -> Option<&mut OccupancyField> {
        self.fields.get_mut(index)
    }

    /// The optimiser settings.
    pub fn optimiser(&self) -> &AdamWConfig {
        &self.optim
    }

    /// One training step on `batch` (one [`super::RaySamples`] per field, in field order):
    /// returns each field's losses before the update.
    pub fn train_step(&mut self, batch: &SampleBatch) -> Result<Vec<FieldLosses>> {
        let all: Vec<usize> = (0..self.fields.len()).collect();
        self.train_step_of(&all, batch)
    }

    /// One training step of the fields `active` only (ascending indices; `batch` holds one
    /// [`super::RaySamples`] per active field, in that order): returns their losses before the
    /// update. The other fields get no forward, backward or AdamW update — not even weight
    /// decay — so their weights and optimiser moments stay bit for bit as they were.
    pub fn train_step_of(&mut self, active: &[usize], batch: &SampleBatch) -> Result<Vec<FieldLosses>> {
        self.train_step_scaled(active, &vec![1.0; active.len()], batch)
    }

    /// [`FieldBatch::train_step_of`] with field `active[k]`'s learning rate (and so its weight
    /// decay, as in PyTorch's schedulers) multiplied by `learning_rate_scales[k]`.
    pub fn train_step_scaled(
        &mut self,
        active: &[usize],
        learning_rate_scales: &[f32],
        batch: &SampleBatch,
    ) -> Result<Vec<FieldLosses>> {
        let optims = scaled_optimisers(&self.optim, active, learning_rate_scales)?;
        let losses = self.compute_gradients(active, batch)?;
        update_active(&mut self.fields, active, &self.grads, |k, field, grad| {
            let (params, state) = field.params_and_state_mut();
            state.update(&optims[k], params, grad);
        });
        Ok(losses)
    }

    /// Losses and canonical gradients (flat, in each field's layout order) without updating.
    pub fn loss_and_gradients(&mut self, batch: &SampleBatch) -> Result<(Vec<FieldLosses>, Vec<Vec<f32>>)> {
        let all: Vec<usize> = (0..self.fields.len()).collect();
        let losses = self.compute_gradients(&all, batch)?;
        Ok((losses, self.grads[..self.fields.len()].to_vec()))
    }

    /// Losses and gradients of the fields `active` (ascending), whose samples `batch` holds in
    /// that order; `self.grads[k]` is the gradient of field `active[k]`.
    fn compute_gradients(&mut self, active: &[usize], batch: &SampleBatch) -> Result<Vec<FieldLosses>> {
        if batch.fields.len() != active.len() {
            return Err(CatmapError::Degenerate(format!(
                "{} fields to train but samples for {}",
                active.len(),
                batch.fields.len()
            )));
        }
        if active.windows(2).any(|w| w[0] >= w[1]) || active.last().is_some_and(|&i| i >= self.fields.len()) {
            return Err(CatmapError::Degenerate(format!(
                "field indices {active:?} must ascend and lie below {}",
                self.fields.len()
            )));
        }
        for rays in &batch.fields {
            rays.validate()?;
        }
        let backend = self.backend;
        let nets = &self.nets;
        let fields: Vec<&OccupancyField> = active.iter().map(|&i| &self.fields[i]).collect();
        let net_of = |f: &OccupancyField| nets.iter().find(|n| n.hidden == f.hidden());
        let nets_of: Vec<&OccupancyNet> = fields.iter().filter_map(|f| net_of(f)).collect();
        debug_assert_eq!(nets_of.len(), fields.len(), "every hidden width has a net");

        // Pack every active field's weights.
        self.packed.resize_with(fields.len().max(self.packed.len()), Vec::new);
        self.packed
            .par_iter_mut()
            .zip(&fields)
            .zip(&nets_of)
            .for_each(|((packed, field), net)| {
                packed.resize(net.packed_len, 0.0);
                net.pack(field.params(), packed);
            });

        // Fused forward/backward, split into tasks of whole rays.
        let units: Vec<usize> = batch.fields.iter().map(|r| r.num_rays()).collect();
        let cost: Vec<usize> = batch
            .fields
            .iter()
            .zip(&fields)
            .map(|(r, f)| r.samples_per_ray * f.params().len())
            .collect();
        let tasks = plan_tasks(&units, &cost, TASK_WORK);
        let norms: Vec<LossNorm> = batch.fields.iter().map(LossNorm::of).collect();
        let packed = &self.packed;
        let task_losses = self.pool.run(
            &tasks,
            |f| nets_of[f].grad_len,
            |task: &Task, scratch, grad| {
                let (f, rays) = (task.field, &batch.fields[task.field]);
                let chunk_rays = (CHUNK_SAMPLES / rays.samples_per_ray).max(1);
                let mut losses = FieldLosses::default();
                let mut start = task.start;
                while start < task.end {
                    let end = (start + chunk_rays).min(task.end);
                    let l = nets_of[f].train_chunk(
                        backend,
                        fields[f].params(),
                        &packed[f],
                        fields[f].scale(),
                        rays,
                        start..end,
                        &norms[f],
                        scratch,
                        grad,
                    );
                    losses = losses.add(l);
                    start = end;
                }
                losses
            },
        );

        // Deterministic per-field reduction into canonical gradients.
        let by_field = tasks_by_field(&tasks, fields.len());
        let task_grads = self.pool.grads();
        self.grads.resize_with(fields.len().max(self.grads.len()), Vec::new);
        let per_field: Vec<FieldLosses> = by_field
            .iter()
            .map(|ids| {
                ids.iter()
                    .fold(FieldLosses::default(), |acc, &i| acc.add(task_losses[i]))
            })
            .collect();
        self.grads
            .par_iter_mut()
            .zip(&by_field)
            .zip(&nets_of)
            .zip(&fields)
            .for_each(|(((grad, ids), net), field)| {
                grad.clear();
                grad.resize(field.params().len(), 0.0);
                for &i in ids {
                    net.unpack_grad(&task_grads[i], grad);
                }
            });
        Ok(per_field)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
            batch
                .train_step_of(&[0, 2], &SampleBatch { fields: samples })
                .expect("valid step");
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
        both.train_step(&SampleBatch {
            fields: samples.clone(),
        })
        .expect("valid step");
        let losses = alone
            .train_step_of(
                &[2],
                &SampleBatch {
                    fields: vec![samples[2].clone()],
                },
            )
            .expect("valid step");
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
            let samples = SampleBatch {
                fields: rays(1, active.len()),
            };
            let err = batch.train_step_of(&active, &samples).expect_err("bad indices");
            assert!(err.to_string().contains("must ascend"), "{active:?}: {err}");
        }
        let err = batch
            .train_step_of(&[0, 1], &SampleBatch { fields: rays(1, 1) })
            .expect_err("one sample set for two fields");
        assert!(err.to_string().contains("samples for 1"), "{err}");
    }

    #[test]
    fn a_scaled_step_trains_each_field_at_its_own_learning_rate() {
        let samples = rays(4, 2);
        let mut scaled = batch_of(2);
        scaled
            .train_step_scaled(
                &[0, 1],
                &[0.5, 1.0],
                &SampleBatch {
                    fields: samples.clone(),
                },
            )
            .expect("valid step");
        let mut halved = FieldBatch::new(AdamWConfig {
            lr: AdamWConfig::default().lr * 0.5,
            ..AdamWConfig::default()
        });
        for field in batch_of(2).fields() {
            halved.push(field.clone());
        }
        halved
            .train_step(&SampleBatch {
                fields: samples.clone(),
            })
            .expect("valid step");
        let mut full = batch_of(2);
        full.train_step(&SampleBatch { fields: samples }).expect("valid step");
        assert_eq!(scaled.field(0), halved.field(0), "field 0 at half the rate");
        assert_eq!(scaled.field(1), full.field(1), "field 1 at the full rate");
        assert_ne!(scaled.field(0), full.field(0));
        for bad in [vec![1.0], vec![1.0, 0.0], vec![f32::NAN, 1.0]] {
            let err = scaled
                .train_step_scaled(&[0, 1], &bad, &SampleBatch { fields: rays(5, 2) })
                .expect_err("bad scales");
            assert!(err.to_string().contains("scale"), "{bad:?}: {err}");
        }
    }
}
