//! [`FusedBatch`]: the one training skeleton of every batch of fields — the per-object occupancy
//! fields ([`super::FieldBatch`]) and the category fields ([`super::CategoryBatch`]).
//!
//! One `train_step` does, for every field of the step and in parallel:
//! 1. prepare the field once (pack its weights into GEMM panels; a category also evaluates its
//!    code table);
//! 2. split each field's rays into tasks of whole rays (by shape only, never by thread count)
//!    and run each task chunk by chunk (≈ [`CHUNK_SAMPLES`] samples, so activations stay in L2):
//!    forward, render, loss and the whole backward pass, into the task's own gradient buffer;
//! 3. reduce each field's task buffers in task order into its canonical gradient (a category
//!    also back-propagates its code table and adds the code regulariser);
//! 4. apply AdamW with the field's own state(s), to the fields of the step only.
//!
//! So the results are bit-identical for any thread count. What differs between the two kinds of
//! field — the network, what a chunk computes, the reduction, the update — is a [`FusedModel`].

use std::fmt::Debug;
use std::ops::Range;

use rayon::prelude::*;

use super::adamw::{AdamWConfig, scaled_optimisers};
use super::loss::{FieldLosses, LossNorm};
use super::samples::RaySamples;
use super::simd::Backend;
use super::tasks::{Task, TaskPool, plan_tasks, tasks_by_field, update_active};
use crate::error::{CatmapError, Result};

/// Target samples per chunk.
pub const CHUNK_SAMPLES: usize = 120;
/// Upper bound of a task's work, in sample × parameter units (≈ one object's step).
const TASK_WORK: usize = 1200 * 12_000;

/// One kind of field trained by [`FusedBatch`]: its network and what the skeleton's steps do
/// for it. Implemented by [`super::OccupancyModel`] and [`super::CategoryModel`].
pub trait FusedModel {
    /// A field: weights, optimiser state(s), encoding scale.
    type Field: Debug + Send + Sync;
    /// The packed network of one field shape (fields of one shape share it).
    type Net: Debug + Send + Sync;
    /// A task's reusable activations.
    type Scratch: Debug + Default + Send;
    /// One field's samples of a step.
    type Samples: Debug + Sync;
    /// What a field's chunks read besides its weights, made once per step.
    type Prepared: Debug + Default + Send + Sync;
    /// One field's gradients.
    type Gradients: Debug + Default + Clone + Send + Sync;
    /// One field's losses of a step.
    type Losses: Send;
    /// The fields' plural noun in error messages.
    const NOUN: &'static str;

    /// Whether `net` is the network of `field`'s shape.
    fn fits(net: &Self::Net, field: &Self::Field) -> bool;
    /// The network of `field`'s shape.
    fn net_of(field: &Self::Field) -> Self::Net;
    /// The rays of `samples`.
    fn rays(samples: &Self::Samples) -> &RaySamples;
    /// Checks `samples` against `field`.
    fn validate(samples: &Self::Samples, field: &Self::Field) -> Result<()>;
    /// Trainable weights of `field` (its codes not included).
    fn param_count(field: &Self::Field) -> usize;
    /// Floats of a task's gradient buffer.
    fn task_grad_len(net: &Self::Net, field: &Self::Field) -> usize;
    /// Prepares `field` for a step into `out`.
    fn prepare(net: &Self::Net, field: &Self::Field, out: &mut Self::Prepared);
    /// Forward, render, loss and backward of rays `rays` of one field; adds the gradient to
    /// `grad` and returns the chunk's share of the losses.
    fn train_chunk(
        field: FieldStep<'_, Self>,
        rays: Range<usize>,
        scratch: &mut Self::Scratch,
        grad: &mut [f32],
    ) -> FieldLosses;
    /// Reduces one field's task buffers (in task order) into `out`; returns its losses, given
    /// the sum of its chunks' rendering losses.
    fn reduce(
        field: FieldStep<'_, Self>,
        task_grads: &[&[f32]],
        out: &mut Self::Gradients,
        rendering: FieldLosses,
    ) -> Self::Losses;
    /// Applies AdamW (`optim`) with `grad` to `field`.
    fn update(optim: &AdamWConfig, field: &mut Self::Field, grad: &Self::Gradients);
}

/// What one field's chunks read in a step.
#[derive(Debug)]
pub struct FieldStep<'a, M: FusedModel + ?Sized> {
    /// The SIMD backend.
    pub backend: Backend,
    /// The field's network.
    pub net: &'a M::Net,
    /// The field.
    pub field: &'a M::Field,
    /// What the step prepared for it.
    pub prepared: &'a M::Prepared,
    /// Its samples.
    pub samples: &'a M::Samples,
    /// Reciprocal mask counts over all its rays.
    pub norm: &'a LossNorm,
}

impl<M: FusedModel + ?Sized> Clone for FieldStep<'_, M> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M: FusedModel + ?Sized> Copy for FieldStep<'_, M> {}

/// Independent fields of one kind, each with its own optimiser state, trained in one fused
/// batched step.
#[derive(Debug)]
pub struct FusedBatch<M: FusedModel> {
    fields: Vec<M::Field>,
    optim: AdamWConfig,
    backend: Backend,
    nets: Vec<M::Net>,
    prepared: Vec<M::Prepared>,
    grads: Vec<M::Gradients>,
    pool: TaskPool<M::Scratch>,
}

impl<M: FusedModel> FusedBatch<M> {
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
            prepared: Vec::new(),
            grads: Vec::new(),
            pool: TaskPool::default(),
        }
    }

    /// Adds a field; returns its index. Other fields' states are untouched.
    pub fn push(&mut self, field: M::Field) -> usize {
        if !self.nets.iter().any(|n| M::fits(n, &field)) {
            self.nets.push(M::net_of(&field));
        }
        self.fields.push(field);
        self.fields.len() - 1
    }

    /// Removes and returns field `index` (later fields shift down by one).
    pub fn remove(&mut self, index: usize) -> Option<M::Field> {
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
    pub fn fields(&self) -> &[M::Field] {
        &self.fields
    }

    /// Field `index`.
    pub fn field(&self, index: usize) -> Option<&M::Field> {
        self.fields.get(index)
    }

    /// Field `index`, mutable (e.g. to add a category member).
    pub fn field_mut(&mut self, index: usize) -> Option<&mut M::Field> {
        self.fields.get_mut(index)
    }

    /// The optimiser settings.
    pub fn optimiser(&self) -> &AdamWConfig {
        &self.optim
    }

    /// One training step on `samples` (one per field, in field order): returns each field's
    /// losses before the update.
    pub fn train_step(&mut self, samples: &[M::Samples]) -> Result<Vec<M::Losses>> {
        let all: Vec<usize> = (0..self.fields.len()).collect();
        self.train_step_of(&all, samples)
    }

    /// One training step of the fields `active` only (ascending indices; `samples` holds one
    /// entry per active field, in that order): returns their losses before the update. The
    /// other fields get no forward, backward or AdamW update — not even weight decay — so their
    /// weights and optimiser moments stay bit for bit as they were.
    pub fn train_step_of(&mut self, active: &[usize], samples: &[M::Samples]) -> Result<Vec<M::Losses>> {
        self.train_step_scaled(active, &vec![1.0; active.len()], samples)
    }

    /// [`FusedBatch::train_step_of`] with field `active[k]`'s learning rate (and so its weight
    /// decay, as in PyTorch's schedulers) multiplied by `learning_rate_scales[k]`.
    pub fn train_step_scaled(
        &mut self,
        active: &[usize],
        learning_rate_scales: &[f32],
        samples: &[M::Samples],
    ) -> Result<Vec<M::Losses>> {
        let optims = scaled_optimisers(&self.optim, active, learning_rate_scales)?;
        let losses = self.compute_gradients(active, samples)?;
        update_active(&mut self.fields, active, &self.grads, |k, field, grad| {
            M::update(&optims[k], field, grad);
        });
        Ok(losses)
    }

    /// Losses and gradients of every field without updating.
    pub fn loss_and_gradients(&mut self, samples: &[M::Samples]) -> Result<(Vec<M::Losses>, Vec<M::Gradients>)> {
        let all: Vec<usize> = (0..self.fields.len()).collect();
        let losses = self.compute_gradients(&all, samples)?;
        Ok((losses, self.grads[..self.fields.len()].to_vec()))
    }

    /// Losses and gradients of the fields `active` (ascending), whose samples come in that
    /// order; `self.grads[k]` belongs to field `active[k]`.
    fn compute_gradients(&mut self, active: &[usize], samples: &[M::Samples]) -> Result<Vec<M::Losses>> {
        if samples.len() != active.len() {
            return Err(CatmapError::mismatch(
                format!("samples of the {} to train", M::NOUN),
                active.len(),
                samples.len(),
            ));
        }
        if active.windows(2).any(|w| w[0] >= w[1]) || active.last().is_some_and(|&i| i >= self.fields.len()) {
            return Err(CatmapError::mismatch(
                format!("indices of the {} to train", M::NOUN),
                format!("ascending, below {}", self.fields.len()),
                format!("{active:?}"),
            ));
        }
        let fields: Vec<&M::Field> = active.iter().map(|&i| &self.fields[i]).collect();
        for (s, field) in samples.iter().zip(&fields) {
            M::validate(s, field)?;
        }
        let nets = &self.nets;
        let nets_of: Vec<&M::Net> = fields
            .iter()
            .filter_map(|f| nets.iter().find(|n| M::fits(n, f)))
            .collect();
        debug_assert_eq!(nets_of.len(), fields.len(), "every field shape has a net");

        // 1. Prepare every active field.
        self.prepared
            .resize_with(fields.len().max(self.prepared.len()), M::Prepared::default);
        self.prepared
            .par_iter_mut()
            .zip(&fields)
            .zip(&nets_of)
            .for_each(|((prepared, field), net)| M::prepare(net, field, prepared));

        // 2. Fused forward/backward, split into tasks of whole rays.
        let units: Vec<usize> = samples.iter().map(|s| M::rays(s).num_rays()).collect();
        let cost: Vec<usize> = samples
            .iter()
            .zip(&fields)
            .map(|(s, f)| M::rays(s).samples_per_ray * M::param_count(f))
            .collect();
        let tasks = plan_tasks(&units, &cost, TASK_WORK);
        let norms: Vec<LossNorm> = samples.iter().map(|s| LossNorm::of(M::rays(s))).collect();
        let backend = self.backend;
        let prepared = &self.prepared;
        let step_of = |f: usize| FieldStep::<M> {
            backend,
            net: nets_of[f],
            field: fields[f],
            prepared: &prepared[f],
            samples: &samples[f],
            norm: &norms[f],
        };
        let task_losses = self.pool.run(
            &tasks,
            |f| M::task_grad_len(nets_of[f], fields[f]),
            |task: &Task, scratch, grad| {
                let chunk_rays = (CHUNK_SAMPLES / M::rays(&samples[task.field]).samples_per_ray).max(1);
                let mut losses = FieldLosses::default();
                let mut start = task.start;
                while start < task.end {
                    let end = (start + chunk_rays).min(task.end);
                    losses = losses.add(M::train_chunk(step_of(task.field), start..end, scratch, grad));
                    start = end;
                }
                losses
            },
        );

        // 3. Deterministic per-field reduction, in task order.
        let by_field = tasks_by_field(&tasks, fields.len());
        let task_grads = self.pool.grads();
        self.grads
            .resize_with(fields.len().max(self.grads.len()), M::Gradients::default);
        Ok(self.grads[..fields.len()]
            .par_iter_mut()
            .zip(&by_field)
            .enumerate()
            .map(|(f, (grad, ids))| {
                let rendering = ids
                    .iter()
                    .fold(FieldLosses::default(), |acc, &i| acc.add(task_losses[i]));
                let buffers: Vec<&[f32]> = ids.iter().map(|&i| task_grads[i].as_slice()).collect();
                M::reduce(step_of(f), &buffers, grad, rendering)
            })
            .collect())
    }
}
