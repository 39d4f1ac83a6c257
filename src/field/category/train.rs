//! The fused training pass of the category network on one chunk: forward, render, loss,
//! backward, with each member's ∂L/∂c summed into the `dc` tail of the gradient buffer.

use super::super::dense::Rows;
use super::super::encoding::{self, COL_DIMS, EMB_LD, GEO_DIMS};
use super::super::gemm::{Init, Post, padded};
use super::super::heads::{HEAD_LD, HeadBuffers};
use super::super::loss::{FieldLosses, LossNorm};
use super::super::occupancy::Heads;
use super::super::simd::Backend;
use super::CategorySamples;
use super::net::{CAT, CategoryNet, CategoryScratch, Membership, SHAPE_1, SHAPE_2, TEXTURE, encoding_rows};

/// The read-only inputs of one category's chunks in a step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ChunkInputs<'a> {
    /// Canonical weights.
    pub params: &'a [f32],
    /// Packed weights.
    pub packed: &'a [f32],
    /// Code table of the step.
    pub table: &'a [f32],
    /// Encoding scale.
    pub scale: f32,
    /// The category's samples.
    pub samples: &'a CategorySamples,
    /// Reciprocal mask counts over all the category's rays.
    pub norm: &'a LossNorm,
}

impl CategoryNet {
    /// One fused training pass over rays `rays` of `input.samples`. Returns this chunk's share
    /// of the losses; adds packed gradients to `grad[..grad_len]` and each member's ∂L/∂c to
    /// the table-shaped tail `grad[grad_len..]`.
    pub(crate) fn train_chunk(
        &self,
        backend: Backend,
        input: ChunkInputs<'_>,
        rays: std::ops::Range<usize>,
        s: &mut CategoryScratch,
        grad: &mut [f32],
    ) -> FieldLosses {
        let samples = &input.samples.rays;
        let spr = samples.samples_per_ray;
        let range = rays.start * spr..rays.end * spr;
        let n = range.len();
        let (hp, hh) = (self.hp(), padded(self.hidden / 2));
        let members = Membership {
            rays: &input.samples.members[rays.clone()],
            samples_per_ray: spr,
        };
        let (params, packed) = (input.params, input.packed);
        let points = &samples.points[range];
        let nc = HeadBuffers::colour_prefix(samples, rays.clone());
        self.forward(
            backend,
            params,
            packed,
            input.table,
            input.scale,
            points,
            members,
            s,
            Heads::ColourOfFirst(nc),
        );
        let losses = s.heads.render_loss_backward(samples, rays, input.norm);

        // Backward through the network, colour head first.
        let (grad, dc) = grad.split_at_mut(self.grad_len);
        let [l_xyz, l_s1, l_cat, l_s2, l_enc, l_sigma, l_view, l_t1, l_rgb0, l_rgb2] = &self.layers;
        let [y0, y0c, y1, y1c, y2, y2c, y3, y4, y5, y5c, y6, y7] = &s.h;
        let geo = Rows::new(&s.emb, EMB_LD);
        let col = Rows::new(&s.emb[GEO_DIMS..], EMB_LD);
        let (p, q) = (&mut s.p, &mut s.q);
        let (gp, cp) = (padded(GEO_DIMS), padded(COL_DIMS));
        let d_colour = Rows::new(&s.heads.d_colour, HEAD_LD);
        let d_alpha = Rows::new(&s.heads.d_alpha, HEAD_LD);
        let code_grad = |d: &mut [f32], y: &[f32], slot: usize, rows: usize, dc: &mut [f32]| {
            self.code_grad_and_mask(backend, d, y, slot, rows, members, dc);
        };
        // The colour branch runs on the first nc samples only (their colour gradients are the
        // only non-zero ones). rgb.2 → p = d(y7 pre), width W/2.
        l_rgb2.backward_weights(backend, nc, &[Rows::new(y7, hh)], d_colour, grad);
        let post = Post::Mask { data: y7, ld: hh };
        l_rgb2.backward_input(backend, packed, nc, 0, d_colour, p, hh, Init::Zero, post);
        // rgb.0 → q = d(y6 pre).
        l_rgb0.backward_weights(backend, nc, &[Rows::new(y6, hp)], Rows::new(p, hh), grad);
        l_rgb0.backward_input(
            backend,
            packed,
            nc,
            0,
            Rows::new(p, hh),
            q,
            hp,
            Init::Zero,
            Post::Mask { data: y6, ld: hp },
        );
        // texture_layer_1 → p = d(y5 + c_t) → dc_t, then d(y5 pre).
        l_t1.backward_weights(backend, nc, &[Rows::new(y5c, hp)], Rows::new(q, hp), grad);
        l_t1.backward_input(
            backend,
            packed,
            nc,
            0,
            Rows::new(q, hp),
            p,
            hp,
            Init::Zero,
            Post::Identity,
        );
        code_grad(p, y5, TEXTURE, nc, dc);
        // encoding_viewdir → q = dy4 (from colour), d_col.
        l_view.backward_weights(backend, nc, &[Rows::new(y4, hp), col], Rows::new(p, hp), grad);
        l_view.backward_input(
            backend,
            packed,
            nc,
            0,
            Rows::new(p, hp),
            q,
            hp,
            Init::Zero,
            Post::Identity,
        );
        q[nc * hp..n * hp].fill(0.0);
        let d_col = &mut s.d_col;
        l_view.backward_input(
            backend,
            packed,
            nc,
            1,
            Rows::new(p, hp),
            d_col,
            cp,
            Init::Zero,
            Post::Identity,
        );
        d_col[nc * cp..n * cp].fill(0.0);
        // sigma → q += dy4 (from α); y4 is linear.
        l_sigma.backward_weights(backend, n, &[Rows::new(y4, hp)], d_alpha, grad);
        l_sigma.backward_input(backend, packed, n, 0, d_alpha, q, hp, Init::Accumulate, Post::Identity);
        // encoding_shape → p = d(y3 pre).
        l_enc.backward_weights(backend, n, &[Rows::new(y3, hp)], Rows::new(q, hp), grad);
        l_enc.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(q, hp),
            p,
            hp,
            Init::Zero,
            Post::Mask { data: y3, ld: hp },
        );
        // shape_layer_2 → q = d(y2 + c) → dc, then d(y2 pre).
        l_s2.backward_weights(backend, n, &[Rows::new(y2c, hp)], Rows::new(p, hp), grad);
        l_s2.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(p, hp),
            q,
            hp,
            Init::Zero,
            Post::Identity,
        );
        code_grad(q, y2, SHAPE_2, n, dc);
        // cat_layer → p = d(y1 + c) → dc, then d(y1 pre); d_geo.
        l_cat.backward_weights(backend, n, &[Rows::new(y1c, hp), geo], Rows::new(q, hp), grad);
        l_cat.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(q, hp),
            p,
            hp,
            Init::Zero,
            Post::Identity,
        );
        let d_geo = &mut s.d_geo;
        l_cat.backward_input(
            backend,
            packed,
            n,
            1,
            Rows::new(q, hp),
            d_geo,
            gp,
            Init::Zero,
            Post::Identity,
        );
        code_grad(p, y1, CAT, n, dc);
        // shape_layer_1 → q = d(y0 + c) → dc, then d(y0 pre).
        l_s1.backward_weights(backend, n, &[Rows::new(y0c, hp)], Rows::new(p, hp), grad);
        l_s1.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(p, hp),
            q,
            hp,
            Init::Zero,
            Post::Identity,
        );
        code_grad(q, y0, SHAPE_1, n, dc);
        // encoding_xyz → d_geo += ….
        l_xyz.backward_weights(backend, n, &[geo], Rows::new(q, hp), grad);
        let d_geo = &mut s.d_geo;
        l_xyz.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(q, hp),
            d_geo,
            gp,
            Init::Accumulate,
            Post::Identity,
        );
        let gb = &mut grad[self.b_grad..self.b_grad + 3 * encoding_rows()];
        encoding::backward_chunk(backend, &s.emb, &s.dsin, &s.d_geo, gp, &s.d_col, cp, n, gb);
        losses
    }

    /// `d` holds ∂L/∂(y + c) row by row: adds each row to its member's `dc[slot]`, then keeps
    /// it only where `y` (post-ReLU) is positive, giving ∂L/∂(y's pre-activation). Runs with
    /// `backend`'s instructions (the loop is element-wise, so every lane width gives the same
    /// bits; in baseline x86-64 code it took a seventh of a category run's time).
    fn code_grad_and_mask(
        &self,
        backend: Backend,
        d: &mut [f32],
        y: &[f32],
        slot: usize,
        n: usize,
        members: Membership<'_>,
        dc: &mut [f32],
    ) {
        struct CodeGradAndMask<'a> {
            d: &'a mut [f32],
            y: &'a [f32],
            dc: &'a mut [f32],
            rows: usize,
            hp: usize,
            offset_of_row: &'a dyn Fn(usize) -> usize,
        }
        impl pulp::WithSimd for CodeGradAndMask<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: pulp::Simd>(self, _simd: S) {
                let hp = self.hp;
                for s in 0..self.rows {
                    let acc = &mut self.dc[(self.offset_of_row)(s)..][..hp];
                    let row = &mut self.d[s * hp..(s + 1) * hp];
                    let y = &self.y[s * hp..(s + 1) * hp];
                    for ((a, g), &y) in acc.iter_mut().zip(row.iter_mut()).zip(y) {
                        *a += *g;
                        *g = if y <= 0.0 { 0.0 } else { *g };
                    }
                }
            }
        }
        let hp = self.hp();
        let offset_of_row = |s: usize| members.of(s) * self.table_row() + slot * hp;
        backend.dispatch(CodeGradAndMask {
            d,
            y,
            dc,
            rows: n,
            hp,
            offset_of_row: &offset_of_row,
        });
    }
}
