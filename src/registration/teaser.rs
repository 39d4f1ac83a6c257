//! The TEASER++ back end without scale: consistency graph → maximum clique → GNC-TLS rotation
//! over the clique's translation-invariant measurements → component-wise scalar TLS translation.
//!
//! With the clique's correspondences (a_k, b_k), k = c_0 … c_{s−1}, the translation-invariant
//! measurements are the consecutive differences ā_k = a_{k+1} − a_k, b̄_k = b_{k+1} − b_k, which
//! satisfy b̄_k = R ā_k up to 2ε. Given R, each translation component is the scalar TLS estimate
//! of t_k = (b_k − R a_k)_x (resp. y, z) with bound ε.

use nalgebra::{Point3, Rotation3, Vector3};

use super::RegistrationConfig;
use super::consistency::{Correspondence, consistency_graph};
use super::gnc_tls::{GncParams, gnc_tls_rotation};
use super::max_clique::maximum_clique;
use super::scalar_tls::scalar_tls;
use crate::error::{CatmapError, Result};

/// A rigid estimate `template ≈ rotation · source + translation`, with diagnostics.
#[derive(Debug, Clone, PartialEq)]
pub struct RobustEstimate {
    /// Rotation of template_from_source.
    pub rotation: Rotation3<f64>,
    /// Translation of template_from_source, metres.
    pub translation: Vector3<f64>,
    /// Correspondences given to the back end.
    pub correspondences: usize,
    /// Size of the maximum clique.
    pub clique_size: usize,
    /// Whether the clique is proven maximum (the search stayed within its budget).
    pub clique_proven_maximum: bool,
    /// Clique correspondences that are inliers of the rotation and of all three translation axes.
    pub inliers: usize,
}

/// Robust rigid registration of `source` to `template` from putative `correspondences`.
/// Errors when the maximum clique has fewer than 3 correspondences.
pub fn robust_registration(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    correspondences: &[Correspondence],
    cfg: &RegistrationConfig,
) -> Result<RobustEstimate> {
    let graph = consistency_graph(source, template, correspondences, cfg.noise_bound_m);
    let clique = maximum_clique(&graph, cfg.max_clique_nodes);
    if clique.vertices.len() < 3 {
        return Err(CatmapError::too_few(
            format!(
                "mutually consistent correspondences (the largest set of {})",
                correspondences.len()
            ),
            3,
            clique.vertices.len(),
        ));
    }
    let a: Vec<Vector3<f64>> = clique
        .vertices
        .iter()
        .map(|&k| source[correspondences[k as usize].0 as usize].coords.cast())
        .collect();
    let b: Vec<Vector3<f64>> = clique
        .vertices
        .iter()
        .map(|&k| template[correspondences[k as usize].1 as usize].coords.cast())
        .collect();
    let differences = |v: &[Vector3<f64>]| -> Vec<Vector3<f64>> { v.windows(2).map(|w| w[1] - w[0]).collect() };
    let noise_bound = f64::from(cfg.noise_bound_m);
    let rotation = gnc_tls_rotation(
        &differences(&a),
        &differences(&b),
        &GncParams {
            noise_bound: 2.0 * noise_bound,
            gnc_factor: cfg.gnc_factor,
            max_iterations: cfg.gnc_max_iterations,
            cost_threshold: cfg.gnc_cost_threshold,
        },
    )
    .rotation;
    let offsets: Vec<Vector3<f64>> = a.iter().zip(&b).map(|(ai, bi)| bi - rotation * ai).collect();
    let bounds = vec![noise_bound; offsets.len()];
    let mut translation = Vector3::zeros();
    let mut inlier = vec![true; offsets.len()];
    for axis in 0..3 {
        let component: Vec<f64> = offsets.iter().map(|o| o[axis]).collect();
        let fit = scalar_tls(&component, &bounds).expect("a clique of 3 or more gives measurements");
        translation[axis] = fit.estimate;
        for (keep, ok) in inlier.iter_mut().zip(fit.inliers) {
            *keep &= ok;
        }
    }
    Ok(RobustEstimate {
        rotation,
        translation,
        correspondences: correspondences.len(),
        clique_size: clique.vertices.len(),
        clique_proven_maximum: clique.proven_maximum,
        inliers: inlier.iter().filter(|&&i| i).count(),
    })
}

#[cfg(test)]
mod tests {
    use crate::registration::horn::rotation_angle_between;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::registration::consistency::all_to_all_pairs;

    #[test]
    fn all_to_all_pairs_recover_a_rigid_motion_of_a_random_cloud() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let source: Vec<Point3<f32>> = (0..40)
            .map(|_| {
                Point3::new(
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-0.5..0.5),
                    rng.random_range(-0.5..0.5),
                )
            })
            .collect();
        let truth = Rotation3::from_euler_angles(2.5, -0.3, 1.9);
        let shift = Vector3::new(0.3, -0.7, 0.2);
        let template: Vec<Point3<f32>> = source
            .iter()
            .map(|p| truth.cast::<f32>() * p + shift.cast::<f32>())
            .collect();
        let pairs = all_to_all_pairs(source.len(), template.len(), 10_000, &mut rng);
        let estimate =
            robust_registration(&source, &template, &pairs, &RegistrationConfig::default()).expect("solvable");
        assert!(
            rotation_angle_between(&estimate.rotation, &truth) < 1e-3,
            "rotation off by {}",
            rotation_angle_between(&estimate.rotation, &truth)
        );
        assert!(
            (estimate.translation - shift).norm() < 1e-3,
            "translation {:?}",
            estimate.translation
        );
        assert_eq!(estimate.clique_size, 40, "every true match is in the clique");
    }

    #[test]
    fn two_correspondences_are_not_enough() {
        let points = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let err = robust_registration(&points, &points, &[(0, 0), (1, 1)], &RegistrationConfig::default())
            .expect_err("a pair of points fixes no rotation");
        assert!(
            matches!(
                err,
                CatmapError::TooFew {
                    needed: 3,
                    found: 2,
                    ..
                }
            ),
            "{err}"
        );
    }
}
