//! Rotation by graduated non-convexity with a truncated least squares cost (GNC-TLS; Yang,
//! Antonante, Tzoumas, Carlone, RA-L 2020), as TEASER++ solves its rotation subproblem.
//!
//! Cost: min_R Σ_i min(r_i², ε²) with r_i = |b_i − R a_i| and ε the bound on an inlier's
//! residual. GNC replaces it by a surrogate with control parameter μ, starting near the convex
//! least-squares problem and growing μ by `gnc_factor` each iteration until it is the TLS cost.
//! Each iteration alternates
//! 1. R = argmin Σ w_i r_i² (weighted Horn/SVD, [`weighted_rotation`]), and
//! 2. the weights in closed form, with θ₁ = (μ+1)/μ·ε², θ₂ = μ/(μ+1)·ε²:
//!    w_i = 1 if r_i² ≤ θ₂, 0 if r_i² ≥ θ₁, else ε·√(μ(μ+1))/r_i − μ.
//!
//! μ starts at ε² / (2·max r_i² − ε²) for the least-squares residuals; a non-positive start
//! means every residual is already an inlier and least squares is the answer.

use nalgebra::{Rotation3, Vector3};

use super::horn::weighted_rotation;

/// Parameters of [`gnc_tls_rotation`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GncParams {
    /// Bound ε on an inlier's residual |b_i − R a_i|.
    pub noise_bound: f64,
    /// Factor μ grows by per iteration (TEASER++: 1.4).
    pub gnc_factor: f64,
    /// Most iterations.
    pub max_iterations: usize,
    /// Stop when the weighted cost Σ w_i r_i² changes by less than this.
    pub cost_threshold: f64,
}

/// Outcome of [`gnc_tls_rotation`].
#[derive(Debug, Clone, PartialEq)]
pub struct GncRotation {
    /// The rotation, b ≈ R a.
    pub rotation: Rotation3<f64>,
    /// Per measurement: residual within ε under `rotation`.
    pub inliers: Vec<bool>,
    /// Weighted solves run after the initial least-squares one.
    pub iterations: usize,
}

/// min_R Σ min(|b_i − R a_i|², ε²) by GNC-TLS. Identity for no measurements.
pub fn gnc_tls_rotation(a: &[Vector3<f64>], b: &[Vector3<f64>], params: &GncParams) -> GncRotation {
    debug_assert_eq!(a.len(), b.len(), "one b per a");
    let eps2 = (params.noise_bound * params.noise_bound).max(1e-16);
    let residuals =
        |r: &Rotation3<f64>| -> Vec<f64> { a.iter().zip(b).map(|(ai, bi)| (bi - r * ai).norm_squared()).collect() };
    let mut weights = vec![1.0; a.len()];
    let mut rotation = weighted_rotation(a, b, &weights);
    let mut r2 = residuals(&rotation);
    let max_r2 = r2.iter().copied().fold(0.0, f64::max);
    let mut mu = 1.0 / (2.0 * max_r2 / eps2 - 1.0);
    let mut iterations = 0;
    if mu > 0.0 {
        let mut previous_cost = f64::INFINITY;
        while iterations < params.max_iterations {
            let (theta1, theta2) = ((mu + 1.0) / mu * eps2, mu / (mu + 1.0) * eps2);
            for (w, &r) in weights.iter_mut().zip(&r2) {
                *w = if r >= theta1 {
                    0.0
                } else if r <= theta2 {
                    1.0
                } else {
                    (eps2 * mu * (mu + 1.0) / r).sqrt() - mu
                };
            }
            rotation = weighted_rotation(a, b, &weights);
            r2 = residuals(&rotation);
            iterations += 1;
            let cost: f64 = weights.iter().zip(&r2).map(|(w, r)| w * r).sum();
            if (cost - previous_cost).abs() < params.cost_threshold {
                break;
            }
            previous_cost = cost;
            mu *= params.gnc_factor;
        }
    }
    let inliers = r2.iter().map(|&r| r <= eps2).collect();
    GncRotation {
        rotation,
        inliers,
        iterations,
    }
}

#[cfg(test)]
mod tests {
    use crate::registration::horn::rotation_angle_between;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    fn params() -> GncParams {
        GncParams {
            noise_bound: 0.01,
            gnc_factor: 1.4,
            max_iterations: 100,
            cost_threshold: 1e-12,
        }
    }

    fn random_unit_vectors(count: usize, rng: &mut ChaCha8Rng) -> Vec<Vector3<f64>> {
        (0..count)
            .map(|_| {
                Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
            })
            .collect()
    }

    #[test]
    fn exact_data_gives_the_rotation_in_closed_form() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let truth = Rotation3::from_euler_angles(2.0, -0.7, 1.1);
        let a = random_unit_vectors(20, &mut rng);
        let b: Vec<_> = a.iter().map(|x| truth * x).collect();
        let estimate = gnc_tls_rotation(&a, &b, &params());
        assert!(
            rotation_angle_between(&estimate.rotation, &truth) < 1e-9,
            "exact data is fitted exactly"
        );
        assert!(estimate.inliers.iter().all(|&i| i), "every measurement is an inlier");
    }

    #[test]
    fn forty_percent_outliers_are_rejected() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let truth = Rotation3::from_euler_angles(-0.4, 1.3, 3.0);
        let a = random_unit_vectors(50, &mut rng);
        let outliers = random_unit_vectors(50, &mut rng);
        let b: Vec<_> = (0..50)
            .map(|i| if i % 5 < 2 { outliers[i] * 2.0 } else { truth * a[i] })
            .collect();
        let estimate = gnc_tls_rotation(&a, &b, &params());
        assert!(
            rotation_angle_between(&estimate.rotation, &truth) < 1e-6,
            "outliers get zero weight"
        );
        let expected: Vec<bool> = (0..50).map(|i| i % 5 >= 2).collect();
        assert_eq!(estimate.inliers, expected, "exactly the clean measurements are inliers");
    }
}
