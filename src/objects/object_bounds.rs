//! When and how an object's oriented box is (re)fitted from its observed cloud.

use crate::error::{CatmapError, Result};
use crate::geometry::oriented_box::{OrientedBox, fit_minimum_volume_box};
use crate::objects::config::ObjectConfig;
use crate::objects::observed_cloud::{ObservedCloud, voxel_downsample};
use crate::training::StreamPhase;
use rayon::prelude::*;

/// Fewest cloud voxels an object needs before it gets a box.
pub const MIN_POINTS_FOR_BOX: usize = 10;

/// Whether a box fitted at `fitted_at` voxels is stale now that the cloud has `current` voxels.
pub fn box_is_stale(fitted_at: Option<usize>, current: usize, growth: f32) -> bool {
    match fitted_at {
        None => current >= MIN_POINTS_FOR_BOX,
        Some(n) => current as f64 > n as f64 * (1.0 + f64::from(growth)),
    }
}

/// Refits the boxes gone stale (see [`box_is_stale`]) among `objects` — each a key, the cloud
/// size its box was fitted at (`None`: no box yet) and its cloud — in parallel. Growth is
/// `bounds_refresh_growth` while streaming and 0 once the stream has ended (every grown box is
/// refitted). Returns, in input order, each stale object's key and its new box with the cloud
/// size it was fitted at, or why it has none yet.
pub fn refit_stale_boxes<'a, K: Send>(
    objects: impl IntoIterator<Item = (K, Option<usize>, &'a ObservedCloud)>,
    phase: StreamPhase,
    cfg: &ObjectConfig,
) -> Vec<(K, Result<(OrientedBox, usize)>)> {
    let growth = match phase {
        StreamPhase::Streaming => cfg.bounds_refresh_growth,
        StreamPhase::Ended => 0.0,
    };
    let stale: Vec<(K, &ObservedCloud)> = objects
        .into_iter()
        .filter(|(_, fitted_at, cloud)| box_is_stale(*fitted_at, cloud.len(), growth))
        .map(|(key, _, cloud)| (key, cloud))
        .collect();
    stale
        .into_par_iter()
        .map(|(key, cloud)| (key, fit_object_box(cloud, cfg).map(|b| (b, cloud.len()))))
        .collect()
}

/// The minimum-volume box of the cloud, thinned to `bounds_voxel_m`, every edge ≥ `min_extent_m`.
pub fn fit_object_box(cloud: &ObservedCloud, cfg: &ObjectConfig) -> Result<OrientedBox> {
    if cloud.len() < MIN_POINTS_FOR_BOX {
        return Err(CatmapError::Degenerate(format!(
            "{} observed points, at least {MIN_POINTS_FOR_BOX} needed for a box",
            cloud.len()
        )));
    }
    let thinned = voxel_downsample(&cloud.points(), cfg.bounds_voxel_m);
    Ok(fit_minimum_volume_box(&thinned)?.with_min_extent(cfg.min_extent_m))
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    #[test]
    fn a_box_goes_stale_only_after_the_configured_growth() {
        assert!(!box_is_stale(None, 3, 0.1), "too few points for a first box");
        assert!(box_is_stale(None, 10, 0.1));
        assert!(!box_is_stale(Some(100), 110, 0.1));
        assert!(box_is_stale(Some(100), 111, 0.1));
    }

    #[test]
    fn a_small_flat_object_gets_the_minimum_extent() {
        let mut cloud = ObservedCloud::new(0.01);
        for i in 0..20 {
            for j in 0..20 {
                cloud.add_point(&Point3::new(i as f32 * 0.002, j as f32 * 0.002, 0.5));
            }
        }
        let fitted = fit_object_box(&cloud, &ObjectConfig::default()).expect("enough points");
        assert!(fitted.extents().min() >= 0.1 - 1e-6, "extents {:?}", fitted.extents());
    }

    #[test]
    fn only_stale_boxes_are_refitted_and_every_grown_one_once_the_stream_ends() {
        let mut cloud = ObservedCloud::new(0.01);
        for i in 0..20 {
            for j in 0..20 {
                cloud.add_point(&Point3::new(i as f32 * 0.02, j as f32 * 0.02, (i + j) as f32 * 0.01));
            }
        }
        let n = cloud.len();
        let cfg = ObjectConfig::default();
        let objects = || {
            [
                ("new", None, &cloud),
                ("fresh", Some(n), &cloud),
                ("grown", Some(n - 1), &cloud),
            ]
        };
        let streaming = refit_stale_boxes(objects(), StreamPhase::Streaming, &cfg);
        let keys: Vec<&str> = streaming.iter().map(|(k, _)| *k).collect();
        assert_eq!(keys, vec!["new"], "one more point is less than the growth");
        let (fitted, at) = streaming[0].1.as_ref().expect("enough points");
        assert_eq!(
            (*fitted, *at),
            (fit_object_box(&cloud, &cfg).expect("enough points"), n)
        );
        let ended = refit_stale_boxes(objects(), StreamPhase::Ended, &cfg);
        let keys: Vec<&str> = ended.iter().map(|(k, _)| *k).collect();
        assert_eq!(keys, vec!["new", "grown"]);
        let few = ObservedCloud::new(0.01);
        let none = refit_stale_boxes([("empty", Some(0), &few)], StreamPhase::Ended, &cfg);
        assert!(none.is_empty(), "a cloud that did not grow keeps its box");
    }
}
