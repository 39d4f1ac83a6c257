//! When and how an object's oriented box is (re)fitted from its observed cloud.

use nalgebra::Point3;

use crate::error::{CatmapError, Result};
use crate::geometry::connected_parts::main_parts;
use crate::geometry::local_surfaces::onto_local_surfaces;
use crate::geometry::mirror_symmetry::{MirrorDirections, MirrorPlane, SymmetryConfig, find_vertical_mirrors};
use crate::geometry::oriented_box::{OrientedBox, fit_minimum_volume_box};
use crate::geometry::round_axis::plane_across_axis;
use crate::geometry::upright_box::{fit_upright_box, fit_upright_box_on_faces};
use crate::objects::config::{BoxFit, ObjectConfig, RoundObjects, ShapeVoxels};
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

/// The least cell edge of the grid on which an object's shape points are grouped into connected
/// parts ([`shape_points`]), metres: points up to one cell apart (and some up to two) join, so a
/// depth camera's holes of a few centimetres do not cut a part off. The cell is twice the
/// spacing of the object's points where that is larger (a camera of few pixels, or an object
/// far off: its surface's points lie farther apart than a few centimetres).
pub const SHAPE_PART_CELL_M: f32 = 0.03;

/// Under a segmenter's masks, a voxel stays in an object's shape when it holds at least
/// `box_min_voxel_points` points or as many as this many views put in a voxel of its surface
/// (the voxel's area over the square of the points' spacing,
/// [`ObservedCloud::point_spacing_m`]), whichever is fewer: where a camera samples an object so
/// sparsely that a view puts a fraction of a point in a voxel (160×120 pixels: points 1.5–2.5 cm
/// apart on 1 cm voxels), a count cannot tell a stray point from the surface, and the views'
/// votes and the connected parts decide alone. At 640×480 (f = 512 px) a view puts at least one
/// point in a voxel out to 5 m, and the count stands.
pub const SURFACE_VIEWS: f32 = 2.0;

/// The least share of an object's shape points a connected part must hold to stay in its shape
/// ([`shape_points`]).
pub const SHAPE_PART_MIN_SHARE: f32 = 0.05;

/// Which cloud voxels make an object's shape: those of at least `min_voxel_points` points,
/// taken as `voxels` says (`objects.box_min_voxel_points`, `objects.shape_voxels`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ShapeRule {
    /// Fewest points a voxel holds.
    pub min_voxel_points: u32,
    /// Which of those count.
    pub voxels: ShapeVoxels,
}

impl ObjectConfig {
    /// The rule of an object's shape points under these settings.
    pub fn shape_rule(&self) -> ShapeRule {
        ShapeRule {
            min_voxel_points: self.box_min_voxel_points,
            voxels: self.shape_voxels,
        }
    }
}

/// The points an object's shape is measured from (its box, its registration to its class):
/// - the centroids of the cloud's voxels holding at least `rule.min_voxel_points` points — a
///   depth camera's stray points each land in a voxel of their own, and 28 of them on a
///   Kinect-like chair's 10 000 voxels stretched its registered frame to three times its depth
///   (under [`ShapeVoxels::MostlyOwnMainParts`], or what [`SURFACE_VIEWS`] views put in a
///   voxel of the surface if fewer) —
/// - under [`ShapeVoxels::Uncontested`], those no view contests;
/// - under [`ShapeVoxels::MostlyOwnMainParts`] (a segmenter's masks), those that at least half
///   the views that saw them saw as the object's
///   ([`crate::objects::observed_cloud::ViewVotes::mostly_own`]: a neighbour a segmenter merged
///   into the object's mask in a few frames is seen as the neighbour in the others), in the
///   connected parts ([`main_parts`] on a grid of [`SHAPE_PART_CELL_M`], or of twice the
///   points' spacing [`ObservedCloud::point_spacing_m`]) holding at least
///   [`SHAPE_PART_MIN_SHARE`] of them: a mask bled onto a wall metres behind the object, or a
///   spurious mask given to it, in a frame or two, lies apart from it and is a small share of it.
///   With a segmenter's masks and exact depth these had stretched a 1.2 m cabinet's box to 4.6 m
///   (docs/ROBUSTNESS.md).
///
/// While fewer than [`MIN_POINTS_FOR_BOX`] voxels pass, all uncontested voxels count.
pub fn shape_points(cloud: &ObservedCloud, rule: ShapeRule) -> Vec<Point3<f32>> {
    let min = rule.min_voxel_points;
    let kept = match rule.voxels {
        ShapeVoxels::Uncontested => cloud.points_of_voxels_with(min),
        ShapeVoxels::MostlyOwnMainParts => {
            let per_view = cloud
                .point_spacing_m()
                .map_or(f32::INFINITY, |s| (cloud.voxel_m() / s).powi(2));
            let min = (min as f32).min(SURFACE_VIEWS * per_view);
            cloud.points_of_voxels_where(|n, votes| n as f32 >= min && votes.mostly_own())
        }
    };
    if kept.len() < MIN_POINTS_FOR_BOX {
        return cloud.points();
    }
    match rule.voxels {
        ShapeVoxels::Uncontested => kept,
        ShapeVoxels::MostlyOwnMainParts => {
            let cell = SHAPE_PART_CELL_M.max(2.0 * cloud.point_spacing_m().unwrap_or(0.0));
            main_parts(kept, cell, SHAPE_PART_MIN_SHARE)
        }
    }
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

/// The box of the cloud's [`shape_points`] (`box_min_voxel_points`, `shape_voxels`), moved onto their local
/// surfaces (`box_smoothing_m`, [`on_local_surfaces`]), thinned to `bounds_voxel_m`, fitted as
/// `box_fit` says (unset: the minimum-volume box), every edge ≥ `min_extent_m`.
pub fn fit_object_box(cloud: &ObservedCloud, cfg: &ObjectConfig) -> Result<OrientedBox> {
    Ok(fit_object_bounds(cloud, MirrorStep::Keep(None), cfg)?.oriented_box)
}

/// The box of an object's shape points (moved onto their local surfaces, `box_smoothing_m`),
/// thinned to `bounds_voxel_m`, fitted as `box_fit` says, every edge ≥ `min_extent_m`; and the
/// thinned points.
pub fn fit_box_to_points(shape: Vec<Point3<f32>>, cfg: &ObjectConfig) -> Result<(OrientedBox, Vec<Point3<f32>>)> {
    let shape = on_local_surfaces(shape, cfg.box_smoothing_m);
    let thinned = voxel_downsample(&shape, cfg.bounds_voxel_m);
    let oriented_box = match cfg.box_fit {
        BoxFit::MinimumVolume => fit_minimum_volume_box(&thinned)?,
        BoxFit::Upright => fit_upright_box(&thinned)?,
        BoxFit::UprightOnFaces => fit_upright_box_on_faces(&thinned, cfg.box_turn)?,
    };
    Ok((oriented_box.with_min_extent(cfg.min_extent_m), thinned))
}

/// The box of [`fit_object_box`] and, as `mirror` says, the mirror plane of the same thinned
/// (and smoothed) cloud searched now (along the box's axes first) or the one given kept.
pub fn fit_object_bounds(cloud: &ObservedCloud, mirror: MirrorStep, cfg: &ObjectConfig) -> Result<FittedBounds> {
    if cloud.len() < MIN_POINTS_FOR_BOX {
        return Err(CatmapError::too_few(
            "observed points for a box",
            MIN_POINTS_FOR_BOX,
            cloud.len(),
        ));
    }
    let (oriented_box, thinned) = fit_box_to_points(shape_points(cloud, cfg.shape_rule()), cfg)?;
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
#[path = "object_bounds_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "object_bounds_noise_tests.rs"]
mod noise_tests;

#[cfg(test)]
#[path = "object_bounds_round_tests.rs"]
mod round_tests;

#[cfg(test)]
#[path = "object_bounds_parts_tests.rs"]
mod parts_tests;
