//! [`register_to_representative`]: the composition of METHOD.md §4 (24 initial rotations ×
//! front end → robust back end → ICP, scored by the normalised one-way Chamfer distance).

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::chamfer::normalised_one_way_chamfer;
use super::cloud::{check_cloud, voxel_centroids};
use super::consistency::{Correspondence, all_to_all_pairs};
use super::cube_rotations::cube_rotations;
use super::fpfh::{fpfh_descriptors, mutual_nearest_neighbours};
use super::icp::{IcpParams, icp_point_to_point};
use super::normals::pca_normals;
use super::teaser::{RobustEstimate, robust_registration};
use super::{FrontEnd, RegistrationConfig};
use crate::error::{CatmapError, Result};
use crate::nearest::PointIndex;

/// The best alignment of a source cloud to a template: p_in_template ≈ rotation·p_in_source +
/// translation.
#[derive(Debug, Clone, PartialEq)]
pub struct Registration {
    /// Rotation of template_from_source.
    pub rotation: Rotation3<f32>,
    /// Translation of template_from_source, metres.
    pub translation: Vector3<f32>,
    /// Normalised one-way Chamfer distance CD(aligned source → template) / s(source).
    pub score: f32,
    /// Which of the 24 [`cube_rotations`] the best candidate started from.
    pub initial_rotation_index: usize,
    /// Diagnostics of every candidate, in initial-rotation order.
    pub trace: RegistrationTrace,
}

impl Registration {
    /// template_from_source as an isometry.
    pub fn template_from_source(&self) -> Isometry3<f32> {
        Isometry3::from_parts(
            Translation3::from(self.translation),
            UnitQuaternion::from_rotation_matrix(&self.rotation),
        )
    }
}

/// What each of the 24 candidates did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RegistrationTrace {
    /// Points of the downsampled source and template the front end worked on.
    pub downsampled_points: (usize, usize),
    /// Per initial rotation: the candidate's diagnostics, or why it failed.
    pub candidates: Vec<std::result::Result<CandidateTrace, String>>,
}

/// Diagnostics of one candidate.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateTrace {
    /// Putative correspondences.
    pub correspondences: usize,
    /// Size of the maximum clique.
    pub clique_size: usize,
    /// Whether the clique is proven maximum.
    pub clique_proven_maximum: bool,
    /// ICP iterations.
    pub icp_iterations: usize,
    /// Normalised one-way Chamfer score.
    pub score: f32,
}

/// Registers `source` (a partial, noisy object cloud) to `template` (the representative's
/// cloud), trying each of the 24 cube rotations R₀ applied to the template, and keeps the
/// candidate with the smallest normalised one-way Chamfer score (ties: lowest index).
///
/// Candidate k draws its randomness from a ChaCha8 stream k of one seed drawn from `rng`, so the
/// result does not depend on thread scheduling. Errors on degenerate clouds (fewer than 3 points,
/// non-finite coordinates, no extent) or when every candidate fails.
pub fn register_to_representative<R: Rng + ?Sized>(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    cfg: &RegistrationConfig,
    rng: &mut R,
) -> Result<Registration> {
    check_cloud(source, "source", 3)?;
    check_cloud(template, "template", 3)?;
    let seed: u64 = rng.random();
    let clouds = Clouds {
        source: voxel_centroids(source, cfg.voxel_m)?,
        template: voxel_centroids(template, cfg.voxel_m)?,
        source_icp: voxel_centroids(source, cfg.icp_voxel_m)?,
        template_icp: voxel_centroids(template, cfg.icp_voxel_m)?,
    };
    let candidates: Vec<Result<(Isometry3<f64>, CandidateTrace)>> = cube_rotations()
        .par_iter()
        .enumerate()
        .map(|(k, initial)| {
            let mut candidate_rng = ChaCha8Rng::seed_from_u64(seed);
            candidate_rng.set_stream(k as u64);
            let rotated = Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_rotation_matrix(&initial.cast::<f64>()),
            );
            let (rotated_from_source, mut trace) = register_candidate(&clouds, &rotated, cfg, &mut candidate_rng)?;
            let template_from_source = rotated.inverse() * rotated_from_source;
            let aligned: Vec<Point3<f32>> = source
                .iter()
                .map(|p| (template_from_source * p.cast()).cast())
                .collect();
            trace.score = normalised_one_way_chamfer(&aligned, template)?;
            Ok((template_from_source, trace))
        })
        .collect();
    let best = candidates
        .iter()
        .enumerate()
        .filter_map(|(k, c)| c.as_ref().ok().map(|(pose, trace)| (k, pose, trace.score)))
        .min_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)));
    let Some((index, pose, score)) = best else {
        let reason = candidates
            .iter()
            .find_map(|c| c.as_ref().err())
            .map(ToString::to_string);
        return Err(CatmapError::Degenerate(format!(
            "all 24 registration candidates failed; the first because: {}",
            reason.unwrap_or_default()
        )));
    };
    Ok(Registration {
        rotation: pose.rotation.to_rotation_matrix().cast(),
        translation: pose.translation.vector.cast(),
        score,
        initial_rotation_index: index,
        trace: RegistrationTrace {
            downsampled_points: (clouds.source.len(), clouds.template.len()),
            candidates: candidates
                .into_iter()
                .map(|c| c.map(|(_, trace)| trace).map_err(|e| e.to_string()))
                .collect(),
        },
    })
}

/// The downsampled clouds, shared by all candidates.
struct Clouds {
    source: Vec<Point3<f32>>,
    template: Vec<Point3<f32>>,
    source_icp: Vec<Point3<f32>>,
    template_icp: Vec<Point3<f32>>,
}

/// One candidate: registers the source to the template moved by `rotated_from_template`.
/// Returns rotated_from_source.
fn register_candidate(
    clouds: &Clouds,
    rotated_from_template: &Isometry3<f64>,
    cfg: &RegistrationConfig,
    rng: &mut ChaCha8Rng,
) -> Result<(Isometry3<f64>, CandidateTrace)> {
    let rotate = |points: &[Point3<f32>]| -> Vec<Point3<f32>> {
        points
            .iter()
            .map(|p| (rotated_from_template * p.cast()).cast())
            .collect()
    };
    let template = rotate(&clouds.template);
    let correspondences = front_end_correspondences(&clouds.source, &template, cfg, rng)?;
    let estimate: RobustEstimate = robust_registration(&clouds.source, &template, &correspondences, cfg)?;
    let initial = Isometry3::from_parts(
        Translation3::from(estimate.translation),
        UnitQuaternion::from_rotation_matrix(&estimate.rotation),
    );
    let template_icp = rotate(&clouds.template_icp);
    let index = PointIndex::new(&template_icp)?;
    let params = IcpParams {
        max_correspondence_m: cfg.icp_max_correspondence_m,
        max_iterations: cfg.icp_max_iterations,
    };
    let refined = icp_point_to_point(&clouds.source_icp, &template_icp, &index, initial, &params);
    let trace = CandidateTrace {
        correspondences: estimate.correspondences,
        clique_size: estimate.clique_size,
        clique_proven_maximum: estimate.clique_proven_maximum,
        icp_iterations: refined.iterations,
        score: f32::NAN,
    };
    Ok((refined.template_from_source, trace))
}

/// Putative correspondences between the downsampled clouds, by the configured front end.
pub fn front_end_correspondences<R: Rng + ?Sized>(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    cfg: &RegistrationConfig,
    rng: &mut R,
) -> Result<Vec<Correspondence>> {
    match cfg.front_end {
        FrontEnd::AllToAll => Ok(all_to_all_pairs(source.len(), template.len(), cfg.max_pairs, rng)),
        FrontEnd::Fpfh => {
            let describe = |points: &[Point3<f32>]| -> Result<_> {
                let index = PointIndex::new(points)?;
                let normals = pca_normals(points, &index, cfg.fpfh_normal_radius_voxels * cfg.voxel_m);
                Ok(fpfh_descriptors(
                    points,
                    &normals,
                    &index,
                    cfg.fpfh_feature_radius_voxels * cfg.voxel_m,
                ))
            };
            Ok(mutual_nearest_neighbours(&describe(source)?, &describe(template)?))
        }
    }
}
