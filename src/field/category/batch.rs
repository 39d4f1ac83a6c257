//! [`CategoryBatch`]: many category fields trained together in one fused step.
//!
//! One `train_step` does, for every category and in parallel: pack the weights and evaluate the
//! code table (each member's four code activations); split each category's rays into tasks of
//! whole rays (by shape only, never by thread count) and run forward, rendering, loss and
//! backward chunk by chunk, each task into its own gradient buffer; reduce each category's task
//! buffers in task order, back-propagate the summed code-activation gradients once per member,
//! add the code regulariser, and apply AdamW to the weights and to every member's codes. So the
//! results are bit-identical for any thread count.

use rayon::prelude::*;

use super::super::adamw::AdamWConfig;
use super::super::adamw::scaled_optimisers;
use super::super::batch::CHUNK_SAMPLES;
use super::super::loss::{FieldLosses, LossNorm};
use super::super::simd::Backend;
use super::super::tasks::{Task, TaskPool, plan_tasks, tasks_by_field, update_active};
use super::model::CategoryField;
use super::net::{CategoryNet, CategoryScratch};
use super::train::ChunkInputs;
use super::{CategoryLosses, CategorySamples};
use crate::error::{CatmapError, Result};

/// Upper bound of a task's work, in sample × parameter units (as the object batch).
const TASK_WORK: usize = 1200 * 12_000;

/// Gradients of one category's total loss.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CategoryGradients {
    /// Of the network, flat in [`super::super::ParamLayout::category`] order.
    pub weights: Vec<f32>,
    /// Of each member's codes `[z_s ‖ z_t]`, in member order.
    pub codes: Vec<Vec<f32>>,
}

/// Category fields with their optimiser states, trained in one batched step.
#[derive(Debug)]
pub struct CategoryBatch {
    fields: Vec<CategoryField>,
    optim: AdamWConfig,
    backend: Backend,
    nets: Vec<CategoryNet>,
    packed: Vec<Vec<f32>>,
    tables: Vec<Vec<f32>>,
    grads: Vec<CategoryGradients>,
    pool: TaskPool<CategoryScratch>,
}

impl CategoryBatch {
    /// An empty batch with optimiser settings `optim` (weights and codes), on the best SIMD
    /// backend of this CPU.
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
            tables: Vec::new(),
            grads: Vec::new(),
            pool: TaskPool::default(),
        }
    }

    /// Adds a category; returns its index. Other categories' states are untouched.
    pub fn push(&mut self, field: CategoryField) -> usize {
        let shape = (field.hidden(), field.code_dim());
        if !self.nets.iter().any(|n| (n.hidden, n.code_dim) == shape) {
            self.nets.push(CategoryNet::new(shape.0, shape.1));
        }
        self.fields.push(field);
        self.fields.len() - 1
    }

    /// Removes and returns category `index` (later ones shift down by one).
    pub fn remove(&mut self, index: usize) -> Option<CategoryField> {
        (index < self.fields.len()).then(|| self.fields.remove(index))
    }

    /// Number of categories.
    pub fn len(&self) -> usize {
        self.fields.len()
    }

    /// Whether the batch has no category.
    pub fn is_empty(&self) -> bool {
        self.fields.is_empty()
    }

    /// The categories, in index order.
    pub fn fields(&self) -> &[CategoryField] {
        &self.fields
    }

    /// Category `index`.
    pub fn field(&self, index: usize) -> Option<&CategoryField> {
        self.fields.get(index)
    }

    /// Category `index`, mutable (e.g. to add a member).
    pub fn field_mut(&mut self, index: usize) -> Option<&mut CategoryField> {
        self.fields.get_mut(index)
    }

    /// The optimiser settings.
    pub fn optimiser(&self) -> &AdamWConfig {
        &self.optim
    }

    /// One training step on `samples` (one [`CategorySamples`] per category, in order): returns
    /// each category's losses before the update.
    pub fn train_step(&mut self, samples: &[CategorySamples]) -> Result<Vec<CategoryLosses>> {
        let all: Vec<usize> = (0..self.fields.len()).collect();
        self.train_step_of(&all, samples)
    }

    /// One training step of the categories `active` only (ascending indices; one
    /// [`CategorySamples`] per active category, in that order): returns their losses before the
    /// update. The other categories' weights, codes and optimiser moments stay bit for bit.
    pub fn train_step_of(&mut self, active: &[usize], samples: &[CategorySamples]) -> Result<Vec<CategoryLosses>> {
        self.train_step_scaled(active, &vec![1.0; active.len()], samples)
    }

    /// [`CategoryBatch::train_step_of`] with category `active[k]`'s learning rate (weights and
    /// codes, and so their weight decay) multiplied by `learning_rate_scales[k]`.
    pub fn train_step_scaled(
        &mut self,
        active: &[usize],
        learning_rate_scales: &[f32],
        samples: &[CategorySamples],
    ) -> Result<Vec<CategoryLosses>> {
        let optims = scaled_optimisers(&self.optim, active, learning_rate_scales)?;
        let losses = self.compute_gradients(active, samples)?;
        update_active(&mut self.fields, active, &self.grads, |k, field, grad| {
            let optim = &optims[k];
            let ((params, state), codes) = field.states_mut();
            state.update(optim, params, &grad.weights);
            for ((code, state), g) in codes.into_iter().zip(&grad.codes) {
                state.update(optim, code, g);
            }
        });
        Ok(losses)
    }

    /// Losses and gradients (weights and codes) without updating.
    pub fn loss_and_gradients(
        &mut self,
        samples: &[CategorySamples],
    ) -> Result<(Vec<CategoryLosses>, Vec<CategoryGradients>)> {
        let all: Vec<usize> = (0..self.fields.len()).collect();
        let losses = self.compute_gradients(&all, samples)?;
        Ok((losses, self.grads[..self.fields.len()].to_vec()))
    }

    /// Losses and gradients of the categories `active` (ascending), whose samples come in that
    /// order; `self.grads[k]` belongs to category `active[k]`.
    fn compute_gradients(&mut self, active: &[usize], samples: &[CategorySamples]) -> Result<Vec<CategoryLosses>> {
        if samples.len() != active.len() {
            return Err(CatmapError::Degenerate(format!(
                "{} categories to train but samples for {}",
                active.len(),
                samples.len()
            )));
        }
        if active.windows(2).any(|w| w[0] >= w[1]) || active.last().is_some_and(|&i| i >= self.fields.len()) {
            return Err(CatmapError::Degenerate(format!(
                "category indices {active:?} must ascend and lie below {}",
                self.fields.len()
            )));
        }
        let fields: Vec<&CategoryField> = active.iter().map(|&i| &self.fields[i]).collect();
        for (s, field) in samples.iter().zip(&fields) {
            s.validate(field.num_members())?;
        }
        let backend = self.backend;
        let nets = &self.nets;
        let net_of = |f: &CategoryField| {
            nets.iter()
                .find(|n| (n.hidden, n.code_dim) == (f.hidden(), f.code_dim()))
        };
        let nets_of: Vec<&CategoryNet> = fields.iter().filter_map(|f| net_of(f)).collect();
        debug_assert_eq!(nets_of.len(), fields.len(), "every shape has a net");

        // Pack weights and evaluate the code tables.
        let codes: Vec<Vec<Vec<f32>>> = fields.iter().map(|f| f.codes()).collect();
        self.packed.resize_with(fields.len().max(self.packed.len()), Vec::new);
        self.tables.resize_with(fields.len().max(self.tables.len()), Vec::new);
        self.packed
            .par_iter_mut()
            .zip(self.tables.par_iter_mut())
            .zip(&fields)
            .zip(&nets_of)
            .zip(&codes)
            .for_each(|((((packed, table), field), net), codes)| {
                packed.resize(net.packed_len, 0.0);
                net.pack(field.params(), packed);
                net.code_table(field.params(), codes, table);
            });

        // Fused forward/backward, split into tasks of whole rays.
        let units: Vec<usize> = samples.iter().map(|s| s.rays.num_rays()).collect();
        let cost: Vec<usize> = samples
            .iter()
            .zip(&fields)
            .map(|(s, f)| s.rays.samples_per_ray * f.param_count())
            .collect();
        let tasks = plan_tasks(&units, &cost, TASK_WORK);
        let norms: Vec<LossNorm> = samples.iter().map(|s| LossNorm::of(&s.rays)).collect();
        let (packed, tables) = (&self.packed, &self.tables);
        let dc_len = |f: usize| fields[f].num_members() * nets_of[f].table_row();
        let task_losses = self.pool.run(
            &tasks,
            |f| nets_of[f].grad_len + dc_len(f),
            |task: &Task, scratch, grad| {
                let f = task.field;
                let input = ChunkInputs {
                    params: fields[f].params(),
                    packed: &packed[f],
                    table: &tables[f],
                    scale: fields[f].scale(),
                    samples: &samples[f],
                    norm: &norms[f],
                };
                let chunk_rays = (CHUNK_SAMPLES / samples[f].rays.samples_per_ray).max(1);
                let mut losses = FieldLosses::default();
                let mut start = task.start;
                while start < task.end {
                    let end = (start + chunk_rays).min(task.end);
                    let l = nets_of[f].train_chunk(backend, input, start..end, scratch, grad);
                    losses = losses.add(l);
                    start = end;
                }
                losses
            },
        );

        // Deterministic per-category reduction, code backward and regulariser.
        let by_field = tasks_by_field(&tasks, fields.len());
        let task_grads = self.pool.grads();
        self.grads
            .resize_with(fields.len().max(self.grads.len()), CategoryGradients::default);
        let regs: Vec<f32> = self
            .grads
            .par_iter_mut()
            .zip(&by_field)
            .enumerate()
            .map(|(f, (grad, ids))| {
                let (field, net) = (&fields[f], nets_of[f]);
                let (reg, reg_grads) = field.code_reg();
                grad.weights.clear();
                grad.weights.resize(field.param_count(), 0.0);
                let mut dc = vec![0.0f32; dc_len(f)];
                for &i in ids {
                    net.unpack_grad(&task_grads[i], &mut grad.weights);
                    for (d, g) in dc.iter_mut().zip(&task_grads[i][net.grad_len..]) {
                        *d += g;
                    }
                }
                grad.codes = reg_grads;
                net.code_backward(
                    field.params(),
                    &codes[f],
                    &tables[f],
                    &dc,
                    &mut grad.weights,
                    &mut grad.codes,
                );
                reg
            })
            .collect();
        Ok(by_field
            .iter()
            .zip(regs)
            .map(|(ids, code_reg)| {
                let field = ids
                    .iter()
                    .fold(FieldLosses::default(), |acc, &i| acc.add(task_losses[i]));
                CategoryLosses {
                    field,
                    code_reg,
                    total: field.total + code_reg,
                }
            })
            .collect())
    }
}
