//! A vertical mirror-symmetry plane of a point cloud: the plane, among all vertical ones, across
//! which the most points land on another point of the cloud.
//!
//! Most furniture is mirror-symmetric about a vertical plane (a sofa, a bed, a chair, a lamp
//! about any plane through its pole). A cloud seen from one side still shows it: the two arms of
//! a sofa seen from the front, a chair's two front legs. The search scores a plane `n·p = d`
//! (`n` horizontal) by the share of the points off the plane — farther than
//! [`SymmetryConfig::min_off_plane_m`], so that a flat patch does not call its own plane a
//! symmetry — whose reflection lies within [`SymmetryConfig::tolerance_m`] of a point of the
//! cloud: first over a coarse grid of directions and offsets on a subset of the points, then
//! twice finer around the best on all of them, where among the planes whose share is within 5 %
//! of the best the one whose matched reflections land nearest their points wins (a share counted
//! at a 2.5 cm tolerance is flat over a degree or two; a ray reflected across a plane off by 2°
//! grazes the floor under the object). A plane is kept only when that share reaches
//! [`SymmetryConfig::min_matched`]: an asymmetric cloud gets none. A partly seen object's
//! reflections that land in space no view saw are unmatched; whether they contradict what a
//! view saw is the caller's question (`crate::objects::mirror_prior`).
//!
//! Given the object's box ([`MirrorDirections::BoxAxesFirst`]), the search tries the planes
//! parallel to the box's vertical faces first, and every direction only when neither reaches
//! [`SymmetryConfig::min_matched`]. Furniture is built along its box's axes, and an object seen
//! from two adjacent sides shows an L whose bisector maps one side onto the other: a depth
//! camera's nightstand seen from its front and one side (its top lost to noise at a grazing
//! angle) matched 0.99 across its diagonal and 0.66 across its true plane, a cabinet 0.72 and
//! 0.63, a storage box 0.89 and 0.68 even with exact depth. The cost: an object whose plane is
//! oblique to its box and whose box's axes still match enough keeps a plane along them (a
//! corner sofa's arm-parallel plane matches about 0.7 — flat seats match across any plane over
//! their footprint); the sampler drops its reflected rays that land in space a view saw free.

use nalgebra::{Point3, Vector3};
use rayon::prelude::*;

use super::tolerance_grid::ToleranceGrid;

/// A vertical plane `normal · p = offset` (world frame, z up).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MirrorPlane {
    /// Unit horizontal normal.
    pub normal: Vector3<f32>,
    /// Signed distance of the plane from the origin along the normal, metres.
    pub offset: f32,
}

impl MirrorPlane {
    /// The vertical plane at angle `theta` (radians, from world x towards y) of its normal and
    /// `offset` from the origin.
    pub fn vertical(theta: f32, offset: f32) -> Self {
        Self {
            normal: Vector3::new(theta.cos(), theta.sin(), 0.0),
            offset,
        }
    }

    /// Signed distance of `p` from the plane.
    pub fn distance(&self, p: &Point3<f32>) -> f32 {
        self.normal.dot(&p.coords) - self.offset
    }

    /// The mirror image of point `p`.
    pub fn reflect(&self, p: &Point3<f32>) -> Point3<f32> {
        p - self.normal * (2.0 * self.distance(p))
    }

    /// The mirror image of direction `v`.
    pub fn reflect_vector(&self, v: &Vector3<f32>) -> Vector3<f32> {
        v - self.normal * (2.0 * self.normal.dot(v))
    }

    /// The angle between the two planes' normals, radians in [0, π/2] (a plane's normal and its
    /// negation name the same plane).
    pub fn angle_to(&self, other: &MirrorPlane) -> f32 {
        self.normal.dot(&other.normal).abs().min(1.0).acos()
    }
}

/// How the search runs and when a plane counts as found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymmetryConfig {
    /// How near another point a reflection must land to match, metres.
    pub tolerance_m: f32,
    /// Points nearer the plane than this are not scored, metres.
    pub min_off_plane_m: f32,
    /// Share of the scored points that must match for a plane to count.
    pub min_matched: f32,
    /// Share that must match for a second plane, at right angles to the first, to count: a
    /// partly seen object's faces across the first plane match about any plane through their
    /// middle (a cabinet seen from the front matched 0.67 front to back, a bed 0.64; the
    /// tables, stools and nightstands of the six scenes 0.74–0.98).
    pub min_matched_second: f32,
    /// Fewest scored points a plane needs.
    pub min_scored: usize,
}

impl Default for SymmetryConfig {
    fn default() -> Self {
        Self {
            tolerance_m: 0.025,
            min_off_plane_m: 0.04,
            min_matched: 0.6,
            min_matched_second: 0.7,
            min_scored: 40,
        }
    }
}

/// A plane the search found, with its score.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymmetryFit {
    /// The plane.
    pub plane: MirrorPlane,
    /// Share of the scored points whose reflection matched.
    pub matched: f32,
    /// Points scored (off the plane).
    pub scored: usize,
    /// Root mean square distance of the matched reflections to their nearest points, metres.
    pub residual_m: f32,
}

/// Directions of the coarse search (over half a turn).
const COARSE_DIRECTIONS: usize = 36;
/// Offset step of the coarse search, metres.
const COARSE_OFFSET_M: f32 = 0.02;
/// Most points the coarse search scores (every k-th point of the cloud).
const COARSE_POINTS: usize = 300;
/// Most points the fine search scores.
const FINE_POINTS: usize = 3000;
/// Steps each side of the coarse best in the fine search, per parameter.
const FINE_STEPS: i32 = 4;
/// Share of the best matched share a plane of the fine stages must keep to compete on nearness.
const REFINE_KEEP: f32 = 0.95;

/// The best vertical mirror plane of `points` (world frame, z up), if its matched share reaches
/// `cfg.min_matched`; see the module doc.
pub fn find_vertical_mirror(points: &[Point3<f32>], cfg: &SymmetryConfig) -> Option<SymmetryFit> {
    Search::new(points, cfg)?.best(coarse_directions())
}

/// Which directions the search tries for the first plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MirrorDirections {
    /// Every direction.
    Any,
    /// The normals along the two horizontal axes of the object's box, turned `yaw` radians
    /// about world z (from world x), first; every direction only when neither gives a plane
    /// (module doc).
    BoxAxesFirst {
        /// The box's yaw, radians.
        yaw: f32,
    },
}

/// The best vertical mirror plane of `points` among the `directions`, and the best one at
/// right angles to it (within the refinement's few degrees), if their matched shares reach
/// `cfg.min_matched` and `cfg.min_matched_second`: a table, a bed or a box is symmetric end to
/// end as well as side to side, and a table seen from one side with a chair before one end
/// shows the other end. An object symmetric about one plane only (a sofa: its back is not its
/// front) finds none at right angles.
pub fn find_vertical_mirrors(
    points: &[Point3<f32>],
    cfg: &SymmetryConfig,
    directions: MirrorDirections,
) -> (Option<SymmetryFit>, Option<SymmetryFit>) {
    let Some(search) = Search::new(points, cfg) else {
        return (None, None);
    };
    let along_box = match directions {
        MirrorDirections::Any => None,
        MirrorDirections::BoxAxesFirst { yaw } => search.best([yaw, yaw + std::f32::consts::FRAC_PI_2].into_iter()),
    };
    let Some(first) = along_box.or_else(|| search.best(coarse_directions())) else {
        return (None, None);
    };
    let normal = first.plane.normal;
    let right_angle = normal.x.atan2(-normal.y);
    let second = search
        .best(std::iter::once(right_angle))
        .filter(|f| f.matched >= cfg.min_matched_second);
    (Some(first), second)
}

/// The normals' angles of the coarse search: half a turn in [`COARSE_DIRECTIONS`] steps.
fn coarse_directions() -> impl Iterator<Item = f32> {
    let dtheta = std::f32::consts::PI / COARSE_DIRECTIONS as f32;
    (0..COARSE_DIRECTIONS).map(move |t| t as f32 * dtheta)
}

/// A cloud ready to score planes on: its points in a voxel set, the coarse and the fine subsets.
struct Search<'a> {
    cfg: &'a SymmetryConfig,
    cells: ToleranceGrid,
    coarse: Vec<Point3<f32>>,
    fine: Vec<Point3<f32>>,
}

impl<'a> Search<'a> {
    fn new(points: &[Point3<f32>], cfg: &'a SymmetryConfig) -> Option<Self> {
        (points.len() >= cfg.min_scored).then(|| Self {
            cfg,
            cells: ToleranceGrid::new(points, cfg.tolerance_m),
            coarse: every_kth(points, COARSE_POINTS),
            fine: every_kth(points, FINE_POINTS),
        })
    }

    /// The best plane whose normal is at one of the angles `thetas` (radians from world x),
    /// refined to within a few degrees of it.
    fn best(&self, thetas: impl Iterator<Item = f32>) -> Option<SymmetryFit> {
        let (coarse, cfg) = (&self.coarse, self.cfg);
        let mut planes = Vec::new();
        for theta in thetas {
            let normal = Vector3::new(theta.cos(), theta.sin(), 0.0);
            let (lo, hi) = coarse
                .iter()
                .map(|p| normal.dot(&p.coords))
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), s| (lo.min(s), hi.max(s)));
            // A plane within a fifth of the extent from the cloud's end reflects most points out.
            let margin = 0.2 * (hi - lo);
            let steps = ((hi - lo - 2.0 * margin) / COARSE_OFFSET_M).ceil().max(0.0) as usize;
            planes.extend((0..=steps).map(|k| MirrorPlane::vertical(theta, lo + margin + k as f32 * COARSE_OFFSET_M)));
        }
        let fits: Vec<Option<SymmetryFit>> = planes
            .par_iter()
            .map(|plane| score(plane, coarse, &self.cells, cfg, Residual::Skip))
            .collect();
        // The first of the best shares, in candidate order.
        let mut best: Option<SymmetryFit> = None;
        for f in fits.into_iter().flatten() {
            if best.is_none_or(|b| f.matched > b.matched) {
                best = Some(f);
            }
        }
        let coarse_best = best?;
        let around = |centre: MirrorPlane, dtheta: f32, doffset: f32| {
            let theta0 = centre.normal.y.atan2(centre.normal.x);
            (-FINE_STEPS..=FINE_STEPS).flat_map(move |a| {
                (-FINE_STEPS..=FINE_STEPS)
                    .map(move |b| MirrorPlane::vertical(theta0 + a as f32 * dtheta, centre.offset + b as f32 * doffset))
            })
        };
        let step = FINE_STEPS as f32;
        let dtheta = std::f32::consts::PI / COARSE_DIRECTIONS as f32;
        let fine_best = nearest_of_the_best(
            around(coarse_best.plane, dtheta / step, COARSE_OFFSET_M / step),
            &self.fine,
            &self.cells,
            cfg,
        )?;
        let (dtheta, doffset) = (dtheta / (step * step), COARSE_OFFSET_M / (step * step));
        let refined = nearest_of_the_best(around(fine_best.plane, dtheta, doffset), &self.fine, &self.cells, cfg)?;
        Some(refined).filter(|f| f.matched >= cfg.min_matched)
    }
}

/// Among `planes`, those whose matched share is within [`REFINE_KEEP`] of the best, the one whose
/// matched reflections land nearest their points.
fn nearest_of_the_best(
    planes: impl Iterator<Item = MirrorPlane>,
    points: &[Point3<f32>],
    cells: &ToleranceGrid,
    cfg: &SymmetryConfig,
) -> Option<SymmetryFit> {
    let planes: Vec<MirrorPlane> = planes.collect();
    let fits: Vec<SymmetryFit> = planes
        .par_iter()
        .filter_map(|p| score(p, points, cells, cfg, Residual::Measure))
        .collect();
    let best = fits.iter().map(|f| f.matched).fold(0.0f32, f32::max);
    fits.into_iter()
        .filter(|f| f.matched >= REFINE_KEEP * best)
        .min_by(|a, b| a.residual_m.total_cmp(&b.residual_m))
}

/// Whether a score measures the residual of its matched reflections (the coarse stage ranks by
/// share alone, and stops at the first point within the tolerance).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Residual {
    Skip,
    Measure,
}

/// The matched share of `plane` over `points` (`None` with fewer than `cfg.min_scored` scored).
fn score(
    plane: &MirrorPlane,
    points: &[Point3<f32>],
    cells: &ToleranceGrid,
    cfg: &SymmetryConfig,
    residual: Residual,
) -> Option<SymmetryFit> {
    let (mut scored, mut matched, mut sum_sq) = (0usize, 0usize, 0f32);
    for p in points {
        if plane.distance(p).abs() < cfg.min_off_plane_m {
            continue;
        }
        scored += 1;
        let reflected = plane.reflect(p);
        match residual {
            Residual::Skip => matched += usize::from(cells.any_near(&reflected)),
            Residual::Measure => {
                if let Some(d_sq) = cells.nearest_sq(&reflected) {
                    matched += 1;
                    sum_sq += d_sq;
                }
            }
        }
    }
    (scored >= cfg.min_scored).then(|| SymmetryFit {
        plane: *plane,
        matched: matched as f32 / scored as f32,
        scored,
        residual_m: if matched == 0 {
            f32::INFINITY
        } else {
            (sum_sq / matched as f32).sqrt()
        },
    })
}

/// At most `max` points of `points`, every k-th.
fn every_kth(points: &[Point3<f32>], max: usize) -> Vec<Point3<f32>> {
    let k = points.len().div_ceil(max.max(1)).max(1);
    points.iter().step_by(k).copied().collect()
}

#[cfg(test)]
#[path = "mirror_symmetry_tests.rs"]
mod tests;
