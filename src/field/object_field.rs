//! One object's occupancy field: its flat parameters, its AdamW state, and batched evaluation.

use rand::Rng;
use rayon::prelude::*;

use super::adamw::AdamWState;
use super::layout::ParamLayout;
use super::occupancy::{Heads, OccupancyNet, OccupancyScratch};
use super::render::{RayRender, render_ray};
use super::samples::RaySamples;
use super::simd::Backend;
use crate::error::{CatmapError, Result};

/// Points per evaluation chunk.
const EVAL_CHUNK: usize = 256;

/// Hidden width of an object's field (vMAP `hidden_feature_size`).
pub const OBJECT_HIDDEN: usize = 32;
/// Hidden width of the background field (vMAP `hidden_feature_size_bg`).
pub const BACKGROUND_HIDDEN: usize = 128;

/// Occupancy and colour at a set of points.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FieldEval {
    /// Occupancy sigmoid(α), α = 10·raw, one per point.
    pub occupancy: Vec<f32>,
    /// Colour in [0, 1], one per point.
    pub colour: Vec<[f32; 3]>,
}

/// One object's (or the background's) occupancy field.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyField {
    hidden: usize,
    scale: f32,
    params: Vec<f32>,
    adam: AdamWState,
}

impl OccupancyField {
    /// A fresh field with `hidden` units and encoding scale `scale` (x' = x / scale), drawn from
    /// `rng` (seed it per object with [`crate::rng::seeded_rng`]).
    pub fn new(hidden: usize, scale: f32, rng: &mut impl Rng) -> Self {
        let params = ParamLayout::occupancy(hidden).init(rng);
        let adam = AdamWState::new(params.len());
        Self {
            hidden,
            scale,
            params,
            adam,
        }
    }

    /// A field with given flat parameters (in [`ParamLayout::occupancy`] order) and fresh
    /// optimiser state.
    pub fn from_params(hidden: usize, scale: f32, params: Vec<f32>) -> Result<Self> {
        let want = ParamLayout::occupancy(hidden).len();
        if params.len() != want {
            return Err(CatmapError::mismatch(
                format!("parameters of a field with H = {hidden}"),
                want,
                params.len(),
            ));
        }
        let adam = AdamWState::new(params.len());
        Ok(Self {
            hidden,
            scale,
            params,
            adam,
        })
    }

    /// Hidden width H.
    pub fn hidden(&self) -> usize {
        self.hidden
    }

    /// Encoding scale (x' = x / scale).
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// Flat parameters.
    pub fn params(&self) -> &[f32] {
        &self.params
    }

    /// Flat parameters, mutable (e.g. to load a checkpoint).
    pub fn params_mut(&mut self) -> &mut [f32] {
        &mut self.params
    }

    /// AdamW moments and step count.
    pub fn optimiser_state(&self) -> &AdamWState {
        &self.adam
    }

    /// Replaces the AdamW state (e.g. from a checkpoint); its moments must match the parameters.
    pub fn with_optimiser_state(mut self, adam: AdamWState) -> Result<Self> {
        if adam.m.len() != self.params.len() || adam.v.len() != self.params.len() {
            return Err(CatmapError::mismatch(
                "optimiser moments (m / v) of a field's parameters",
                self.params.len(),
                format!("{} / {}", adam.m.len(), adam.v.len()),
            ));
        }
        self.adam = adam;
        Ok(self)
    }

    /// Parameters and optimiser state together (for the batched update).
    pub(crate) fn params_and_state_mut(&mut self) -> (&mut [f32], &mut AdamWState) {
        (&mut self.params, &mut self.adam)
    }

    /// The parameter layout.
    pub fn layout(&self) -> ParamLayout {
        ParamLayout::occupancy(self.hidden)
    }

    /// The tensor called `name` (see [`ParamLayout`] for names).
    pub fn tensor(&self, name: &str) -> Option<&[f32]> {
        self.layout().get(name).map(|t| &self.params[t.range()])
    }

    /// Occupancy and colour at `points`, chunked and parallel.
    pub fn eval(&self, points: &[[f32; 3]]) -> FieldEval {
        let parts = self.eval_chunks(points, Heads::All, |net, s, n| {
            (net.occupancy(s, n).to_vec(), net.colour(s, n).to_vec())
        });
        let mut out = FieldEval::default();
        for (o, c) in parts {
            out.occupancy.extend(o);
            out.colour.extend(c);
        }
        out
    }

    /// Occupancy sigmoid(α) at `points` (geometry head only).
    pub fn eval_occupancy(&self, points: &[[f32; 3]]) -> Vec<f32> {
        self.eval_chunks(points, Heads::OccupancyOnly, |net, s, n| net.occupancy(s, n).to_vec())
            .concat()
    }

    /// α = 10·raw at `points`, for callers that apply their own activation (METHOD §3).
    pub fn eval_alpha(&self, points: &[[f32; 3]]) -> Vec<f32> {
        self.eval_chunks(points, Heads::OccupancyOnly, |net, s, n| net.alpha(s, n))
            .concat()
    }

    /// α at world `points` for a field whose coordinates start at `origin` (world − origin).
    pub fn eval_alpha_world(&self, origin: &nalgebra::Point3<f32>, points: &[nalgebra::Point3<f32>]) -> Vec<f32> {
        self.eval_alpha(&relative_to(origin, points))
    }

    /// Occupancy at world `points` for a field whose coordinates start at `origin`.
    pub fn eval_occupancy_world(&self, origin: &nalgebra::Point3<f32>, points: &[nalgebra::Point3<f32>]) -> Vec<f32> {
        self.eval_occupancy(&relative_to(origin, points))
    }

    /// Occupancy and colour at world `points` for a field whose coordinates start at `origin`.
    pub fn eval_world(&self, origin: &nalgebra::Point3<f32>, points: &[nalgebra::Point3<f32>]) -> FieldEval {
        self.eval(&relative_to(origin, points))
    }

    /// Renders each ray of `rays` (forward only).
    pub fn render_rays(&self, rays: &RaySamples) -> Result<Vec<RayRender>> {
        rays.validate()?;
        let spr = rays.samples_per_ray;
        let eval = self.eval(&rays.points);
        let mut weights = vec![0.0; spr];
        let mut trans = vec![0.0; spr];
        Ok((0..rays.num_rays())
            .map(|r| {
                let s = r * spr..(r + 1) * spr;
                render_ray(
                    &eval.occupancy[s.clone()],
                    &eval.colour[s.clone()],
                    &rays.z[s],
                    &mut weights,
                    &mut trans,
                )
            })
            .collect())
    }

    fn eval_chunks<T: Send>(
        &self,
        points: &[[f32; 3]],
        heads: Heads,
        take: impl Fn(&OccupancyNet, &OccupancyScratch, usize) -> T + Sync,
    ) -> Vec<T> {
        let net = OccupancyNet::new(self.hidden);
        let mut packed = vec![0.0; net.packed_len];
        net.pack(&self.params, &mut packed);
        let backend = Backend::detect();
        points
            .par_chunks(EVAL_CHUNK)
            .map_init(OccupancyScratch::default, |scratch, chunk| {
                net.forward(backend, &self.params, &packed, self.scale, chunk, scratch, heads);
                take(&net, scratch, chunk.len())
            })
            .collect()
    }
}

/// `points − origin` as plain arrays, the field's input.
fn relative_to(origin: &nalgebra::Point3<f32>, points: &[nalgebra::Point3<f32>]) -> Vec<[f32; 3]> {
    points.iter().map(|p| (p - origin.coords).coords.into()).collect()
}
