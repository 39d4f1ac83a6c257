//! Fast point feature histograms (Rusu et al., ICRA 2009) and mutual-nearest-neighbour matching:
//! the alternative front end of METHOD.md §4.
//!
//! For a point pair (p_s, n_s), (p_t, n_t) with d = p_t − p_s (source chosen as the one whose
//! normal makes the smaller angle with the line), the Darboux frame u = n_s, v = (d × u)/|d × u|,
//! w = u × v gives three angles: θ = atan2(w·n_t, u·n_t), α = v·n_t, φ = u·d/|d|. SPFH(p) holds
//! 11-bin histograms of θ ∈ [−π, π], α ∈ [−1, 1], φ ∈ [−1, 1] over its neighbours within r, and
//! FPFH(p) = SPFH(p) + (1/k) Σ_k SPFH(p_k)/|p_k − p|, each 11-bin block scaled to sum 100.

use nalgebra::{Point3, Vector3};

use super::consistency::Correspondence;
use crate::geometry::nearest::PointIndex;

/// Bins per angle.
const BINS: usize = 11;
/// Length of a descriptor: three angles × 11 bins.
pub const FPFH_LEN: usize = 3 * BINS;

/// A 33-bin FPFH descriptor.
pub type Fpfh = [f32; FPFH_LEN];

/// FPFH of every point with a normal, over neighbours within `radius_m`; `None` without normal.
pub fn fpfh_descriptors(
    points: &[Point3<f32>],
    normals: &[Option<Vector3<f32>>],
    index: &PointIndex,
    radius_m: f32,
) -> Vec<Option<Fpfh>> {
    let neighbours: Vec<Vec<usize>> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            index
                .within(p, radius_m)
                .into_iter()
                .filter(|&j| j != i && normals[j].is_some())
                .collect()
        })
        .collect();
    let spfh: Vec<Fpfh> = (0..points.len())
        .map(|i| simplified_histogram(i, points, normals, &neighbours[i]))
        .collect();
    (0..points.len())
        .map(|i| {
            normals[i]?;
            let mut descriptor = spfh[i];
            let k = neighbours[i].len().max(1) as f32;
            for &j in &neighbours[i] {
                let weight = 1.0 / ((points[j] - points[i]).norm().max(1e-6) * k);
                for (d, s) in descriptor.iter_mut().zip(&spfh[j]) {
                    *d += weight * s;
                }
            }
            for block in descriptor.chunks_mut(BINS) {
                let sum: f32 = block.iter().sum();
                if sum > 0.0 {
                    block.iter_mut().for_each(|x| *x *= 100.0 / sum);
                }
            }
            Some(descriptor)
        })
        .collect()
}

/// SPFH of point `i` over `neighbours` (all with normals), each block summing to 100.
fn simplified_histogram(
    i: usize,
    points: &[Point3<f32>],
    normals: &[Option<Vector3<f32>>],
    neighbours: &[usize],
) -> Fpfh {
    let mut histogram = [0.0; FPFH_LEN];
    let Some(n_i) = normals[i] else {
        return histogram;
    };
    let features: Vec<[f32; 3]> = neighbours
        .iter()
        .filter_map(|&j| pair_features(&points[i], &n_i, &points[j], &normals[j]?))
        .collect();
    let increment = 100.0 / features.len().max(1) as f32;
    let bin = |x: f32, lo: f32, hi: f32| (((x - lo) / (hi - lo) * BINS as f32) as usize).min(BINS - 1);
    for [theta, alpha, phi] in features {
        histogram[bin(theta, -std::f32::consts::PI, std::f32::consts::PI)] += increment;
        histogram[BINS + bin(alpha, -1.0, 1.0)] += increment;
        histogram[2 * BINS + bin(phi, -1.0, 1.0)] += increment;
    }
    histogram
}

/// (θ, α, φ) of a point pair, or `None` when the frame is undefined.
fn pair_features(p1: &Point3<f32>, n1: &Vector3<f32>, p2: &Point3<f32>, n2: &Vector3<f32>) -> Option<[f32; 3]> {
    let d = p2 - p1;
    let length = d.norm();
    if length < 1e-9 {
        return None;
    }
    let (c1, c2) = (n1.dot(&d) / length, n2.dot(&d) / length);
    // The source is the point whose normal is closer to the connecting line.
    let (u, target, d, phi) = if c1.abs().acos() <= c2.abs().acos() {
        (n1, n2, d, c1)
    } else {
        (n2, n1, -d, -c2)
    };
    let v = d.cross(u);
    let v_norm = v.norm();
    if v_norm < 1e-9 {
        return None;
    }
    let v = v / v_norm;
    let w = u.cross(&v);
    Some([w.dot(target).atan2(u.dot(target)), v.dot(target), phi])
}

/// Pairs (i, j) where template descriptor j is the nearest (L2) to source descriptor i and i
/// the nearest to j. Points without descriptor take no part. Sorted by source index.
pub fn mutual_nearest_neighbours(source: &[Option<Fpfh>], template: &[Option<Fpfh>]) -> Vec<Correspondence> {
    let distance2 = |a: &Fpfh, b: &Fpfh| -> f32 { a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum() };
    let nearest = |query: &Fpfh, set: &[Option<Fpfh>]| -> Option<usize> {
        set.iter()
            .enumerate()
            .filter_map(|(j, d)| d.as_ref().map(|d| (j, distance2(query, d))))
            .min_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)))
            .map(|(j, _)| j)
    };
    source
        .iter()
        .enumerate()
        .filter_map(|(i, d)| {
            let j = nearest(d.as_ref()?, template)?;
            (nearest(template[j].as_ref()?, source)? == i).then_some((i as u32, j as u32))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use nalgebra::Rotation3;

    use super::*;
    use crate::registration::normals::pca_normals;

    /// Points on an ellipsoid, a shape whose points have distinct local geometry.
    fn ellipsoid() -> Vec<Point3<f32>> {
        (0..400)
            .map(|k| {
                let (t, s) = (k as f32 * 2.399_963, (k as f32 + 0.5) / 400.0);
                let (z, r) = (1.0 - 2.0 * s, (1.0 - (1.0 - 2.0 * s).powi(2)).sqrt());
                Point3::new(0.5 * r * t.cos(), 0.3 * r * t.sin(), 0.2 * z)
            })
            .collect()
    }

    fn descriptors(points: &[Point3<f32>]) -> Vec<Option<Fpfh>> {
        let index = PointIndex::new(points).expect("non-empty");
        let normals = pca_normals(points, &index, 0.08);
        fpfh_descriptors(points, &normals, &index, 0.2)
    }

    #[test]
    fn descriptors_are_invariant_to_rigid_motion_and_blocks_sum_to_100() {
        let points = ellipsoid();
        let rotation = Rotation3::from_euler_angles(0.7, -1.1, 2.0);
        let moved: Vec<Point3<f32>> = points
            .iter()
            .map(|p| rotation * p + Vector3::new(1.0, 2.0, 3.0))
            .collect();
        let (a, b) = (descriptors(&points), descriptors(&moved));
        for (da, db) in a.iter().zip(&b) {
            let (da, db) = (
                da.expect("every point has a normal"),
                db.expect("every point has a normal"),
            );
            assert!(da.iter().zip(&db).all(|(x, y)| (x - y).abs() < 0.5), "{da:?} vs {db:?}");
            assert!(
                da.chunks(BINS)
                    .all(|block| (block.iter().sum::<f32>() - 100.0).abs() < 1e-3)
            );
        }
    }

    #[test]
    fn mutual_neighbours_pair_identical_descriptors() {
        let a = [Some([1.0; FPFH_LEN]), Some([5.0; FPFH_LEN]), None];
        let b = [Some([5.1; FPFH_LEN]), Some([0.9; FPFH_LEN]), Some([0.8; FPFH_LEN])];
        assert_eq!(mutual_nearest_neighbours(&a, &b), [(0, 1), (1, 0)]);
    }
}
