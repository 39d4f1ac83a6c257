//! When and how an object's oriented box is (re)fitted from its observed cloud.

use nalgebra::Point3;

use crate::error::{CatmapError, Result};
use crate::geometry::local_surfaces::onto_local_surfaces;
use crate::geometry::mirror_symmetry::{MirrorDirections, MirrorPlane, SymmetryConfig, find_vertical_mirrors};
use crate::geometry::oriented_box::{OrientedBox, fit_minimum_volume_box};
use crate::geometry::round_axis::plane_across_axis;
use crate::geometry::upright_box::{fit_upright_box, fit_upright_box_on_faces};
use crate::objects::config::{BoxFit, ObjectConfig, RoundObjects};
use crate::objects::observed_cloud::{ObservedCloud, voxel_downsample};
use crate::training::{StreamPhase, takes_shape_priors};
use rayon::prelude::*;

/// Fewest cloud voxels an object needs before it gets a box.
pub const MIN_POINTS_FOR_BOX: usize = 10;

/// While streaming, an object's mirror plane is searched again when its cloud has grown by more
/// than this fraction since the last search (at a box refit; every grown one when the stream
/// ends). The search costs tens of milliseconds; the box is refitted every 10 %.
pub const MIRROR_REFRESH_GROWTH: f32 = 0.5;

/// An object's vertical mirror planes as last searched for in its thinned cloud
/// ([`crate::geometry::mirror_symmetry::find_vertical_mirrors`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MirrorFit {
    /// The plane, if the cloud has one.
    pub plane: Option<MirrorPlane>,
    /// A second plane at right angles to the first, if the cloud is symmetric about it too (a
    /// table end to end as well as side to side).
    #[serde(default)]
    pub second: Option<MirrorPlane>,
    /// Cloud voxels at the search.
    pub fitted_at_points: usize,
}

/// Which of an object's vertical mirror planes ([`MirrorFit`]) its mirrored rays are reflected
/// across.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MirrorPlanes {
    /// The best plane only.
    Best,
    /// The best plane, and the one at right angles to it when the cloud is symmetric about that
    /// too: a table whose one end a chair hides learns it from the other end.
    #[default]
    BothWhenFound,
}

impl MirrorFit {
    /// The planes `which` asks for, of those found: the best first.
    pub fn planes(&self, which: MirrorPlanes) -> Vec<MirrorPlane> {
        let second = match which {
            MirrorPlanes::Best => None,
            MirrorPlanes::BothWhenFound => self.second.filter(|_| self.plane.is_some()),
        };
        self.plane.into_iter().chain(second).collect()
    }
}

/// What a refit gives an object: its box, the cloud size it was fitted at, and its mirror plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedBounds {
    /// The minimum-volume box (edges at least `min_extent_m`).
    pub oriented_box: OrientedBox,
    /// Cloud voxels when the box was fitted.
    pub fitted_at_points: usize,
    /// The mirror plane: searched again at this refit, or the last one kept (none if never
    /// searched).
    pub mirror: Option<MirrorFit>,
}

/// Whether refits search an object's cloud for a mirror plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MirrorSearch {
    /// Search when the last search went stale (the object's sampler reflects rays across the
    /// plane).
    Search,
    /// Keep what there is (no sampler uses the object's plane: the search would only cost time).
    Skip,
}

impl MirrorSearch {
    /// Search for an object of a class of `class_size` objects (itself included) when the
    /// sampler reflects rays across the plane (`mirror_rays` per step) and the object takes the
    /// shape priors of objects alone in their class ([`takes_shape_priors`]), else skip: an
    /// object with a twin never trains on its plane (a plane kept from before its twin appeared
    /// stays, unused; one that loses its twin is searched at its next refit).
    pub fn for_object(mirror_rays: usize, class_size: usize) -> Self {
        if mirror_rays > 0 && takes_shape_priors(class_size) {
            Self::Search
        } else {
            Self::Skip
        }
    }
}

/// What a refit does with the mirror plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MirrorStep {
    /// Search the cloud now.
    Search,
    /// Keep this one.
    Keep(Option<MirrorFit>),
}

/// Whether a box fitted at `fitted_at` voxels is stale now that the cloud has `current` voxels.
pub fn box_is_stale(fitted_at: Option<usize>, current: usize, growth: f32) -> bool {
    match fitted_at {
        None => current >= MIN_POINTS_FOR_BOX,
        Some(n) => current as f64 > n as f64 * (1.0 + f64::from(growth)),
    }
}

/// Refits the boxes gone stale (see [`box_is_stale`]) among `objects` — each a key, the cloud
/// size its box was fitted at (`None`: no box yet), its last mirror plane, whether its plane is
/// searched ([`MirrorSearch::for_object`]) and its cloud — in parallel. Growth is
/// `bounds_refresh_growth` while streaming and 0 once the stream has ended (every grown box is
/// refitted). A refitted object's mirror plane is searched again when its
/// cloud has grown by [`MIRROR_REFRESH_GROWTH`] since the last search (0 once the stream has
/// ended; never under [`MirrorSearch::Skip`]). Returns, in input order, each stale object's key
/// and its new bounds, or why it has none yet.
pub fn refit_stale_boxes<'a, K: Send>(
    objects: impl IntoIterator<Item = (K, Option<usize>, Option<MirrorFit>, MirrorSearch, &'a ObservedCloud)>,
    phase: StreamPhase,
    cfg: &ObjectConfig,
) -> Vec<(K, Result<FittedBounds>)> {
    let (growth, mirror_growth) = match phase {
        StreamPhase::Streaming => (cfg.bounds_refresh_growth, MIRROR_REFRESH_GROWTH),
        StreamPhase::Ended => (0.0, 0.0),
    };
    let stale: Vec<(K, Option<MirrorFit>, MirrorSearch, &ObservedCloud)> = objects
        .into_iter()
        .filter(|(_, fitted_at, _, _, cloud)| box_is_stale(*fitted_at, cloud.len(), growth))
        .map(|(key, _, mirror, search, cloud)| (key, mirror, search, cloud))
        .collect();
    stale
        .into_par_iter()
        .map(|(key, mirror, mirror_search, cloud)| {
            let stale = mirror.is_none_or(|m| box_is_stale(Some(m.fitted_at_points), cloud.len(), mirror_growth));
            let step = match mirror_search {
                MirrorSearch::Search if stale => MirrorStep::Search,
                MirrorSearch::Search | MirrorSearch::Skip => MirrorStep::Keep(mirror),
            };
            (key, fit_object_bounds(cloud, step, cfg))
        })
        .collect()
}

/// The points an object's shape is measured from (its box, its registration to its class):
/// the centroids of the cloud's uncontested voxels holding at least `min_voxel_points` points —
/// a depth camera's stray points each land in a voxel of their own, and 28 of them on a
/// Kinect-like chair's 10 000 voxels stretched its registered frame to three times its depth —
/// or of all its uncontested voxels while fewer than [`MIN_POINTS_FOR_BOX`] hold enough.
pub fn shape_points(cloud: &ObservedCloud, min_voxel_points: u32) -> Vec<Point3<f32>> {
    let kept = cloud.points_of_voxels_with(min_voxel_points);
    if kept.len() >= MIN_POINTS_FOR_BOX {
        return kept;
    }
    cloud.points()
}

/// `points` moved onto their neighbours' surfaces within `radius_m` ([`onto_local_surfaces`], fitted
/// to the points thinned to a third of the radius); unmoved when `radius_m` is 0.
pub fn on_local_surfaces(points: Vec<Point3<f32>>, radius_m: f32) -> Vec<Point3<f32>> {
    if radius_m <= 0.0 {
        return points;
    }
    let reference = voxel_downsample(&points, radius_m / 3.0);
    onto_local_surfaces(&points, &reference, radius_m)
}

/// The box of the cloud's [`shape_points`] (`box_min_voxel_points`), moved onto their local
/// surfaces (`box_smoothing_m`, [`on_local_surfaces`]), thinned to `bounds_voxel_m`, fitted as
/// `box_fit` says (unset: the minimum-volume box), every edge ≥ `min_extent_m`.
pub fn fit_object_box(cloud: &ObservedCloud, cfg: &ObjectConfig) -> Result<OrientedBox> {
    Ok(fit_object_bounds(cloud, MirrorStep::Keep(None), cfg)?.oriented_box)
}

/// The box of [`fit_object_box`] and, as `mirror` says, the mirror plane of the same thinned
/// (and smoothed) cloud searched now (along the box's axes first) or the one given kept.
pub fn fit_object_bounds(cloud: &ObservedCloud, mirror: MirrorStep, cfg: &ObjectConfig) -> Result<FittedBounds> {
    if cloud.len() < MIN_POINTS_FOR_BOX {
        return Err(CatmapError::Degenerate(format!(
            "{} observed points, at least {MIN_POINTS_FOR_BOX} needed for a box",
            cloud.len()
        )));
    }
    let shape = on_local_surfaces(shape_points(cloud, cfg.box_min_voxel_points), cfg.box_smoothing_m);
    let thinned = voxel_downsample(&shape, cfg.bounds_voxel_m);
    let oriented_box = match cfg.box_fit.unwrap_or_default() {
        BoxFit::MinimumVolume => fit_minimum_volume_box(&thinned)?,
        BoxFit::Upright => fit_upright_box(&thinned)?,
        BoxFit::UprightOnFaces => fit_upright_box_on_faces(&thinned, cfg.box_turn)?,
    };
    let oriented_box = oriented_box.with_min_extent(cfg.min_extent_m);
    let mirror = match mirror {
        MirrorStep::Search => {
            let (yaw, symmetry) = (oriented_box.yaw(), SymmetryConfig::default());
            let (first, second) = find_vertical_mirrors(&thinned, &symmetry, MirrorDirections::BoxAxesFirst { yaw });
            let across_axis = || match cfg.round_objects {
                RoundObjects::AcrossAxis => first.and_then(|f| plane_across_axis(&thinned, &f.plane)),
                RoundObjects::Off => None,
            };
            Some(MirrorFit {
                plane: first.map(|f| f.plane),
                second: second.map(|f| f.plane).or_else(across_axis),
                fitted_at_points: cloud.len(),
            })
        }
        MirrorStep::Keep(kept) => kept,
    };
    Ok(FittedBounds {
        oriented_box,
        fitted_at_points: cloud.len(),
        mirror,
    })
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;

    #[test]
    fn the_second_plane_is_used_only_when_asked_and_only_beside_a_first() {
        let (first, second) = (MirrorPlane::vertical(0.0, 0.5), MirrorPlane::vertical(1.5, -0.2));
        let fit = MirrorFit {
            plane: Some(first),
            second: Some(second),
            fitted_at_points: 100,
        };
        assert_eq!(fit.planes(MirrorPlanes::BothWhenFound), vec![first, second]);
        assert_eq!(fit.planes(MirrorPlanes::Best), vec![first]);
        let alone = MirrorFit { plane: None, ..fit };
        assert!(alone.planes(MirrorPlanes::BothWhenFound).is_empty());
        let one = MirrorFit { second: None, ..fit };
        assert_eq!(one.planes(MirrorPlanes::BothWhenFound), vec![first]);
    }

    #[test]
    fn a_box_goes_stale_only_after_the_configured_growth() {
        assert!(!box_is_stale(None, 3, 0.1), "too few points for a first box");
        assert!(box_is_stale(None, 10, 0.1));
        assert!(!box_is_stale(Some(100), 110, 0.1));
        assert!(box_is_stale(Some(100), 111, 0.1));
    }

    #[test]
    fn voxels_with_too_few_points_are_left_out_of_the_box_unless_too_few_remain() {
        // A 40 cm square seen five times over, and three stray points a metre off.
        let mut cloud = ObservedCloud::new(0.01);
        for _ in 0..5 {
            for i in 0..40 {
                for j in 0..40 {
                    cloud.add_point(&Point3::new(0.005 + i as f32 * 0.01, 0.005 + j as f32 * 0.01, 0.5));
                }
            }
        }
        for k in 0..3 {
            cloud.add_point(&Point3::new(1.5 + k as f32 * 0.1, 0.2, 0.5));
        }
        let all = fit_object_box(&cloud, &ObjectConfig::default()).expect("enough points");
        assert!(
            all.extents().max() > 1.0,
            "the stray points stretch it: {:?}",
            all.extents()
        );
        let cfg = ObjectConfig {
            box_min_voxel_points: 3,
            ..ObjectConfig::default()
        };
        let kept = fit_object_box(&cloud, &cfg).expect("enough points");
        assert!(kept.extents().max() < 0.6, "the square alone: {:?}", kept.extents());
        // A cloud seen once has no voxel of three points: every voxel counts.
        let mut once = ObservedCloud::new(0.01);
        for i in 0..20 {
            once.add_point(&Point3::new(i as f32 * 0.02, 0.0, 0.5));
        }
        assert!(fit_object_box(&once, &cfg).is_ok());
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
                ("new", None, None, MirrorSearch::Search, &cloud),
                ("fresh", Some(n), None, MirrorSearch::Search, &cloud),
                ("grown", Some(n - 1), None, MirrorSearch::Search, &cloud),
            ]
        };
        let streaming = refit_stale_boxes(objects(), StreamPhase::Streaming, &cfg);
        let keys: Vec<&str> = streaming.iter().map(|(k, _)| *k).collect();
        assert_eq!(keys, vec!["new"], "one more point is less than the growth");
        let fitted = streaming[0].1.as_ref().expect("enough points");
        assert_eq!(
            (fitted.oriented_box, fitted.fitted_at_points),
            (fit_object_box(&cloud, &cfg).expect("enough points"), n)
        );
        let ended = refit_stale_boxes(objects(), StreamPhase::Ended, &cfg);
        let keys: Vec<&str> = ended.iter().map(|(k, _)| *k).collect();
        assert_eq!(keys, vec!["new", "grown"]);
        let few = ObservedCloud::new(0.01);
        let none = refit_stale_boxes(
            [("empty", Some(0), None, MirrorSearch::Search, &few)],
            StreamPhase::Ended,
            &cfg,
        );
        assert!(none.is_empty(), "a cloud that did not grow keeps its box");
    }

    #[test]
    fn the_mirror_plane_is_searched_again_only_after_its_own_growth_and_at_the_end() {
        // Two posts 0.6 m apart: mirror-symmetric about x = 0.3.
        let mut cloud = ObservedCloud::new(0.01);
        for x in [0.0, 0.6] {
            for k in 0..60 {
                for a in 0..8 {
                    let t = a as f32 * std::f32::consts::TAU / 8.0;
                    cloud.add_point(&Point3::new(x + 0.04 * t.cos(), 0.04 * t.sin(), k as f32 * 0.02));
                }
            }
        }
        let n = cloud.len();
        let cfg = ObjectConfig::default();
        let fitted = fit_object_bounds(&cloud, MirrorStep::Search, &cfg).expect("enough points");
        let plane = fitted.mirror.and_then(|m| m.plane).expect("two posts are symmetric");
        assert!(
            plane.normal.x.abs() > 0.999 && (plane.distance(&Point3::new(0.3, 0.0, 0.0))).abs() < 0.01,
            "{plane:?}"
        );
        // A remembered search (here: none found) is kept while the cloud grew by less than the
        // growth, though the box is refitted.
        let remembered = MirrorFit {
            plane: None,
            second: None,
            fitted_at_points: (n as f32 / (1.0 + MIRROR_REFRESH_GROWTH)) as usize + 1,
        };
        let refit =
            |mirror, phase, search| refit_stale_boxes([("a", Some(1), Some(mirror), search, &cloud)], phase, &cfg);
        let streaming = refit(remembered, StreamPhase::Streaming, MirrorSearch::Search);
        assert_eq!(streaming[0].1.as_ref().expect("fitted").mirror, Some(remembered));
        let ended = refit(remembered, StreamPhase::Ended, MirrorSearch::Search);
        assert_eq!(
            ended[0].1.as_ref().expect("fitted").mirror,
            fitted.mirror,
            "searched again at the end"
        );
        let older = MirrorFit {
            fitted_at_points: remembered.fitted_at_points - 2,
            ..remembered
        };
        let grown = refit(older, StreamPhase::Streaming, MirrorSearch::Search);
        assert_eq!(
            grown[0].1.as_ref().expect("fitted").mirror,
            fitted.mirror,
            "grown past the growth"
        );
        assert_eq!(MirrorSearch::for_object(24, 1), MirrorSearch::Search);
        assert_eq!(MirrorSearch::for_object(0, 1), MirrorSearch::Skip);
        assert_eq!(
            MirrorSearch::for_object(24, 2),
            MirrorSearch::Skip,
            "an object with a twin"
        );
        let skipped = refit(older, StreamPhase::Ended, MirrorSearch::for_object(0, 1));
        assert_eq!(
            skipped[0].1.as_ref().expect("fitted").mirror,
            Some(older),
            "no search without mirrored rays"
        );
        let twin = refit(older, StreamPhase::Ended, MirrorSearch::for_object(24, 3));
        assert_eq!(
            twin[0].1.as_ref().expect("fitted").mirror,
            Some(older),
            "no search for an object with twins"
        );
    }
}

#[cfg(test)]
#[path = "object_bounds_noise_tests.rs"]
mod noise_tests;

#[cfg(test)]
#[path = "object_bounds_round_tests.rs"]
mod round_tests;
