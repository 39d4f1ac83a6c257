//! One-way Chamfer distance, scale-normalised: the registration score of METHOD.md §4.
//!
//! CD(P→Q) = (1/|P|) Σ_{p∈P} min_{q∈Q} |p − q|, and the normalised score divides it by the
//! scale of P, s(P) = max(AABB extent of P)/2. The reverse distance of the subcategory rule is the
//! same function with the clouds swapped: `normalised_one_way_chamfer(template, aligned_source)`.

use nalgebra::Point3;

use super::cloud::{check_cloud, half_max_extent};
use crate::error::{CatmapError, Result};
use crate::geometry::nearest::PointIndex;

/// CD(P→Q) = mean over p ∈ `from` of the distance to the closest q ∈ `to`, metres.
pub fn one_way_chamfer(from: &[Point3<f32>], to: &[Point3<f32>]) -> Result<f32> {
    check_cloud(from, "chamfer query", 1)?;
    check_cloud(to, "chamfer reference", 1)?;
    Ok(PointIndex::new(to)?.mean_distance(from))
}

/// CD(P→Q) / s(P) with s(P) = max(AABB extent of P)/2: dimensionless, comparable across
/// objects of different size. Errors when P has no extent.
pub fn normalised_one_way_chamfer(from: &[Point3<f32>], to: &[Point3<f32>]) -> Result<f32> {
    let scale = half_max_extent(from);
    if scale.is_nan() || scale <= 0.0 {
        return Err(CatmapError::bad_value(
            "the half extent of a chamfer query cloud",
            scale,
            "be positive",
        ));
    }
    Ok(one_way_chamfer(from, to)? / scale)
}

/// Trimmed one-way Chamfer: the mean of the smallest fraction ρ of the distances from each
/// point of `from` to the set `index` was built over, divided by s(`from`). Robust to the
/// outliers of a segmented cloud; ranks registration candidates.
pub fn trimmed_normalised_chamfer(from: &[Point3<f32>], index: &PointIndex, keep_fraction: f32) -> f32 {
    let mut d = index.nearest_distances(from);
    let keep = super::icp::kept_count(d.len(), keep_fraction);
    if keep == 0 {
        return f32::INFINITY;
    }
    if keep < d.len() {
        d.select_nth_unstable_by(keep, f32::total_cmp);
    }
    let sum: f64 = d[..keep].iter().map(|&x| f64::from(x)).sum();
    let scale = half_max_extent(from);
    if scale.is_nan() || scale <= 0.0 {
        return f32::INFINITY;
    }
    (sum / keep as f64) as f32 / scale
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shifted_copy_scores_its_shift_over_the_scale() {
        // P = two points 2 m apart (scale 1), Q = P shifted by 0.1 m across: CD = 0.1.
        let p = [Point3::new(0.0, 0.0, 0.0), Point3::new(2.0, 0.0, 0.0)];
        let q = [Point3::new(0.0, 0.1, 0.0), Point3::new(2.0, 0.1, 0.0)];
        assert!((one_way_chamfer(&p, &q).expect("valid") - 0.1).abs() < 1e-6);
        assert!((normalised_one_way_chamfer(&p, &q).expect("valid") - 0.1).abs() < 1e-6);
    }

    #[test]
    fn the_one_way_distance_ignores_unmatched_reference_points() {
        let p = [Point3::new(0.0, 0.0, 0.0), Point3::new(1.0, 0.0, 0.0)];
        let q = [p[0], p[1], Point3::new(5.0, 5.0, 5.0)];
        assert_eq!(one_way_chamfer(&p, &q).expect("valid"), 0.0, "P lies on Q");
        assert!(
            one_way_chamfer(&q, &p).expect("valid") > 1.0,
            "the reverse sees the stray point"
        );
    }

    #[test]
    fn a_cloud_without_extent_has_no_normalised_score() {
        assert!(normalised_one_way_chamfer(&[Point3::origin()], &[Point3::origin()]).is_err());
    }

    #[test]
    fn trimming_ignores_the_farthest_points() {
        // 4 points on a 2 m line (scale 1) at distance 0.1 from Q, one at 10 m: trimmed at 0.8
        // the score is 0.1, untrimmed it is (4·0.1 + 10)/5.
        let q: Vec<_> = (0..=20).map(|i| Point3::new(i as f32 * 0.1, 0.0, 0.0)).collect();
        let mut p: Vec<_> = (0..4).map(|i| Point3::new(i as f32 * 0.5, 0.1, 0.0)).collect();
        p.push(Point3::new(2.0, 10.0, 0.0));
        let index = PointIndex::new(&q).unwrap();
        let scale = half_max_extent(&p);
        assert!((trimmed_normalised_chamfer(&p, &index, 0.8) - 0.1 / scale).abs() < 1e-5);
        assert!((trimmed_normalised_chamfer(&p, &index, 1.0) - 10.4 / 5.0 / scale).abs() < 1e-4);
    }
}
