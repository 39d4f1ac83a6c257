//! Occupancy rendering of one ray (UNISURF-style, as vMAP's `render_rays.py`) and its backward.
//!
//! ```text
//! o_i = sigmoid(α_i)                      α_i = 10 · raw_i
//! T_i = ∏_{j<i} (1 − o_j + 1e-10)         w_i = o_i T_i
//! D̂ = Σ w_i z_i   Ĉ = Σ w_i c_i   Ô = Σ w_i   Var = Σ w_i (z_i − D̂)²   (Var: no gradient)
//! ```
//!
//! Backward, given g_i = ∂L/∂w_i, without dividing by (1 − o + 1e-10):
//! `∂L/∂o_k = T_k (g_k − U_k)` with `U_{S−1} = 0`, `U_k = g_{k+1} o_{k+1} + (1 − o_{k+1} + 1e-10) U_{k+1}`.

/// Added to every free-space probability, as in vMAP (keeps the product from vanishing).
pub const FREE_EPS: f32 = 1e-10;

/// What one ray renders.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RayRender {
    /// Expected termination depth D̂ (same unit as the sample depths).
    pub depth: f32,
    /// Expected colour Ĉ.
    pub colour: [f32; 3],
    /// Rendered opacity Ô = Σ w.
    pub opacity: f32,
    /// Depth variance Var = Σ w (z − D̂)².
    pub variance: f32,
}

/// Gradients of the loss with respect to one ray's rendered values.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RenderGrad {
    /// ∂L/∂D̂.
    pub depth: f32,
    /// ∂L/∂Ĉ.
    pub colour: [f32; 3],
    /// ∂L/∂Ô.
    pub opacity: f32,
}

/// The logistic function, 1 / (1 + e^(−x)).
#[inline]
pub fn sigmoid(x: f32) -> f32 {
    1.0 / (1.0 + (-x).exp())
}

/// Renders one ray from its samples' occupancies `occ` (o_i), colours and depths `z`.
/// Writes the termination weights w_i into `weights` and the transmittances T_i into `trans`.
pub fn render_ray(occ: &[f32], colour: &[[f32; 3]], z: &[f32], weights: &mut [f32], trans: &mut [f32]) -> RayRender {
    let mut t = 1.0f32;
    let mut out = RayRender::default();
    for i in 0..occ.len() {
        trans[i] = t;
        let w = occ[i] * t;
        weights[i] = w;
        t *= (1.0 - occ[i]) + FREE_EPS;
        out.depth += w * z[i];
        for (acc, c) in out.colour.iter_mut().zip(colour[i]) {
            *acc += w * c;
        }
        out.opacity += w;
    }
    out.variance = weights
        .iter()
        .zip(z)
        .map(|(w, zi)| w * (zi - out.depth) * (zi - out.depth))
        .sum();
    out
}

/// Backward of [`render_ray`]: writes ∂L/∂o_i into `d_occ` and ∂L/∂c_i into `d_colour`.
pub fn render_ray_backward(
    grad: &RenderGrad,
    occ: &[f32],
    colour: &[[f32; 3]],
    z: &[f32],
    weights: &[f32],
    trans: &[f32],
    d_occ: &mut [f32],
    d_colour: &mut [[f32; 3]],
) {
    let g_w = |i: usize| -> f32 {
        grad.depth * z[i]
            + grad.colour[0] * colour[i][0]
            + grad.colour[1] * colour[i][1]
            + grad.colour[2] * colour[i][2]
            + grad.opacity
    };
    let mut u = 0.0f32;
    for k in (0..occ.len()).rev() {
        let gk = g_w(k);
        d_occ[k] = trans[k] * (gk - u);
        d_colour[k] = grad.colour.map(|g| g * weights[k]);
        u = gk * occ[k] + ((1.0 - occ[k]) + FREE_EPS) * u;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn loss(occ: &[f32], colour: &[[f32; 3]], z: &[f32], g: &RenderGrad) -> f64 {
        let n = occ.len();
        let r = render_ray(occ, colour, z, &mut vec![0.0; n], &mut vec![0.0; n]);
        f64::from(g.depth * r.depth + g.opacity * r.opacity)
            + (0..3).map(|c| f64::from(g.colour[c] * r.colour[c])).sum::<f64>()
    }

    #[test]
    fn an_opaque_first_sample_takes_all_the_weight() {
        let occ = [1.0, 0.7, 0.2];
        let colour = [[0.1, 0.2, 0.3], [0.9, 0.9, 0.9], [0.5, 0.5, 0.5]];
        let z = [1.0, 2.0, 3.0];
        let r = render_ray(&occ, &colour, &z, &mut [0.0; 3], &mut [0.0; 3]);
        assert!((r.depth - 1.0).abs() < 1e-6 && (r.opacity - 1.0).abs() < 1e-6, "{r:?}");
        assert!((r.colour[2] - 0.3).abs() < 1e-6 && r.variance < 1e-6, "{r:?}");
    }

    #[test]
    fn golden_two_sample_ray() {
        // w = [0.5, 0.5·0.5] → D̂ = 0.5·1 + 0.25·3 = 1.25, Ô = 0.75, Var = 0.5·0.0625 + 0.25·3.0625.
        let r = render_ray(
            &[0.5, 0.5],
            &[[0.0; 3], [1.0; 3]],
            &[1.0, 3.0],
            &mut [0.0; 2],
            &mut [0.0; 2],
        );
        assert!((r.depth - 1.25).abs() < 1e-6 && (r.opacity - 0.75).abs() < 1e-6);
        assert!((r.variance - 0.796_875).abs() < 1e-6 && (r.colour[0] - 0.25).abs() < 1e-6);
    }

    #[test]
    fn backward_matches_finite_differences() {
        let occ = [0.3f32, 0.6, 0.2, 0.9, 0.4];
        let colour = [
            [0.1, 0.5, 0.9],
            [0.3, 0.2, 0.1],
            [0.8, 0.8, 0.2],
            [0.4, 0.6, 0.1],
            [0.2, 0.9, 0.7],
        ];
        let z = [0.5f32, 1.0, 1.5, 2.0, 2.5];
        let g = RenderGrad {
            depth: 0.7,
            colour: [-0.3, 0.5, 0.2],
            opacity: -1.1,
        };
        let (mut w, mut t) = ([0.0; 5], [0.0; 5]);
        render_ray(&occ, &colour, &z, &mut w, &mut t);
        let (mut d_occ, mut d_col) = ([0.0; 5], [[0.0; 3]; 5]);
        render_ray_backward(&g, &occ, &colour, &z, &w, &t, &mut d_occ, &mut d_col);
        let h = 1e-3f32;
        for k in 0..5 {
            let (mut up, mut down) = (occ, occ);
            up[k] += h;
            down[k] -= h;
            let fd = (loss(&up, &colour, &z, &g) - loss(&down, &colour, &z, &g)) / (2.0 * f64::from(h));
            assert!(
                (fd - f64::from(d_occ[k])).abs() < 1e-3,
                "∂L/∂o_{k}: {fd} vs {}",
                d_occ[k]
            );
            for c in 0..3 {
                let (mut up, mut down) = (colour, colour);
                up[k][c] += h;
                down[k][c] -= h;
                let fd = (loss(&occ, &up, &z, &g) - loss(&occ, &down, &z, &g)) / (2.0 * f64::from(h));
                assert!((fd - f64::from(d_col[k][c])).abs() < 1e-3, "∂L/∂c_{k}{c}");
            }
        }
    }
}
