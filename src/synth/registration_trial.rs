//! [`RegistrationTrial`]: a partial, noisy, outlier-laden view of a furniture design posed at
//! random, with the design's full surface as the template — the registration test case of the
//! category-registration issue.
//!
//! From one seed: `template_points` uniform samples of the design's surface (object frame);
//! `source_points` further samples, cut as one view would see them: toward a camera direction d
//! (elevation 0…60°, any azimuth) the fraction f ∈ [`RegistrationTrialSpec::visible`] of the
//! samples whose surface normals face d the most (largest n·d; f = ½ is back-face culling of a
//! closed surface; self-occlusion is not modelled), perturbed by isotropic
//! Gaussian noise σ, joined by outliers (a fraction of the final cloud, uniform in the cut's box
//! enlarged by 10 %), then moved by a uniformly random rotation (any axis, upside down included)
//! and a translation uniform in a ball of radius `max_translation_m`. The truth is
//! template_from_source, the inverse of that motion.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::furniture::Design;
use crate::error::Result;
use crate::geometry::mesh::Aabb;
use crate::geometry::nearest::PointIndex;
use crate::registration::Rotations;
use crate::rng::standard_normal_f32;

/// Samples of the dense surface [`RegistrationTrial::aligned_cloud_distance`] measures against.
const DENSE_REFERENCE_POINTS: usize = 100_000;

/// How a [`RegistrationTrial`] is drawn.
#[derive(Debug, Clone, PartialEq)]
pub struct RegistrationTrialSpec {
    /// Samples of the full surface (the template).
    pub template_points: usize,
    /// Samples of the surface before the cut (the source keeps a fraction of them).
    pub source_points: usize,
    /// Range of the visible fraction of the source's surface samples.
    pub visible: (f32, f32),
    /// Standard deviation of the Gaussian noise on every source coordinate, metres.
    pub noise_sigma_m: f32,
    /// Fraction of the final source cloud that are outliers.
    pub outlier_fraction: f32,
    /// Radius of the ball the translation is drawn from, metres.
    pub max_translation_m: f32,
    /// The rotations the pose is drawn from: any (uniform), or turns about z (the object stays
    /// upright, as furniture on a floor).
    pub rotations: Rotations,
}

impl Default for RegistrationTrialSpec {
    /// The trial: 40–70 % visible, 1 cm noise, 20 % outliers, translation ≤ 1 m.
    fn default() -> Self {
        Self {
            template_points: 6000,
            source_points: 6000,
            visible: (0.4, 0.7),
            noise_sigma_m: 0.01,
            outlier_fraction: 0.2,
            max_translation_m: 1.0,
            rotations: Rotations::Any,
        }
    }
}

/// One drawn trial.
#[derive(Debug, Clone)]
pub struct RegistrationTrial {
    /// The design sampled.
    pub design: Design,
    /// Full-surface samples in the object frame.
    pub template: Vec<Point3<f32>>,
    /// The partial, noisy, moved view with outliers.
    pub source: Vec<Point3<f32>>,
    /// Noise-free full-surface samples moved like the source (to measure aligned-cloud distance).
    pub source_full_clean: Vec<Point3<f32>>,
    /// The true template_from_source.
    pub truth: Isometry3<f32>,
    /// Fraction of the surface samples kept by the cut.
    pub visible_fraction: f32,
}

impl RegistrationTrial {
    /// Draws a trial of `design` from `seed`.
    pub fn draw(design: Design, spec: &RegistrationTrialSpec, seed: u64) -> Result<Self> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mesh = design.mesh();
        let template = mesh.sample_surface(spec.template_points, &mut rng)?;
        let surface = mesh.sample_surface_oriented(spec.source_points, &mut rng)?;
        let azimuth = rng.random::<f32>() * std::f32::consts::TAU;
        let elevation = rng.random::<f32>() * 60f32.to_radians();
        let toward_camera = Vector3::new(
            elevation.cos() * azimuth.cos(),
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
        );
        let (lo, hi) = spec.visible;
        let visible_fraction = lo + (hi - lo) * rng.random::<f32>();
        let mut by_facing: Vec<(f32, usize)> = surface
            .iter()
            .enumerate()
            .map(|(i, (_, normal))| (normal.dot(&toward_camera), i))
            .collect();
        by_facing.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let keep = ((surface.len() as f32 * visible_fraction).round() as usize).max(3);
        let mut kept: Vec<usize> = by_facing[..keep.min(surface.len())].iter().map(|&(_, i)| i).collect();
        kept.sort_unstable();
        let sigma = spec.noise_sigma_m.max(0.0);
        let mut local: Vec<Point3<f32>> = kept
            .iter()
            .map(|&i| surface[i].0 + Vector3::from_fn(|_, _| sigma * standard_normal_f32(&mut rng)))
            .collect();
        let bounds = Aabb::from_points(&local).expect("at least 3 kept points");
        let margin = bounds.extent() * 0.05;
        let (min, extent) = (bounds.min - margin, bounds.extent() + 2.0 * margin);
        let outliers = (local.len() as f32 * spec.outlier_fraction / (1.0 - spec.outlier_fraction)).round() as usize;
        for _ in 0..outliers {
            local.push(min + Vector3::from_fn(|i, _| extent[i] * rng.random::<f32>()));
        }
        let rotation = match spec.rotations {
            Rotations::Any => UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
                standard_normal_f32(&mut rng),
                standard_normal_f32(&mut rng),
                standard_normal_f32(&mut rng),
                standard_normal_f32(&mut rng),
            )),
            Rotations::AboutUp => {
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), rng.random::<f32>() * std::f32::consts::TAU)
            }
        };
        let translation = loop {
            let t = Vector3::from_fn(|_, _| 2.0 * rng.random::<f32>() - 1.0);
            if t.norm() <= 1.0 {
                break t * spec.max_translation_m;
            }
        };
        let source_from_object = Isometry3::from_parts(Translation3::from(translation), rotation);
        let source = local.iter().map(|p| source_from_object * p).collect();
        let source_full_clean = template.iter().map(|p| source_from_object * p).collect();
        Ok(Self {
            design,
            template,
            source,
            source_full_clean,
            truth: source_from_object.inverse(),
            visible_fraction,
        })
    }

    /// Rotation error (degrees) and translation error (metres) of an estimated
    /// template_from_source; the translation error is how far the estimate puts the object's
    /// centre (the template's centroid) from where it belongs.
    pub fn pose_error(&self, estimate: &Isometry3<f32>) -> (f32, f32) {
        let delta = estimate * self.truth.inverse();
        let centre =
            Point3::from(self.template.iter().map(|p| p.coords).sum::<Vector3<f32>>() / self.template.len() as f32);
        (delta.rotation.angle().to_degrees(), (delta * centre - centre).norm())
    }

    /// Mean distance (metres) from the clean full surface, aligned by `estimate`, to the
    /// template: 0 for the truth, small for any pose the object's symmetry makes equivalent.
    /// The reference is a dense resampling of the design's surface (so sampling gaps do not
    /// count), the aligned cloud the template's samples moved like the source.
    pub fn aligned_cloud_distance(&self, estimate: &Isometry3<f32>) -> Result<f32> {
        let dense = self
            .design
            .mesh()
            .sample_surface(DENSE_REFERENCE_POINTS, &mut ChaCha8Rng::seed_from_u64(0))?;
        let index = PointIndex::new(&dense)?;
        let aligned: Vec<Point3<f32>> = self.source_full_clean.iter().map(|p| estimate * p).collect();
        Ok(index.mean_distance(&aligned))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_truth_maps_the_clean_moved_surface_back_onto_the_template() {
        let trial = RegistrationTrial::draw(Design::LadderBackChair, &RegistrationTrialSpec::default(), 3).unwrap();
        for (moved, original) in trial.source_full_clean.iter().zip(&trial.template) {
            assert!((trial.truth * moved - original).norm() < 1e-4);
        }
        let (rotation_deg, translation_m) = trial.pose_error(&trial.truth);
        assert!(rotation_deg < 1e-3 && translation_m < 1e-5);
    }

    #[test]
    fn the_source_keeps_the_visible_fraction_plus_outliers() {
        let spec = RegistrationTrialSpec::default();
        let trial = RegistrationTrial::draw(Design::Cabinet, &spec, 5).unwrap();
        assert!((0.4..=0.7).contains(&trial.visible_fraction));
        let inliers = (spec.source_points as f32 * trial.visible_fraction).round();
        let expected = inliers / (1.0 - spec.outlier_fraction);
        assert!(
            (trial.source.len() as f32 - expected).abs() <= 2.0,
            "{} vs {expected}",
            trial.source.len()
        );
        let again = RegistrationTrial::draw(Design::Cabinet, &spec, 5).unwrap();
        assert_eq!(again.source, trial.source, "deterministic from the seed");
    }
}
