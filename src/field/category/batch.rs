//! [`CategoryBatch`]: many category fields trained together in one fused step
//! ([`super::super::FusedBatch`] with the category network). A step prepares each category's
//! packed weights and its code table (each member's four code activations); the chunks sum each
//! member's ∂L/∂(code activations) into the tail of their gradient buffers; the reduction
//! back-propagates those sums once per member and adds the code regulariser; AdamW then updates
//! the weights and every member's codes, each with its own state.

use std::ops::Range;

use super::super::adamw::AdamWConfig;
use super::super::fused_batch::{FieldStep, FusedBatch, FusedModel};
use super::super::loss::FieldLosses;
use super::super::samples::RaySamples;
use super::model::CategoryField;
use super::net::{CategoryNet, CategoryScratch};
use super::train::ChunkInputs;
use super::{CategoryLosses, CategorySamples};
use crate::error::Result;

/// Category fields with their optimiser states, trained in one batched step on one
/// [`CategorySamples`] per category.
pub type CategoryBatch = FusedBatch<CategoryModel>;

/// Gradients of one category's total loss.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CategoryGradients {
    /// Of the network, flat in [`super::super::ParamLayout::category`] order.
    pub weights: Vec<f32>,
    /// Of each member's codes `[z_s ‖ z_t]`, in member order.
    pub codes: Vec<Vec<f32>>,
}

/// What a step prepares for one category.
#[derive(Debug, Default)]
pub struct PreparedCategory {
    packed: Vec<f32>,
    table: Vec<f32>,
    codes: Vec<Vec<f32>>,
}

/// The CodeNeRF-style category field as a [`FusedModel`].
#[derive(Debug)]
pub struct CategoryModel;

impl CategoryModel {
    /// Floats of the summed ∂L/∂(code activations) of every member.
    fn code_grad_len(net: &CategoryNet, field: &CategoryField) -> usize {
        field.num_members() * net.table_row()
    }
}

impl FusedModel for CategoryModel {
    type Field = CategoryField;
    type Net = CategoryNet;
    type Scratch = CategoryScratch;
    type Samples = CategorySamples;
    type Prepared = PreparedCategory;
    type Gradients = CategoryGradients;
    type Losses = CategoryLosses;
    const NOUN: &'static str = "categories";

    fn fits(net: &CategoryNet, field: &CategoryField) -> bool {
        (net.hidden, net.code_dim) == (field.hidden(), field.code_dim())
    }

    fn net_of(field: &CategoryField) -> CategoryNet {
        CategoryNet::new(field.hidden(), field.code_dim())
    }

    fn rays(samples: &CategorySamples) -> &RaySamples {
        &samples.rays
    }

    fn validate(samples: &CategorySamples, field: &CategoryField) -> Result<()> {
        samples.validate(field.num_members())
    }

    fn param_count(field: &CategoryField) -> usize {
        field.param_count()
    }

    fn task_grad_len(net: &CategoryNet, field: &CategoryField) -> usize {
        net.grad_len + Self::code_grad_len(net, field)
    }

    fn prepare(net: &CategoryNet, field: &CategoryField, out: &mut Self::Prepared) {
        out.codes = field.codes();
        out.packed.resize(net.packed_len, 0.0);
        net.pack(field.params(), &mut out.packed);
        net.code_table(field.params(), &out.codes, &mut out.table);
    }

    fn train_chunk(
        step: FieldStep<'_, Self>,
        rays: Range<usize>,
        scratch: &mut CategoryScratch,
        grad: &mut [f32],
    ) -> FieldLosses {
        let input = ChunkInputs {
            params: step.field.params(),
            packed: &step.prepared.packed,
            table: &step.prepared.table,
            scale: step.field.scale(),
            samples: step.samples,
            norm: step.norm,
        };
        step.net.train_chunk(step.backend, input, rays, scratch, grad)
    }

    fn reduce(
        step: FieldStep<'_, Self>,
        task_grads: &[&[f32]],
        out: &mut CategoryGradients,
        rendering: FieldLosses,
    ) -> CategoryLosses {
        let (field, net, prepared) = (step.field, step.net, step.prepared);
        let (code_reg, reg_grads) = field.code_reg();
        out.weights.clear();
        out.weights.resize(field.param_count(), 0.0);
        let mut dc = vec![0.0f32; Self::code_grad_len(net, field)];
        for g in task_grads {
            net.unpack_grad(g, &mut out.weights);
            for (d, g) in dc.iter_mut().zip(&g[net.grad_len..]) {
                *d += g;
            }
        }
        out.codes = reg_grads;
        net.code_backward(
            field.params(),
            &prepared.codes,
            &prepared.table,
            &dc,
            &mut out.weights,
            &mut out.codes,
        );
        for grad in &mut out.codes {
            field.shape_codes().fit(grad, field.code_dim());
        }
        CategoryLosses {
            field: rendering,
            code_reg,
            total: rendering.total + code_reg,
        }
    }

    fn update(optim: &AdamWConfig, field: &mut CategoryField, grad: &CategoryGradients) {
        let ((params, state), codes) = field.states_mut();
        state.update(optim, params, &grad.weights);
        for ((code, state), g) in codes.into_iter().zip(&grad.codes) {
            state.update(optim, code, g);
        }
    }
}
