//! One (sub)category's field: shared weights, per-member codes, their AdamW states, evaluation.

use rand::Rng;
use rayon::prelude::*;

use super::super::adamw::AdamWState;
use super::super::layout::ParamLayout;
use super::super::object_field::FieldEval;
use super::super::occupancy::Heads;
use super::super::simd::Backend;
use super::CODE_REG_WEIGHT;
use super::member_codes::ShapeCodes;
use super::net::{CategoryNet, CategoryScratch, Membership};
use crate::error::{CatmapError, Result};
use crate::rng::standard_normal_f64 as standard_normal;

/// Points per evaluation chunk.
const EVAL_CHUNK: usize = 256;

/// One member's codes `[z_s ‖ z_t]` and their AdamW state.
#[derive(Debug, Clone, PartialEq)]
struct MemberCode {
    code: Vec<f32>,
    adam: AdamWState,
}

/// A category field: the network of [`ParamLayout::category`] and one code pair per member.
#[derive(Debug, Clone, PartialEq)]
pub struct CategoryField {
    hidden: usize,
    code_dim: usize,
    scale: f32,
    params: Vec<f32>,
    adam: AdamWState,
    members: Vec<MemberCode>,
    shape_codes: ShapeCodes,
}

impl CategoryField {
    /// A fresh field of width `hidden`, code dimension `code_dim` and encoding scale `scale`
    /// (x' = x / scale; NOCS points use 1.0) with `members` members, all drawn from `rng`.
    pub fn new(hidden: usize, code_dim: usize, scale: f32, members: usize, rng: &mut impl Rng) -> Self {
        let params = ParamLayout::category(hidden, code_dim).init(rng);
        let mut field = Self {
            hidden,
            code_dim,
            scale,
            adam: AdamWState::new(params.len()),
            params,
            members: Vec::new(),
            shape_codes: ShapeCodes::PerMember,
        };
        for _ in 0..members {
            field.add_member(rng);
        }
        field
    }

    /// A field with given flat weights (in [`ParamLayout::category`] order) and codes (one
    /// `[z_s ‖ z_t]` of 2·`code_dim` per member), with fresh optimiser states.
    pub fn from_params(
        hidden: usize,
        code_dim: usize,
        scale: f32,
        params: Vec<f32>,
        codes: Vec<Vec<f32>>,
    ) -> Result<Self> {
        let want = ParamLayout::category(hidden, code_dim).len();
        if params.len() != want {
            return Err(CatmapError::mismatch(
                format!("parameters of a category field with W = {hidden}, D = {code_dim}"),
                want,
                params.len(),
            ));
        }
        if let Some(bad) = codes.iter().find(|c| c.len() != 2 * code_dim) {
            return Err(CatmapError::mismatch("a member's code values", 2 * code_dim, bad.len()));
        }
        Ok(Self {
            hidden,
            code_dim,
            scale,
            adam: AdamWState::new(params.len()),
            params,
            members: codes
                .into_iter()
                .map(|code| MemberCode {
                    adam: AdamWState::new(code.len()),
                    code,
                })
                .collect(),
            shape_codes: ShapeCodes::PerMember,
        })
    }

    /// The field with its members' shapes as `shape_codes` says: shared zeroes every member's
    /// shape code (and every code added later).
    pub fn with_shape_codes(mut self, shape_codes: ShapeCodes) -> Self {
        self.shape_codes = shape_codes;
        for member in &mut self.members {
            shape_codes.fit(&mut member.code, self.code_dim);
        }
        self
    }

    /// Whose shape the field draws for a member.
    pub fn shape_codes(&self) -> ShapeCodes {
        self.shape_codes
    }

    /// Adds a member with codes drawn from N(0, 2/D) (CodeNeRF; its shape code zero when shapes
    /// are shared); returns its index. Other members' codes and optimiser states are untouched.
    pub fn add_member(&mut self, rng: &mut impl Rng) -> usize {
        let std = (2.0 / self.code_dim as f64).sqrt();
        let mut code: Vec<f32> = (0..2 * self.code_dim)
            .map(|_| (std * standard_normal(rng)) as f32)
            .collect();
        self.shape_codes.fit(&mut code, self.code_dim);
        self.members.push(MemberCode {
            adam: AdamWState::new(code.len()),
            code,
        });
        self.members.len() - 1
    }

    /// Rebuilds the member list: member `j` of the result is the current member `sources[j]`
    /// (its codes and their optimiser state moved), or a new member with fresh codes drawn from
    /// `rng` when `None`. The network and its optimiser state are untouched.
    pub fn remap_members(&mut self, sources: &[Option<usize>], rng: &mut impl Rng) -> Result<()> {
        if let Some(bad) = sources.iter().flatten().find(|&&j| j >= self.members.len()) {
            return Err(CatmapError::NoSuchIndex {
                what: "category member",
                index: *bad,
                len: self.members.len(),
            });
        }
        let mut old: Vec<Option<MemberCode>> = std::mem::take(&mut self.members).into_iter().map(Some).collect();
        for source in sources {
            match source.and_then(|j| old[j].take()) {
                Some(member) => self.members.push(member),
                None => {
                    self.add_member(rng);
                }
            }
        }
        Ok(())
    }

    /// Hidden width W.
    pub fn hidden(&self) -> usize {
        self.hidden
    }

    /// Dimension D of each code.
    pub fn code_dim(&self) -> usize {
        self.code_dim
    }

    /// Encoding scale (x' = x / scale).
    pub fn scale(&self) -> f32 {
        self.scale
    }

    /// Number of members.
    pub fn num_members(&self) -> usize {
        self.members.len()
    }

    /// The parameter layout of the network.
    pub fn layout(&self) -> ParamLayout {
        ParamLayout::category(self.hidden, self.code_dim)
    }

    /// Parameters of the network, codes excluded (18 179 at W = D = 32, as in the paper).
    pub fn param_count(&self) -> usize {
        self.params.len()
    }

    /// Parameters of one member's codes (2·D).
    pub fn code_param_count(&self) -> usize {
        2 * self.code_dim
    }

    /// Flat network parameters.
    pub fn params(&self) -> &[f32] {
        &self.params
    }

    /// Flat network parameters, mutable.
    pub fn params_mut(&mut self) -> &mut [f32] {
        &mut self.params
    }

    /// The tensor called `name` (see [`ParamLayout::category`]).
    pub fn tensor(&self, name: &str) -> Option<&[f32]> {
        self.layout().get(name).map(|t| &self.params[t.range()])
    }

    /// Member `member`'s codes `[z_s ‖ z_t]`.
    pub fn code(&self, member: usize) -> Option<&[f32]> {
        self.members.get(member).map(|m| m.code.as_slice())
    }

    /// Member `member`'s codes, mutable.
    pub fn code_mut(&mut self, member: usize) -> Option<&mut [f32]> {
        self.members.get_mut(member).map(|m| m.code.as_mut_slice())
    }

    /// Member `member`'s shape code z_s.
    pub fn shape_code(&self, member: usize) -> Option<&[f32]> {
        self.code(member).map(|c| &c[..self.code_dim])
    }

    /// Member `member`'s texture code z_t.
    pub fn texture_code(&self, member: usize) -> Option<&[f32]> {
        self.code(member).map(|c| &c[self.code_dim..])
    }

    /// Every member's codes, in member order.
    pub(crate) fn codes(&self) -> Vec<Vec<f32>> {
        self.members.iter().map(|m| m.code.clone()).collect()
    }

    /// AdamW state of the network.
    pub fn optimiser_state(&self) -> &AdamWState {
        &self.adam
    }

    /// AdamW state of member `member`'s codes.
    pub fn code_optimiser_state(&self, member: usize) -> Option<&AdamWState> {
        self.members.get(member).map(|m| &m.adam)
    }

    /// Replaces the AdamW states of the network and of every member's codes (e.g. from a
    /// checkpoint); every moment vector must match what it optimises.
    pub fn with_optimiser_states(mut self, adam: AdamWState, codes: Vec<AdamWState>) -> Result<Self> {
        let fits = |state: &AdamWState, len: usize| state.m.len() == len && state.v.len() == len;
        if !fits(&adam, self.params.len())
            || codes.len() != self.members.len()
            || self.members.iter().zip(&codes).any(|(m, s)| !fits(s, m.code.len()))
        {
            return Err(CatmapError::mismatch(
                "category optimiser states (network values; members)",
                format!("{}; {}", self.params.len(), self.members.len()),
                format!("{}; {}", adam.m.len(), codes.len()),
            ));
        }
        self.adam = adam;
        for (member, state) in self.members.iter_mut().zip(codes) {
            member.adam = state;
        }
        Ok(self)
    }

    /// The code regulariser [`CODE_REG_WEIGHT`] · Σ_members (‖z_s‖ + ‖z_t‖) and its gradient,
    /// one `[∂/∂z_s ‖ ∂/∂z_t]` per member (0 for a zero code).
    pub(crate) fn code_reg(&self) -> (f32, Vec<Vec<f32>>) {
        let d = self.code_dim;
        let mut total = 0.0;
        let grads = self
            .members
            .iter()
            .map(|m| {
                let mut g = vec![0.0; 2 * d];
                for (z, g) in m.code.chunks_exact(d).zip(g.chunks_exact_mut(d)) {
                    let norm = z.iter().map(|v| v * v).sum::<f32>().sqrt();
                    total += CODE_REG_WEIGHT * norm;
                    if norm > 0.0 {
                        for (g, z) in g.iter_mut().zip(z) {
                            *g = CODE_REG_WEIGHT * z / norm;
                        }
                    }
                }
                g
            })
            .collect();
        (total, grads)
    }

    /// Network parameters and state, and each member's codes and state (for the batched update).
    pub(crate) fn states_mut(&mut self) -> ((&mut [f32], &mut AdamWState), Vec<(&mut [f32], &mut AdamWState)>) {
        let codes = self
            .members
            .iter_mut()
            .map(|m| (m.code.as_mut_slice(), &mut m.adam))
            .collect();
        ((&mut self.params, &mut self.adam), codes)
    }

    /// Occupancy and colour of member `member` at `points_nocs`, chunked and parallel.
    pub fn eval(&self, member: usize, points_nocs: &[[f32; 3]]) -> Result<FieldEval> {
        let parts = self.eval_chunks(member, points_nocs, Heads::All, |net, s, n| {
            (net.occupancy(s, n).to_vec(), net.colour(s, n).to_vec())
        })?;
        let mut out = FieldEval::default();
        for (o, c) in parts {
            out.occupancy.extend(o);
            out.colour.extend(c);
        }
        Ok(out)
    }

    /// Occupancy sigmoid(α) of member `member` at `points_nocs` (geometry head only).
    pub fn eval_occupancy(&self, member: usize, points_nocs: &[[f32; 3]]) -> Result<Vec<f32>> {
        let parts = self.eval_chunks(member, points_nocs, Heads::OccupancyOnly, |net, s, n| {
            net.occupancy(s, n).to_vec()
        })?;
        Ok(parts.concat())
    }

    /// α = 10·raw of member `member` at `points_nocs`.
    pub fn eval_alpha(&self, member: usize, points_nocs: &[[f32; 3]]) -> Result<Vec<f32>> {
        let parts = self.eval_chunks(member, points_nocs, Heads::OccupancyOnly, |net, s, n| net.alpha(s, n))?;
        Ok(parts.concat())
    }

    fn eval_chunks<T: Send>(
        &self,
        member: usize,
        points: &[[f32; 3]],
        heads: Heads,
        take: impl Fn(&CategoryNet, &CategoryScratch, usize) -> T + Sync,
    ) -> Result<Vec<T>> {
        let code = self.code(member).ok_or(CatmapError::NoSuchIndex {
            what: "category member",
            index: member,
            len: self.num_members(),
        })?;
        let net = CategoryNet::new(self.hidden, self.code_dim);
        let mut packed = vec![0.0; net.packed_len];
        net.pack(&self.params, &mut packed);
        let mut table = Vec::new();
        net.code_table(&self.params, &[code.to_vec()], &mut table);
        let backend = Backend::detect();
        Ok(points
            .par_chunks(EVAL_CHUNK)
            .map_init(CategoryScratch::default, |scratch, chunk| {
                let members = Membership {
                    rays: &[0],
                    samples_per_ray: chunk.len(),
                };
                net.forward(
                    backend,
                    &self.params,
                    &packed,
                    &table,
                    self.scale,
                    chunk,
                    members,
                    scratch,
                    heads,
                );
                take(&net, scratch, chunk.len())
            })
            .collect())
    }
}

#[cfg(test)]
#[path = "model_tests.rs"]
mod tests;
