//! The robust start of [`super::register_to_representative`] (METHOD.md §4's own pipeline): putative
//! correspondences from a front end (all-to-all pairs or FPFH matches) on clouds thinned to
//! `voxel_m`, then the TEASER++ back end ([`robust_registration`]). With all-to-all pairs the
//! estimate does not depend on the initial rotation, so it is computed once per pair.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::cloud::voxel_centroids;
use super::consistency::{Correspondence, all_to_all_pairs};
use super::fpfh::{fpfh_descriptors, mutual_nearest_neighbours};
use super::normals::pca_normals;
use super::teaser::robust_registration;
use super::{FrontEnd, RegistrationConfig};
use crate::error::Result;
use crate::geometry::nearest::PointIndex;

/// Diagnostics of the front end + TEASER++ back end.
#[derive(Debug, Clone, PartialEq)]
pub struct RobustTrace {
    /// Putative correspondences.
    pub correspondences: usize,
    /// Size of the maximum clique.
    pub clique_size: usize,
    /// Whether the clique is proven maximum.
    pub clique_proven_maximum: bool,
}

/// The front end + TEASER++ back end estimate as one start (module doc, step 1).
pub(super) fn robust_start(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    cfg: &RegistrationConfig,
    seed: u64,
) -> Result<(Isometry3<f64>, RobustTrace)> {
    let source = voxel_centroids(source, cfg.voxel_m)?;
    let template = voxel_centroids(template, cfg.voxel_m)?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let correspondences = front_end_correspondences(&source, &template, cfg, &mut rng)?;
    let estimate = robust_registration(&source, &template, &correspondences, cfg)?;
    let pose = Isometry3::from_parts(
        Translation3::from(estimate.translation),
        UnitQuaternion::from_rotation_matrix(&estimate.rotation),
    );
    let trace = RobustTrace {
        correspondences: estimate.correspondences,
        clique_size: estimate.clique_size,
        clique_proven_maximum: estimate.clique_proven_maximum,
    };
    Ok((pose, trace))
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
