//! [`register_to_representative`]: METHOD.md §4's registration of a partial object cloud to its
//! representative, made robust to partial views and outliers.
//!
//! 1. Starts: the 24 [`cube_rotations`] (the rotation of start k is C_kᵀ, i.e. C_k applied to the
//!    template), optionally each composed with `twists` turns (with `rotations = "about_up"`:
//!    turns about z every `twist_deg`, and every ICP step below solves over turns about z), with
//!    the translation that aligns the centroids; optionally one more start from the
//!    correspondence front end + TEASER++ back end ([`super::robust_start`]; rotation-independent,
//!    so computed once; about up, turned to the nearest turn about z).
//! 2. Coarse: every start runs trimmed ICP ([`icp_point_to_point`] with ρ = `keep_fraction`) at
//!    the `search_gates_m` on clouds thinned to `search_voxel_m` (of the source, an even subset of
//!    at most `search_points`), and is ranked by the trimmed normalised one-way Chamfer distance
//!    ([`trimmed_normalised_chamfer`]) of the whole thinned source.
//! 3. Fine: the `refined_candidates` best distinct poses run trimmed ICP at the `refine_gates_m`
//!    and then METHOD's plain ICP (gate `icp_max_correspondence_m`) on clouds thinned to
//!    `icp_voxel_m`; the smallest whole (untrimmed) one-way Chamfer distance wins (ties: lowest
//!    start index).
//! 4. With `rotations = "any"` and `tilt = "removed"` (the default), a winner whose rotation
//!    tilts world up by an angle within `removed_tilt_deg` (1–15°) is turned to the nearest turn
//!    about up ([`upright_start`]) and refined by step 3's stages over turns about up: both
//!    objects stand on one floor, and a partly seen cloud's best free fit tilts (a chair seen at
//!    20 % under a table through a Kinect-like camera: 4.4–4.8° off, nearly all of it tilt).
//!    [`refine_registration`] ends the same way.
//! 5. The reported score is METHOD's normalised one-way Chamfer distance of the whole aligned
//!    source to the whole template (the subcategory rule's input).
//!
//! Why not METHOD's pipeline alone: with all-to-all pairs of clouds thinned at 0.1 m, the voxel
//! centroids of two different samplings of one surface differ by several centimetres, so the
//! consistency graph at a 1 cm noise bound keeps a clique of only ~15 pairs out of millions of
//! edges (13–16 s per candidate) and the estimate is often wrong; with the 24 rotations the
//! all-to-all result is the same for every rotation anyway. Multi-start trimmed ICP is fast
//! (tens of ms per pair) and meets the trials in `tests/suite/categories/registration_trials.rs`.

use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, RngExt};
use rayon::prelude::*;

use super::RegistrationConfig;
use super::chamfer::{normalised_one_way_chamfer, trimmed_normalised_chamfer};
use super::cloud::{check_cloud, voxel_centroids};
use super::config::Rotations;
use super::icp::{IcpCounts, IcpParams, icp_point_to_point};
use super::robust_start::{RobustTrace, robust_start};
use super::start_rotations::{centroid, start_rotations, upright_start};
use crate::error::Result;
use crate::geometry::nearest::PointIndex;

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
    /// Which start won (see [`RegistrationTrace::starts`]).
    pub start_index: usize,
    /// Diagnostics.
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

/// What the search did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RegistrationTrace {
    /// Points of the coarse source and template.
    pub coarse_points: (usize, usize),
    /// Points of the fine source and template.
    pub fine_points: (usize, usize),
    /// Starts tried: 24·(1 + twists) (about up: one per `twist_deg` turn), plus one when the
    /// robust start succeeded.
    pub starts: usize,
    /// The robust start's diagnostics, or why it failed (None when not configured).
    pub robust: Option<std::result::Result<RobustTrace, String>>,
    /// Trimmed coarse score of every start, in start order.
    pub coarse_scores: Vec<f32>,
    /// (start index, trimmed fine score) of every refined candidate, best first.
    pub refined: Vec<(usize, f32)>,
    /// Every ICP run of the search: how many, their iterations, how many reached their cap.
    pub icp: IcpCounts,
}

/// Registers `source` (a partial, noisy object cloud) to `template` (the representative's
/// cloud) by the multi-start search of the module doc.
///
/// Randomness (the front end's pair subsample) comes from one seed drawn from `rng`, so the
/// result does not depend on thread scheduling. Errors on degenerate clouds (fewer than 3 points,
/// non-finite coordinates, no extent).
pub fn register_to_representative<R: Rng + ?Sized>(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    cfg: &RegistrationConfig,
    rng: &mut R,
) -> Result<Registration> {
    check_cloud(source, "source", 3)?;
    check_cloud(template, "template", 3)?;
    let seed: u64 = rng.random();
    let coarse = Level::new(source, template, cfg.search_voxel_m)?;
    let fine = Level::new(source, template, cfg.icp_voxel_m)?;
    let mut starts = ranked_starts(&coarse, cfg);
    let robust = cfg.robust_start.then(|| robust_start(source, template, cfg, seed));
    if let Some(Ok((pose, _))) = &robust {
        starts.push(match cfg.rotations {
            Rotations::Any => *pose,
            Rotations::AboutUp => upright_start(pose, source),
        });
    }
    let search_source = stride_subset(&coarse.source, cfg.search_points);
    let coarse_fits = coarse_search(&coarse, &search_source, &starts, cfg);
    let chosen = distinct_best(&coarse_fits, cfg.refined_candidates.max(1));
    let mut refined: Vec<(usize, Isometry3<f64>, f32, IcpCounts)> = chosen
        .par_iter()
        .map(|&k| {
            let (pose, icp) = fine.refine_fully(coarse_fits[k].0, cfg);
            (k, pose, fine.score(&pose, 1.0), icp)
        })
        .collect();
    refined.sort_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)));
    let (start_index, pose, ..) = refined[0];
    let (pose, upright_icp) = fine.without_tilt(pose, cfg);
    let icp = coarse_fits
        .iter()
        .map(|f| f.2)
        .chain(refined.iter().map(|r| r.3))
        .fold(upright_icp, |a, b| a + b);
    finished(
        source,
        template,
        &pose,
        start_index,
        RegistrationTrace {
            coarse_points: (coarse.source.len(), coarse.template.len()),
            fine_points: (fine.source.len(), fine.template.len()),
            starts: starts.len(),
            robust: robust.map(|r| r.map(|(_, t)| t).map_err(|e| e.to_string())),
            coarse_scores: coarse_fits.iter().map(|f| f.1).collect(),
            refined: refined.iter().map(|r| (r.0, r.2)).collect(),
            icp,
        },
    )
}

/// Step 2 of the module doc: every start runs the coarse gates on `search_source` and is scored
/// (trimmed) on the whole coarse source; with each start's ICP counts.
fn coarse_search(
    coarse: &Level,
    search_source: &[Point3<f32>],
    starts: &[Isometry3<f64>],
    cfg: &RegistrationConfig,
) -> Vec<(Isometry3<f64>, f32, IcpCounts)> {
    let stage = |gate: f32| icp_params(cfg, gate, cfg.search_iterations, cfg.keep_fraction);
    starts
        .par_iter()
        .map(|start| {
            let (pose, icp) = cfg
                .search_gates_m
                .iter()
                .fold((*start, IcpCounts::default()), |(pose, icp), &gate| {
                    let (pose, run) = coarse.refine_points(search_source, pose, &stage(gate));
                    (pose, icp + run)
                });
            (pose, coarse.score(&pose, cfg.keep_fraction), icp)
        })
        .collect()
}

/// Every `ceil(len / max_points)`-th point: at most about `max_points` of `points`, spread evenly.
fn stride_subset(points: &[Point3<f32>], max_points: usize) -> Vec<Point3<f32>> {
    let stride = points.len().div_ceil(max_points.max(3)).max(1);
    points.iter().step_by(stride).copied().collect()
}

/// The registration at `pose`, scored by METHOD's normalised one-way Chamfer distance of the whole
/// aligned source to the whole template.
fn finished(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    pose: &Isometry3<f64>,
    start_index: usize,
    trace: RegistrationTrace,
) -> Result<Registration> {
    let aligned: Vec<Point3<f32>> = source.iter().map(|p| (pose * p.cast()).cast()).collect();
    Ok(Registration {
        rotation: pose.rotation.to_rotation_matrix().cast(),
        translation: pose.translation.vector.cast(),
        score: normalised_one_way_chamfer(&aligned, template)?,
        start_index,
        trace,
    })
}

/// Refines a known alignment of `source` to `template` — a warm start, e.g. the pose of the
/// previous registration of the same pair — by step 3 of the module doc alone (no search);
/// the score is the same as [`register_to_representative`]'s, so the two can be compared.
pub fn refine_registration(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
    template_from_source: &Isometry3<f32>,
    cfg: &RegistrationConfig,
) -> Result<Registration> {
    check_cloud(source, "source", 3)?;
    check_cloud(template, "template", 3)?;
    let fine = Level::new(source, template, cfg.icp_voxel_m)?;
    let (pose, icp) = fine.refine_fully(template_from_source.cast(), cfg);
    let (pose, upright_icp) = fine.without_tilt(pose, cfg);
    let icp = icp + upright_icp;
    let trace = RegistrationTrace {
        fine_points: (fine.source.len(), fine.template.len()),
        starts: 1,
        refined: vec![(0, fine.score(&pose, 1.0))],
        icp,
        ..RegistrationTrace::default()
    };
    finished(source, template, &pose, 0, trace)
}

/// The source and template thinned to one voxel size, with the template indexed.
struct Level {
    source: Vec<Point3<f32>>,
    template: Vec<Point3<f32>>,
    index: PointIndex,
}

impl Level {
    fn new(source: &[Point3<f32>], template: &[Point3<f32>], voxel_m: f32) -> Result<Self> {
        let template = voxel_centroids(template, voxel_m)?;
        Ok(Self {
            source: voxel_centroids(source, voxel_m)?,
            index: PointIndex::new(&template)?,
            template,
        })
    }

    fn refine(&self, pose: Isometry3<f64>, params: &IcpParams) -> (Isometry3<f64>, IcpCounts) {
        self.refine_points(&self.source, pose, params)
    }

    fn refine_points(
        &self,
        source: &[Point3<f32>],
        pose: Isometry3<f64>,
        params: &IcpParams,
    ) -> (Isometry3<f64>, IcpCounts) {
        let fit = icp_point_to_point(source, &self.index, pose, params);
        (fit.template_from_source, IcpCounts::of(&fit))
    }

    /// Step 3 of the module doc from `start`: trimmed ICP at the `refine_gates_m`, then plain ICP.
    fn refine_fully(&self, start: Isometry3<f64>, cfg: &RegistrationConfig) -> (Isometry3<f64>, IcpCounts) {
        let (pose, icp) = cfg
            .refine_gates_m
            .iter()
            .fold((start, IcpCounts::default()), |(pose, icp), &gate| {
                let (pose, run) = self.refine(pose, &icp_params(cfg, gate, cfg.refine_iterations, cfg.keep_fraction));
                (pose, icp + run)
            });
        let (pose, run) = self.refine(
            pose,
            &icp_params(cfg, cfg.icp_max_correspondence_m, cfg.icp_max_iterations, 1.0),
        );
        (pose, icp + run)
    }

    /// `pose` turned upright and refined about up when `cfg` removes its tilt
    /// ([`RegistrationConfig::removes_tilt`]); otherwise `pose` as it is.
    fn without_tilt(&self, pose: Isometry3<f64>, cfg: &RegistrationConfig) -> (Isometry3<f64>, IcpCounts) {
        if !cfg.removes_tilt(&pose.rotation) {
            return (pose, IcpCounts::default());
        }
        let upright = RegistrationConfig {
            rotations: Rotations::AboutUp,
            ..cfg.clone()
        };
        self.refine_fully(upright_start(&pose, &self.source), &upright)
    }

    fn score(&self, pose: &Isometry3<f64>, keep_fraction: f32) -> f32 {
        let moved: Vec<Point3<f32>> = self.source.iter().map(|p| (pose * p.cast()).cast()).collect();
        trimmed_normalised_chamfer(&moved, &self.index, keep_fraction)
    }
}

/// ICP at `gate` for at most `iterations`, keeping `keep_fraction` of the pairs, with `cfg`'s
/// step tolerance and rotations.
fn icp_params(cfg: &RegistrationConfig, gate: f32, iterations: usize, keep_fraction: f32) -> IcpParams {
    IcpParams {
        max_correspondence_m: gate,
        max_iterations: iterations,
        keep_fraction,
        step_tolerance: cfg.icp_step_tolerance,
        rotations: cfg.rotations,
    }
}

/// Every start rotation with the centroids aligned, its translation shifted by
/// [`shift_translation`], ranked by the trimmed score of a small subset of the coarse source;
/// the `ranked_starts` best (ties: enumeration order).
fn ranked_starts(level: &Level, cfg: &RegistrationConfig) -> Vec<Isometry3<f64>> {
    let rotations = start_rotations(cfg);
    let ct = centroid(&level.template);
    let stride = level.source.len().div_ceil(cfg.ranking_points.max(3));
    let subset: Vec<Point3<f32>> = level.source.iter().step_by(stride.max(1)).copied().collect();
    let cs = centroid(&subset);
    let fitted: Vec<(Isometry3<f64>, f32)> = rotations
        .par_iter()
        .map(|r| {
            let start = Isometry3::from_parts(Translation3::from(ct - r * cs), *r);
            let pose = shift_translation(&subset, level, start, cfg);
            let moved: Vec<Point3<f32>> = subset.iter().map(|p| (pose * p.cast()).cast()).collect();
            (
                pose,
                trimmed_normalised_chamfer(&moved, &level.index, cfg.keep_fraction),
            )
        })
        .collect();
    let mut order: Vec<usize> = (0..fitted.len()).collect();
    order.sort_by(|&a, &b| fitted[a].1.total_cmp(&fitted[b].1).then(a.cmp(&b)));
    order.truncate(cfg.ranked_starts.max(1));
    order.into_iter().map(|k| fitted[k].0).collect()
}

/// `translation_iterations` translation-only trimmed ICP steps: the translation moves by the mean
/// offset from each kept source point to its nearest template point.
fn shift_translation(
    subset: &[Point3<f32>],
    level: &Level,
    pose: Isometry3<f64>,
    cfg: &RegistrationConfig,
) -> Isometry3<f64> {
    let mut pose = pose;
    for _ in 0..cfg.translation_iterations {
        let mut offsets: Vec<(f32, Vector3<f64>)> = subset
            .iter()
            .map(|p| {
                let moved: Point3<f32> = (pose * p.cast()).cast();
                let (j, d2) = level.index.nearest(&moved);
                (d2, (level.template[j] - moved).cast())
            })
            .collect();
        let keep = super::icp::kept_count(offsets.len(), cfg.keep_fraction);
        if keep < offsets.len() {
            offsets.select_nth_unstable_by(keep, |a, b| a.0.total_cmp(&b.0));
        }
        let shift = offsets[..keep].iter().map(|o| o.1).sum::<Vector3<f64>>() / keep.max(1) as f64;
        pose.translation.vector += shift;
    }
    pose
}

/// Indices of up to `count` fits with the smallest scores whose poses differ pairwise by more
/// than 5° or 5 cm (ties: lower index first).
fn distinct_best(fits: &[(Isometry3<f64>, f32, IcpCounts)], count: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..fits.len()).collect();
    order.sort_by(|&a, &b| fits[a].1.total_cmp(&fits[b].1).then(a.cmp(&b)));
    let mut chosen: Vec<usize> = Vec::new();
    for k in order {
        let distinct = chosen.iter().all(|&c| {
            let delta = fits[k].0 * fits[c].0.inverse();
            delta.rotation.angle() > 5f64.to_radians() || delta.translation.vector.norm() > 0.05
        });
        if distinct {
            chosen.push(k);
            if chosen.len() == count {
                break;
            }
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_search_subset_is_an_even_stride_of_at_most_the_asked_points() {
        let cloud: Vec<Point3<f32>> = (0..1_000).map(|i| Point3::new(i as f32, 0.0, 0.0)).collect();
        let subset = stride_subset(&cloud, 400);
        assert_eq!(subset.len(), 334, "stride 3");
        assert!(subset.iter().enumerate().all(|(k, p)| p.x == (3 * k) as f32));
        assert_eq!(
            stride_subset(&cloud, 1_000),
            cloud,
            "a cap at the size keeps every point"
        );
        assert_eq!(stride_subset(&cloud, usize::MAX), cloud);
        assert_eq!(stride_subset(&cloud, 0).len(), 3, "never fewer than 3 points asked");
    }
}
