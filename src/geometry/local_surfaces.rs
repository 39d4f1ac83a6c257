//! A noisy surface's points moved onto the surface their neighbours lie on (one step of a
//! moving-least-squares projection of degree 2).
//!
//! A depth camera's noise grows with distance (σ ≈ 3 cm at 4.5 m for a Kinect v1). Summed over
//! many frames, a flat face seen from afar is no longer a sheet of points but a shell a few
//! centimetres thick, and whatever reads the cloud's extremes reads the shell's: a box fitted to
//! a cabinet seen from 5 m reached 5 cm in front of its doors, and its mirror plane — the box's
//! middle, matched at 2.5 cm — followed. Each point is moved onto the surface of the points within
//! a radius of it, when those points lie near a plane (the smallest spread of their covariance is
//! at most [`MAX_FLATNESS`] of the whole): in the frame of their least-squares plane, the
//! quadric height `w = a u² + b uv + c v² + d u + e v + f` fitted to them is the point's new
//! height. A plane alone pulls a curved surface towards its chords (a lamp's shade 44 cm across,
//! within 8 cm: 1.5 cm; its box and mirror plane came in by 5 cm); the quadric keeps the
//! curvature and drops the noise. The shell's points all land on its middle sheet. A point with
//! fewer than [`MIN_NEIGHBOURS`] neighbours within the radius looks twice as far (the shell's
//! outermost points, a radius off its middle, see only a small cap of it within the radius);
//! points with fewer within twice the radius, and points where the neighbourhood is no plane (a
//! thin leg: a line, its middle spread under [`MIN_SECOND_SPREAD`]; a corner seen closely), stay
//! where they are; where the quadric has no unique fit, the plane is taken.

use nalgebra::{Matrix6, Point3, Vector3, Vector6};
use rayon::prelude::*;

use super::local_plane::LocalPlane;
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

/// `points` each moved onto the least-squares surface of the points of `reference` within
/// `radius_m` of it (module doc; `reference` may be `points` themselves or a thinned copy, which
/// bounds the work per point); the same points, in order, when `radius_m` is 0 or either set is
/// empty.
pub fn onto_local_surfaces(points: &[Point3<f32>], reference: &[Point3<f32>], radius_m: f32) -> Vec<Point3<f32>> {
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
            let Some(plane) = LocalPlane::fit(near.iter().map(|&i| index.point(i).coords.cast::<f64>())) else {
                return *p;
            };
            let [smallest, middle, _] = plane.spreads;
            let total: f64 = plane.spreads.iter().sum();
            if total <= 0.0 || smallest > MAX_FLATNESS * total || middle < MIN_SECOND_SPREAD * total {
                return *p;
            }
            let centre = plane.centre;
            let normal = plane.normal();
            let along = [plane.axes[2], plane.axes[1]];
            let d = p.coords.cast::<f64>() - centre;
            let height = quadric_height(&near, &index, &centre, &normal, &along, &d).unwrap_or(0.0);
            Point3::from((p.coords.cast::<f64>() - normal * (d.dot(&normal) - height)).cast::<f32>())
        })
        .collect()
}

/// The terms of the quadric at offset `d` from the neighbourhood's centre, in the plane's frame
/// (`along` its two directions).
fn quadric_terms(along: &[Vector3<f64>; 2], d: &Vector3<f64>) -> Vector6<f64> {
    let (u, v) = (d.dot(&along[0]), d.dot(&along[1]));
    Vector6::new(u * u, u * v, v * v, u, v, 1.0)
}

/// The height above the plane (`centre`, `normal`) of the least-squares quadric of the points
/// `near` of `index`, at offset `d` from the centre; `None` when the fit is not unique.
fn quadric_height(
    near: &[usize],
    index: &PointIndex,
    centre: &Vector3<f64>,
    normal: &Vector3<f64>,
    along: &[Vector3<f64>; 2],
    d: &Vector3<f64>,
) -> Option<f64> {
    let mut normal_matrix = Matrix6::<f64>::zeros();
    let mut rhs = Vector6::<f64>::zeros();
    for &i in near {
        let q = index.point(i).coords.cast::<f64>() - centre;
        let terms = quadric_terms(along, &q);
        normal_matrix += terms * terms.transpose();
        rhs += terms * q.dot(normal);
    }
    let coefficients = normal_matrix.cholesky()?.solve(&rhs);
    Some(coefficients.dot(&quadric_terms(along, d)))
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
        let projected = onto_local_surfaces(&sheet, &sheet, 0.05);
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
    fn a_noisy_lamp_shade_keeps_its_curvature() {
        // A cylinder of radius 22 cm (a lamp's shade) seen over half its round, every
        // centimetre, each point moved along its radius by N(0, (1.2 cm)²).
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let radius = 0.22_f32;
        let shade: Vec<Point3<f32>> = (0..70)
            .flat_map(|i| (0..30).map(move |k| (i, k)))
            .map(|(i, k)| {
                let angle = -std::f32::consts::FRAC_PI_2 + i as f32 * std::f32::consts::PI / 69.0;
                let r = radius + 0.012 * standard_normal_f32(&mut rng);
                Point3::new(r * angle.cos(), r * angle.sin(), k as f32 * 0.01)
            })
            .collect();
        let projected = onto_local_surfaces(&shade, &shade, 0.08);
        // Away from the rims (the cut edges of the half round, its top and bottom).
        let radial = |ps: &[Point3<f32>]| -> (f32, f32) {
            let inner: Vec<f32> = ps
                .iter()
                .filter(|p| p.y.abs() < 0.15 && p.z > 0.08 && p.z < 0.21)
                .map(|p| p.xy().coords.norm() - radius)
                .collect();
            let mean = inner.iter().sum::<f32>() / inner.len() as f32;
            let rms = (inner.iter().map(|e| e * e).sum::<f32>() / inner.len() as f32).sqrt();
            (mean, rms)
        };
        let (before_mean, before_rms) = radial(&shade);
        let (after_mean, after_rms) = radial(&projected);
        assert!(before_rms > 0.01 && after_rms < 0.005, "{before_rms} → {after_rms}");
        // A plane through 8 cm of the round lies up to 1.5 cm inside it (its chord): moved onto
        // planes, the points came in by 3.5 mm on average; the quadric's surface stays on the
        // round (0.7 mm).
        assert!(
            before_mean.abs() < 0.002 && after_mean.abs() < 0.0015,
            "{before_mean} → {after_mean}"
        );
    }

    #[test]
    fn an_exact_sheet_and_a_radius_of_zero_leave_every_point_where_it_is() {
        let sheet = noisy_sheet(0.0);
        for (a, b) in sheet.iter().zip(onto_local_surfaces(&sheet, &sheet, 0.05)) {
            assert!((a - b).norm() < 1e-5);
        }
        let noisy = noisy_sheet(0.02);
        assert_eq!(onto_local_surfaces(&noisy, &noisy, 0.0), noisy);
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
        let projected = onto_local_surfaces(&points, &points, 0.03);
        assert_eq!(projected.last(), points.last());
        let moved = points
            .iter()
            .zip(&projected)
            .filter(|(a, b)| (*a - *b).norm() > 1e-4)
            .count();
        assert!(moved < 20, "{moved} of the pole's points moved");
    }
}
