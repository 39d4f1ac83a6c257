//! Point-to-point ICP (Besl & McKay) with a correspondence gate.
//!
//! Iteration k: for each source point p_i, its nearest template point q_i under the current
//! transform T_k; pairs with |T_k p_i − q_i| ≤ d_max are kept, and
//! T_{k+1} = argmin_T Σ |q_i − T p_i|² (closed form, [`weighted_rigid`]). Stops after
//! `max_iterations`, when fewer than 3 pairs remain, or when the transform stops changing.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion};

use super::horn::weighted_rigid;
use crate::nearest::PointIndex;

/// Parameters of [`icp_point_to_point`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IcpParams {
    /// Gate d_max on a correspondence's distance, metres.
    pub max_correspondence_m: f32,
    /// Most iterations.
    pub max_iterations: usize,
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
}

/// Refines `initial` (template_from_source) by point-to-point ICP of `source` against the
/// template indexed by `template_index` (over `template`).
pub fn icp_point_to_point(
    source: &[Point3<f32>],
    template: &[Point3<f32>],
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
    };
    for iteration in 0..params.max_iterations {
        let moved: Vec<Point3<f32>> = source.iter().map(|p| (current * p.cast::<f64>()).cast()).collect();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for (p, moved_p) in source.iter().zip(&moved) {
            let (j, d2) = template_index.nearest(moved_p);
            if d2 <= max_d2 {
                a.push(p.coords.cast::<f64>());
                b.push(template[j].coords.cast::<f64>());
            }
        }
        result.correspondences = a.len();
        if a.len() < 3 {
            break;
        }
        let (rotation, translation) = weighted_rigid(&a, &b, &vec![1.0; a.len()]);
        let next = Isometry3::from_parts(
            Translation3::from(translation),
            UnitQuaternion::from_rotation_matrix(&rotation),
        );
        let step = next * current.inverse();
        current = next;
        result.iterations = iteration + 1;
        if step.rotation.angle() < 1e-7 && step.translation.vector.norm() < 1e-7 {
            break;
        }
    }
    result.template_from_source = current;
    result
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
        };
        let fit = icp_point_to_point(&source, &template, &index, Isometry3::identity(), &params);
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
    }
}
