//! Point-to-point ICP (Besl & McKay) with a correspondence gate and optional trimming (TrICP,
//! Chetverikov et al. 2002).
//!
//! Iteration k: for each source point p_i, its nearest template point q_i under the current
//! transform T_k; pairs with |T_k p_i − q_i| ≤ d_max are kept, of those only the fraction ρ
//! with the smallest distances (ρ = 1: all), and
//! T_{k+1} = argmin_T Σ |q_i − T p_i|² (closed form, [`weighted_rigid`]). Stops after
//! `max_iterations`, when fewer than 3 pairs remain, or when a step turns by less than
//! `step_tolerance` radians and moves by less than `step_tolerance` metres. The points are
//! `f32` (a resolution of about 1e-7 m per metre of distance from the origin), so a tolerance
//! much below 1e-6 is met only when the pairs repeat exactly; pairs that alternate between two
//! sets go on to the cap. 1e-5 (10 µm) is far below the clouds' voxels (centimetres).
//!
//! The nearest template points come from a [`TrackedNearest`]: the same answers as a query per
//! point and iteration, but the k-d tree is asked only when a point moved enough to change them.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};

use super::config::Rotations;
use super::horn::{weighted_rigid, weighted_rigid_about_z};
use crate::geometry::nearest::PointIndex;
use crate::geometry::tracked_nearest::TrackedNearest;

/// Parameters of [`icp_point_to_point`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IcpParams {
    /// Gate d_max on a correspondence's distance, metres.
    pub max_correspondence_m: f32,
    /// Most iterations.
    pub max_iterations: usize,
    /// Fraction ρ ∈ (0, 1] of the gated pairs kept, the closest first (1 = plain ICP).
    pub keep_fraction: f32,
    /// A step smaller than this (radians of turn and metres of move) ends the run.
    pub step_tolerance: f64,
    /// The rotations each step solves over.
    pub rotations: Rotations,
}

/// Why an ICP run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IcpStop {
    /// A step below the tolerance.
    #[default]
    Converged,
    /// Fewer than 3 pairs within the gate.
    TooFewPairs,
    /// `max_iterations` reached.
    IterationCap,
}

/// ICP runs and their iterations, summed (a registration's diagnostics).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IcpCounts {
    /// Runs.
    pub runs: usize,
    /// Iterations over all runs.
    pub iterations: usize,
    /// Runs that reached their iteration cap.
    pub capped: usize,
}

impl IcpCounts {
    /// The counts of one run.
    pub fn of(result: &IcpResult) -> Self {
        Self {
            runs: 1,
            iterations: result.iterations,
            capped: usize::from(result.stop == IcpStop::IterationCap),
        }
    }
}

impl std::ops::Add for IcpCounts {
    type Output = Self;

    fn add(self, other: Self) -> Self {
        Self {
            runs: self.runs + other.runs,
            iterations: self.iterations + other.iterations,
            capped: self.capped + other.capped,
        }
    }
}

/// Outcome of [`icp_point_to_point`].
#[derive(Debug, Clone, PartialEq)]
pub struct IcpResult {
    /// The refined template_from_source.
    pub template_from_source: Isometry3<f64>,
    /// Iterations run.
    pub iterations: usize,
    /// Correspondences within the gate in the last iteration.
    pub correspondences: usize,
    /// Why it stopped.
    pub stop: IcpStop,
}

/// Refines `initial` (template_from_source) by point-to-point ICP of `source` against the
/// template indexed by `template_index`.
pub fn icp_point_to_point(
    source: &[Point3<f32>],
    template_index: &PointIndex,
    initial: Isometry3<f64>,
    params: &IcpParams,
) -> IcpResult {
    let max_d2 = params.max_correspondence_m * params.max_correspondence_m;
    let mut current = initial;
    let mut result = IcpResult {
        template_from_source: initial,
        iterations: 0,
        correspondences: 0,
        stop: IcpStop::IterationCap,
    };
    let mut nearest = TrackedNearest::new(source.len());
    for iteration in 0..params.max_iterations {
        let mut pairs: Vec<(f32, usize, usize)> = source
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                let moved: Point3<f32> = (current * p.cast::<f64>()).cast();
                let (j, d2) = nearest.nearest_within(i, &moved, template_index, max_d2)?;
                Some((d2, i, j))
            })
            .collect();
        let keep = kept_count(pairs.len(), params.keep_fraction);
        if keep < pairs.len() {
            pairs.select_nth_unstable_by(keep, |x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            pairs.truncate(keep);
            pairs.sort_unstable_by_key(|&(_, i, _)| i);
        }
        let a: Vec<_> = pairs.iter().map(|&(_, i, _)| source[i].coords.cast::<f64>()).collect();
        let b: Vec<_> = pairs
            .iter()
            .map(|&(_, _, j)| template_index.point(j).coords.cast::<f64>())
            .collect();
        result.correspondences = a.len();
        if a.len() < 3 {
            result.stop = IcpStop::TooFewPairs;
            break;
        }
        let solve = match params.rotations {
            Rotations::Any => weighted_rigid,
            Rotations::AboutUp => weighted_rigid_about_z,
        };
        let (rotation, translation) = solve(&a, &b, &vec![1.0; a.len()]);
        let next = Isometry3::from_parts(
            Translation3::from(translation),
            UnitQuaternion::from_rotation_matrix(&rotation),
        );
        let step = next * current.inverse();
        current = next;
        result.iterations = iteration + 1;
        if step.rotation.angle() < params.step_tolerance && step.translation.vector.norm() < params.step_tolerance {
            result.stop = IcpStop::Converged;
            break;
        }
    }
    result.template_from_source = current;
    result
}

/// How many of `n` gated pairs a keep fraction ρ retains (at least 3 when there are 3).
pub fn kept_count(n: usize, keep_fraction: f32) -> usize {
    // The small slack keeps an f32 fraction such as 0.8 (0.800000012) from rounding 8 up to 9.
    let keep = (n as f64 * f64::from(keep_fraction.clamp(0.0, 1.0)) - 1e-4)
        .ceil()
        .max(0.0) as usize;
    keep.max(n.min(3)).min(n)
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;

    use super::*;

    #[test]
    fn a_small_misalignment_of_a_grid_is_undone() {
        let template: Vec<Point3<f32>> = (0..1000)
            .map(|i| {
                Point3::new(
                    (i % 10) as f32 * 0.05,
                    (i / 10 % 10) as f32 * 0.05,
                    (i / 100) as f32 * 0.05,
                )
            })
            .map(|p| Point3::new(p.x, p.y + 0.3 * p.x * p.x, p.z))
            .collect();
        let truth = Isometry3::new(Vector3::new(0.01, -0.005, 0.008), Vector3::new(0.02, -0.01, 0.015));
        let source: Vec<Point3<f32>> = template
            .iter()
            .map(|q| (truth.inverse() * q.cast::<f64>()).cast())
            .collect();
        let index = PointIndex::new(&template).expect("non-empty");
        let params = IcpParams {
            max_correspondence_m: 0.03,
            max_iterations: 100,
            keep_fraction: 1.0,
            step_tolerance: 1e-5,
            rotations: Rotations::Any,
        };
        let fit = icp_point_to_point(&source, &index, Isometry3::identity(), &params);
        let error = fit.template_from_source * truth.inverse();
        assert!(
            error.translation.vector.norm() < 1e-4,
            "translation error {:?}",
            error.translation
        );
        assert!(
            error.rotation.angle() < 1e-4,
            "rotation error {}",
            error.rotation.angle()
        );
        assert_eq!(fit.correspondences, 1000, "every point matched at the end");
        assert_eq!(fit.stop, IcpStop::Converged, "within {} iterations", fit.iterations);
    }

    #[test]
    fn trimming_ignores_a_cluster_of_outliers_that_biases_plain_icp() {
        let template: Vec<Point3<f32>> = (0..400)
            .map(|i| {
                Point3::new(
                    (i % 20) as f32 * 0.05,
                    (i / 20) as f32 * 0.05,
                    0.02 * ((i % 7) as f32).sin(),
                )
            })
            .collect();
        let truth = Isometry3::new(Vector3::new(0.02, 0.01, 0.0), Vector3::new(0.0, 0.0, 0.03));
        let mut source: Vec<Point3<f32>> = template
            .iter()
            .map(|q| (truth.inverse() * q.cast::<f64>()).cast())
            .collect();
        // 15 % outliers 8 cm above one corner, inside a wide gate.
        source.extend((0..60).map(|i| Point3::new((i % 8) as f32 * 0.02, (i / 8) as f32 * 0.02, 0.08)));
        let index = PointIndex::new(&template).unwrap();
        let run = |keep_fraction| {
            let params = IcpParams {
                max_correspondence_m: 0.5,
                max_iterations: 100,
                keep_fraction,
                step_tolerance: 1e-5,
                rotations: Rotations::Any,
            };
            let fit = icp_point_to_point(&source, &index, Isometry3::identity(), &params);
            (fit.template_from_source * truth.inverse()).translation.vector.norm()
        };
        assert!(run(1.0) > 5e-3, "the outliers pull plain ICP off");
        assert!(run(0.8) < 1e-3, "trimmed ICP recovers the truth");
    }

    #[test]
    fn kept_count_rounds_up_and_keeps_at_least_three() {
        assert_eq!(kept_count(10, 0.8), 8);
        assert_eq!(kept_count(10, 0.81), 9);
        assert_eq!(kept_count(4, 0.1), 3);
        assert_eq!(kept_count(2, 0.5), 2);
        assert_eq!(kept_count(0, 0.5), 0);
    }
}
