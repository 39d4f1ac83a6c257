//! Weighted least-squares rotation and rigid transform between matched vectors (Horn/Kabsch).
//!
//! Rotation only: R* = argmin_{R ∈ SO(3)} Σ w_i |b_i − R a_i|². With H = Σ w_i a_i b_iᵀ = U S Vᵀ,
//! R* = V diag(1, 1, det(V Uᵀ)) Uᵀ (the diag term keeps R proper).
//! Rigid: the same on centred points a_i − ā, b_i − b̄ (weighted centroids), then t* = b̄ − R* ā.
//! About z: R restricted to turns θ about z; on the centred points, θ* = atan2(Σ w (a × b)_z,
//! Σ w (a_x b_x + a_y b_y)) (the z components do not depend on θ), then t* = b̄ − R* ā.

use nalgebra::{Matrix3, Rotation3, Vector3};

/// R* = argmin Σ w_i |b_i − R a_i|² over rotations. Identity when the weights vanish.
pub fn weighted_rotation(a: &[Vector3<f64>], b: &[Vector3<f64>], weights: &[f64]) -> Rotation3<f64> {
    debug_assert_eq!(a.len(), b.len(), "one b per a");
    debug_assert_eq!(a.len(), weights.len(), "one weight per pair");
    let mut h = Matrix3::zeros();
    for ((ai, bi), &w) in a.iter().zip(b).zip(weights) {
        h += w * ai * bi.transpose();
    }
    rotation_from_cross_covariance(&h)
}

/// (R*, t*) = argmin Σ w_i |b_i − (R a_i + t)|². Identity when the weights vanish.
pub fn weighted_rigid(a: &[Vector3<f64>], b: &[Vector3<f64>], weights: &[f64]) -> (Rotation3<f64>, Vector3<f64>) {
    let total: f64 = weights.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return (Rotation3::identity(), Vector3::zeros());
    }
    let centroid = |v: &[Vector3<f64>]| v.iter().zip(weights).map(|(x, &w)| w * x).sum::<Vector3<f64>>() / total;
    let (a_mean, b_mean) = (centroid(a), centroid(b));
    let mut h = Matrix3::zeros();
    for ((ai, bi), &w) in a.iter().zip(b).zip(weights) {
        h += w * (ai - a_mean) * (bi - b_mean).transpose();
    }
    let rotation = rotation_from_cross_covariance(&h);
    (rotation, b_mean - rotation * a_mean)
}

/// (R*, t*) = argmin Σ w_i |b_i − (R a_i + t)|² over turns R about z. Identity when the weights
/// vanish.
pub fn weighted_rigid_about_z(
    a: &[Vector3<f64>],
    b: &[Vector3<f64>],
    weights: &[f64],
) -> (Rotation3<f64>, Vector3<f64>) {
    let total: f64 = weights.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return (Rotation3::identity(), Vector3::zeros());
    }
    let centroid = |v: &[Vector3<f64>]| v.iter().zip(weights).map(|(x, &w)| w * x).sum::<Vector3<f64>>() / total;
    let (a_mean, b_mean) = (centroid(a), centroid(b));
    let (mut sin, mut cos) = (0.0, 0.0);
    for ((ai, bi), &w) in a.iter().zip(b).zip(weights) {
        let (p, q) = (ai - a_mean, bi - b_mean);
        sin += w * (p.x * q.y - p.y * q.x);
        cos += w * (p.x * q.x + p.y * q.y);
    }
    let rotation = Rotation3::from_axis_angle(&Vector3::z_axis(), sin.atan2(cos));
    (rotation, b_mean - rotation * a_mean)
}

/// The turn about z nearest `r` in where it sends the x axis (or, were that upright, the y
/// axis) on the floor.
pub fn nearest_turn_about_z(r: &Rotation3<f64>) -> Rotation3<f64> {
    let x = r * Vector3::x();
    let heading = if x.x.hypot(x.y) > 1e-6 {
        x.y.atan2(x.x)
    } else {
        let y = r * Vector3::y();
        y.y.atan2(y.x) - std::f64::consts::FRAC_PI_2
    };
    Rotation3::from_axis_angle(&Vector3::z_axis(), heading)
}

/// Geodesic angle between two rotations, radians: acos((tr(AᵀB) − 1)/2), clamped so rounding
/// never gives NaN.
pub fn rotation_angle_between(a: &Rotation3<f64>, b: &Rotation3<f64>) -> f64 {
    let cos = ((a.matrix().transpose() * b.matrix()).trace() - 1.0) / 2.0;
    cos.clamp(-1.0, 1.0).acos()
}

fn rotation_from_cross_covariance(h: &Matrix3<f64>) -> Rotation3<f64> {
    if !h.iter().all(|x| x.is_finite()) || h.norm() <= 0.0 {
        return Rotation3::identity();
    }
    let svd = h.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Rotation3::identity();
    };
    let v = v_t.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    Rotation3::from_matrix_unchecked(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_vectors() -> Vec<Vector3<f64>> {
        vec![
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 2.0, 0.0),
            Vector3::new(0.0, 0.0, 3.0),
            Vector3::new(1.0, 1.0, -1.0),
            Vector3::new(-0.5, 0.3, 0.8),
        ]
    }

    #[test]
    fn exact_data_gives_back_the_rotation() {
        let truth = Rotation3::from_euler_angles(0.3, -1.2, 2.5);
        let a = sample_vectors();
        let b: Vec<_> = a.iter().map(|x| truth * x).collect();
        let r = weighted_rotation(&a, &b, &[1.0; 5]);
        assert!(rotation_angle_between(&r, &truth) < 1e-9);
    }

    #[test]
    fn exact_data_gives_back_the_rigid_transform_and_zero_weights_mute_outliers() {
        let truth = Rotation3::from_euler_angles(-2.0, 0.4, 0.1);
        let t = Vector3::new(0.5, -1.0, 2.0);
        let a = sample_vectors();
        let mut b: Vec<_> = a.iter().map(|x| truth * x + t).collect();
        b[4] = Vector3::new(10.0, 10.0, 10.0);
        let (r, t_hat) = weighted_rigid(&a, &b, &[1.0, 1.0, 1.0, 1.0, 0.0]);
        assert!(rotation_angle_between(&r, &truth) < 1e-9);
        assert!((t_hat - t).norm() < 1e-9);
    }

    #[test]
    fn a_reflection_is_never_returned() {
        let a = sample_vectors();
        let b: Vec<_> = a.iter().map(|x| Vector3::new(x.x, x.y, -x.z)).collect();
        assert!((weighted_rotation(&a, &b, &[1.0; 5]).matrix().determinant() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn about_z_gives_back_a_turn_and_stays_upright_where_a_tilt_would_fit_better() {
        let truth = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.7);
        let t = Vector3::new(0.5, -1.0, 0.2);
        let a = sample_vectors();
        let b: Vec<_> = a.iter().map(|x| truth * x + t).collect();
        let (r, t_hat) = weighted_rigid_about_z(&a, &b, &[1.0; 5]);
        assert!(rotation_angle_between(&r, &truth) < 1e-9);
        assert!((t_hat - t).norm() < 1e-9);
        // Matched through a tilt of 0.3 rad about x: the free solve follows it, the turn about z
        // keeps the axis upright.
        let tilted = Rotation3::from_axis_angle(&Vector3::x_axis(), 0.3) * truth;
        let b: Vec<_> = a.iter().map(|x| tilted * x).collect();
        let (free, _) = weighted_rigid(&a, &b, &[1.0; 5]);
        let (upright, _) = weighted_rigid_about_z(&a, &b, &[1.0; 5]);
        assert!((free * Vector3::z()).z < 0.96, "the free solve tilts");
        assert!(
            ((upright * Vector3::z()).z - 1.0).abs() < 1e-12,
            "the turn about z is upright"
        );
    }

    #[test]
    fn the_nearest_turn_about_z_keeps_the_heading() {
        let tilted =
            Rotation3::from_axis_angle(&Vector3::z_axis(), 1.1) * Rotation3::from_axis_angle(&Vector3::x_axis(), 0.2);
        let turn = nearest_turn_about_z(&tilted);
        assert!((turn.angle() - 1.1).abs() < 1e-9, "{}", turn.angle());
        assert!(((turn * Vector3::z()).z - 1.0).abs() < 1e-12);
    }
}
