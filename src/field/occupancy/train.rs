//! The fused training pass of the occupancy MLP on one chunk: forward, render, loss, backward.

use super::super::dense::Rows;
use super::super::encoding::{self, COL_DIMS, EMB_LD, GEO_DIMS};
use super::super::gemm::{Init, Post, padded};
use super::super::heads::{HEAD_LD, HeadBuffers};
use super::super::loss::{FieldLosses, LossNorm};
use super::super::samples::RaySamples;
use super::super::simd::Backend;
use super::{Heads, OccupancyNet, OccupancyScratch, encoding_rows};

impl OccupancyNet {
    /// One fused training pass over rays `rays_range` of `rays`: forward, render, loss and
    /// backward. Returns this chunk's share of the losses; gradients are added to `grad`.
    pub(crate) fn train_chunk(
        &self,
        backend: Backend,
        params: &[f32],
        packed: &[f32],
        scale: f32,
        rays: &RaySamples,
        rays_range: std::ops::Range<usize>,
        norm: &LossNorm,
        s: &mut OccupancyScratch,
        grad: &mut [f32],
    ) -> FieldLosses {
        let spr = rays.samples_per_ray;
        let samples = rays_range.start * spr..rays_range.end * spr;
        let n = samples.len();
        let hp = self.hp();
        let nc = HeadBuffers::colour_prefix(rays, rays_range.clone());
        let heads = Heads::ColourOfFirst(nc);
        self.forward(backend, params, packed, scale, &rays.points[samples], s, heads);
        let losses = s.heads.render_loss_backward(rays, rays_range, norm);

        // Backward through the MLP, heads first.
        let [l1, l2, l3, l4, la, l5, lc] = &self.layers;
        let [h1, h2, h3, h4, h5] = &s.h;
        let geo = Rows {
            data: &s.emb,
            ld: EMB_LD,
        };
        let col = Rows {
            data: &s.emb[GEO_DIMS..],
            ld: EMB_LD,
        };
        let (p, q) = (&mut s.p, &mut s.q);
        let (gp, cp) = (padded(GEO_DIMS), padded(COL_DIMS));
        let d_colour = Rows {
            data: &s.heads.d_colour,
            ld: HEAD_LD,
        };
        let d_alpha = Rows {
            data: &s.heads.d_alpha,
            ld: HEAD_LD,
        };
        // out_color: p = d(h5 pre-activation); the colour branch runs on the first nc samples
        // only (their colour gradients are the only non-zero ones).
        lc.backward_weights(backend, nc, &[Rows::new(h5, hp)], d_colour, grad);
        lc.backward_input(
            backend,
            packed,
            nc,
            0,
            d_colour,
            p,
            hp,
            Init::Zero,
            Post::Mask { data: h5, ld: hp },
        );
        // color_linear: q = dh4 (from colour), d_col
        l5.backward_weights(backend, nc, &[Rows::new(h4, hp), col], Rows::new(p, hp), grad);
        l5.backward_input(
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
        l5.backward_input(
            backend,
            packed,
            nc,
            1,
            Rows::new(p, hp),
            &mut s.d_col,
            cp,
            Init::Zero,
            Post::Identity,
        );
        s.d_col[nc * cp..n * cp].fill(0.0);
        // out_alpha: q = d(h4 pre-activation)
        la.backward_weights(backend, n, &[Rows::new(h4, hp)], d_alpha, grad);
        la.backward_input(
            backend,
            packed,
            n,
            0,
            d_alpha,
            q,
            hp,
            Init::Accumulate,
            Post::Mask { data: h4, ld: hp },
        );
        // mid2: p = d(h3 pre)
        l4.backward_weights(backend, n, &[Rows::new(h3, hp)], Rows::new(q, hp), grad);
        l4.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(q, hp),
            p,
            hp,
            Init::Zero,
            Post::Mask { data: h3, ld: hp },
        );
        // cat_layer: q = d(h2 pre), d_geo
        l3.backward_weights(backend, n, &[Rows::new(h2, hp), geo], Rows::new(p, hp), grad);
        l3.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(p, hp),
            q,
            hp,
            Init::Zero,
            Post::Mask { data: h2, ld: hp },
        );
        l3.backward_input(
            backend,
            packed,
            n,
            1,
            Rows::new(p, hp),
            &mut s.d_geo,
            gp,
            Init::Zero,
            Post::Identity,
        );
        // mid1: p = d(h1 pre)
        l2.backward_weights(backend, n, &[Rows::new(h1, hp)], Rows::new(q, hp), grad);
        l2.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(q, hp),
            p,
            hp,
            Init::Zero,
            Post::Mask { data: h1, ld: hp },
        );
        // in_layer: d_geo += …
        l1.backward_weights(backend, n, &[geo], Rows::new(p, hp), grad);
        l1.backward_input(
            backend,
            packed,
            n,
            0,
            Rows::new(p, hp),
            &mut s.d_geo,
            gp,
            Init::Accumulate,
            Post::Identity,
        );
        let gb = &mut grad[self.b_grad..self.b_grad + 3 * encoding_rows()];
        encoding::backward_chunk(backend, &s.emb, &s.dsin, &s.d_geo, gp, &s.d_col, cp, n, gb);
        losses
    }
}
