//! A noisy surface's points moved onto the plane their neighbours lie on (one step of a
//! moving-least-squares projection).
//!
//! A depth camera's noise grows with distance (σ ≈ 3 cm at 4.5 m for a Kinect v1). Summed over
//! many frames, a flat face seen from afar is no longer a sheet of points but a shell a few
//! centimetres thick, and whatever reads the cloud's extremes reads the shell's: a box fitted to
//! a cabinet seen from 5 m reached 5 cm in front of its doors, and its mirror plane — the box's
//! middle, matched at 2.5 cm — followed. Each point is replaced by its projection onto the
//! least-squares plane of the points within a radius of it, when those points lie near a plane
//! (the smallest spread of their covariance is at most [`MAX_FLATNESS`] of the whole): the
//! shell's points all land on its middle sheet. Points with fewer than [`MIN_NEIGHBOURS`]
//! neighbours, and points where the neighbourhood is no plane (a thin leg, a corner seen
//! closely), stay where they are.

use nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use rayon::prelude::*;

use super::nearest::PointIndex;

/// Fewest points within the radius (the point itself included) for a plane to be fitted.
pub const MIN_NEIGHBOURS: usize = 8;

/// Largest share of the neighbourhood's spread (the sum of its covariance's eigenvalues) that
/// its smallest eigenvalue may hold for the neighbourhood to count as a plane: a disc of radius r
/// holds r²/4 along each of its two directions, so a shell of thickness σ is a plane while
/// σ² ≤ 0.25 · r²/2, i.e. σ up to 0.35 r.
pub const MAX_FLATNESS: f64 = 0.2;

/// Least share of the neighbourhood's spread its middle eigenvalue must hold: a line of points
/// (a chair's leg, a lamp's pole) spreads along one direction only, and any plane holds it.
pub const MIN_SECOND_SPREAD: f64 = 0.1;

/// `points` each moved onto the least-squares plane of the points of `reference` within
/// `radius_m` of it (module doc; `reference` may be `points` themselves or a thinned copy, which
/// bounds the work per point); the same points, in order, when `radius_m` is 0 or either set is
/// empty.
pub fn onto_local_planes(points: &[Point3<f32>], reference: &[Point3<f32>], radius_m: f32) -> Vec<Point3<f32>> {
    if radius_m <= 0.0 || points.is_empty() {
        return points.to_vec();
    }
    let Ok(index) = PointIndex::new(reference) else {
        return points.to_vec();
    };
    points
        .par_iter()
        .map(|p| {
            let mut near = index.within(p, radius_m);
            if near.len() < MIN_NEIGHBOURS {
                near = index.within(p, 2.0 * radius_m);
            }
            if near.len() < MIN_NEIGHBOURS {
                return *p;
            }
            let n = near.len() as f64;
            let centre: Vector3<f64> = near
                .iter()
                .map(|&i| index.point(i).coords.cast::<f64>())
                .sum::<Vector3<f64>>()
                / n;
            let covariance: Matrix3<f64> = near
                .iter()
                .map(|&i| {
                    let d = index.point(i).coords.cast::<f64>() - centre;
                    d * d.transpose()
                })
                .sum::<Matrix3<f64>>()
                / n;
            let eigen = SymmetricEigen::new(covariance);
            let mut order = [0, 1, 2];
            order.sort_by(|&a, &b| eigen.eigenvalues[a].total_cmp(&eigen.eigenvalues[b]));
            let [smallest, middle, _] = order;
            let total = eigen.eigenvalues.sum();
            if total <= 0.0
                || eigen.eigenvalues[smallest] > MAX_FLATNESS * total
                || eigen.eigenvalues[middle] < MIN_SECOND_SPREAD * total
            {
                return *p;
            }
            let normal = eigen.eigenvectors.column(smallest).into_owned();
            let offset = (p.coords.cast::<f64>() - centre).dot(&normal);
            Point3::from((p.coords.cast::<f64>() - normal * offset).cast::<f32>())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use rand::RngExt;

    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use crate::rng::standard_normal_f32;

    /// A 40 × 40 cm sheet at z = 0 sampled every centimetre, each point moved along z by
    /// N(0, σ²).
    fn noisy_sheet(sigma_m: f32) -> Vec<Point3<f32>> {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        (0..41 * 41)
            .map(|i| {
                let (x, y) = ((i % 41) as f32 * 0.01 - 0.2, (i / 41) as f32 * 0.01 - 0.2);
                Point3::new(x, y, sigma_m * standard_normal_f32(&mut rng))
            })
            .collect()
    }

    fn spread_z(points: &[Point3<f32>]) -> f32 {
        let inner: Vec<f32> = points
            .iter()
            .filter(|p| p.x.abs() < 0.15 && p.y.abs() < 0.15)
            .map(|p| p.z)
            .collect();
        (inner.iter().map(|z| z * z).sum::<f32>() / inner.len() as f32).sqrt()
    }

    #[test]
    fn a_noisy_sheet_collapses_onto_its_middle_and_its_extremes_come_in() {
        let sheet = noisy_sheet(0.015);
        let projected = onto_local_planes(&sheet, &sheet, 0.05);
        assert_eq!(projected.len(), sheet.len());
        assert!(spread_z(&sheet) > 0.013, "{}", spread_z(&sheet));
        assert!(spread_z(&projected) < 0.006, "{}", spread_z(&projected));
        // Inside its rim (a corner's quarter disc of a shell is no plane, an edge's half disc
        // tilts) the highest point comes from 3σ to within 1.3σ.
        let top = |ps: &[Point3<f32>]| {
            ps.iter()
                .filter(|p| p.x.abs() < 0.15 && p.y.abs() < 0.15)
                .map(|p| p.z)
                .fold(f32::MIN, f32::max)
        };
        assert!(
            top(&sheet) > 0.04 && top(&projected) < 0.02,
            "{} {}",
            top(&sheet),
            top(&projected)
        );
        // Along the sheet the points inside the rim move little on average (a point 2σ off
        // sees a tilted cap of the sheet and slides a centimetre).
        let inside: Vec<f32> = sheet
            .iter()
            .zip(&projected)
            .filter(|(a, _)| a.x.abs() < 0.15 && a.y.abs() < 0.15)
            .map(|(a, b)| (a.xy() - b.xy()).norm())
            .collect();
        let mean = inside.iter().sum::<f32>() / inside.len() as f32;
        assert!(mean < 0.003, "{mean}");
    }

    #[test]
    fn an_exact_sheet_and_a_radius_of_zero_leave_every_point_where_it_is() {
        let sheet = noisy_sheet(0.0);
        for (a, b) in sheet.iter().zip(onto_local_planes(&sheet, &sheet, 0.05)) {
            assert!((a - b).norm() < 1e-5);
        }
        let noisy = noisy_sheet(0.02);
        assert_eq!(onto_local_planes(&noisy, &noisy, 0.0), noisy);
    }

    #[test]
    fn a_thin_pole_and_a_lone_point_stay_where_they_are() {
        // A vertical pole 1 cm thick (no plane around its points) and one stray point.
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let mut points: Vec<Point3<f32>> = (0..200)
            .map(|i| {
                Point3::new(
                    0.005 * rng.random::<f32>(),
                    0.005 * rng.random::<f32>(),
                    i as f32 * 0.005,
                )
            })
            .collect();
        points.push(Point3::new(1.0, 1.0, 1.0));
        let projected = onto_local_planes(&points, &points, 0.03);
        assert_eq!(projected.last(), points.last());
        let moved = points
            .iter()
            .zip(&projected)
            .filter(|(a, b)| (*a - *b).norm() > 1e-4)
            .count();
        assert!(moved < 20, "{moved} of the pole's points moved");
    }
}
