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
use super::loss::{FieldLosses, LossNorm};
use super::object_field::OccupancyField;
use super::occupancy::{OccupancyNet, OccupancyScratch};
use super::samples::SampleBatch;
use super::simd::Backend;
use super::tasks::{Task, TaskPool, plan_tasks, tasks_by_field};
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
        let losses = self.compute_gradients(batch)?;
        let optim = self.optim;
        self.fields
            .par_iter_mut()
            .zip(self.grads.par_iter())
            .for_each(|(field, grad)| {
                let (params, state) = field.params_and_state_mut();
                state.update(&optim, params, grad);
            });
        Ok(losses)
    }

    /// Losses and canonical gradients (flat, in each field's layout order) without updating.
    pub fn loss_and_gradients(&mut self, batch: &SampleBatch) -> Result<(Vec<FieldLosses>, Vec<Vec<f32>>)> {
        let losses = self.compute_gradients(batch)?;
        Ok((losses, self.grads[..self.fields.len()].to_vec()))
    }

    fn compute_gradients(&mut self, batch: &SampleBatch) -> Result<Vec<FieldLosses>> {
        if batch.fields.len() != self.fields.len() {
            return Err(CatmapError::Degenerate(format!(
                "{} fields but samples for {}",
                self.fields.len(),
                batch.fields.len()
            )));
        }
        for rays in &batch.fields {
            rays.validate()?;
        }
        let backend = self.backend;
        let nets = &self.nets;
        let net_of = |f: &OccupancyField| nets.iter().find(|n| n.hidden == f.hidden());
        let nets_of: Vec<&OccupancyNet> = self.fields.iter().filter_map(net_of).collect();
        debug_assert_eq!(nets_of.len(), self.fields.len(), "every hidden width has a net");

        // Pack every field's weights.
        self.packed.resize_with(self.fields.len(), Vec::new);
        self.packed
            .par_iter_mut()
            .zip(&self.fields)
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
            .zip(&self.fields)
            .map(|(r, f)| r.samples_per_ray * f.params().len())
            .collect();
        let tasks = plan_tasks(&units, &cost, TASK_WORK);
        let norms: Vec<LossNorm> = batch.fields.iter().map(LossNorm::of).collect();
        let (fields, packed) = (&self.fields, &self.packed);
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
        let by_field = tasks_by_field(&tasks, self.fields.len());
        let task_grads = self.pool.grads();
        self.grads.resize_with(self.fields.len(), Vec::new);
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
            .zip(&self.fields)
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
