//! The rotations a registration starts from ([`start_rotations`]; module doc of
//! [`super::register`], step 1) and the robust start turned upright ([`upright_start`]).

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};

use super::RegistrationConfig;
use super::config::Rotations;
use super::cube_rotations::cube_rotations;
use super::horn::nearest_turn_about_z;

/// Start rotations: C_kᵀ for the 24 cube rotations, each also composed with the `twists`; with
/// [`Rotations::AboutUp`], turns about z every `twist_deg` (every 90° without twists).
pub(super) fn start_rotations(cfg: &RegistrationConfig) -> Vec<UnitQuaternion<f64>> {
    let angle = f64::from(cfg.twist_deg).to_radians();
    if cfg.rotations == Rotations::AboutUp {
        let step = if cfg.twists > 0 && angle > 0.0 {
            angle
        } else {
            std::f64::consts::FRAC_PI_2
        };
        let count = (std::f64::consts::TAU / step).round().max(1.0) as usize;
        return (0..count)
            .map(|k| UnitQuaternion::from_axis_angle(&Vector3::z_axis(), k as f64 * step))
            .collect();
    }
    let mut twists = vec![UnitQuaternion::identity()];
    if cfg.twists > 0 {
        for axis in [Vector3::x(), Vector3::y(), Vector3::z()] {
            for sign in [1.0, -1.0] {
                twists.push(UnitQuaternion::from_axis_angle(
                    &Unit::new_normalize(axis * sign),
                    angle,
                ));
            }
        }
    }
    cube_rotations()
        .iter()
        .flat_map(|cube| {
            let base = UnitQuaternion::from_rotation_matrix(&cube.transpose().cast::<f64>());
            twists.iter().map(move |twist| base * twist)
        })
        .collect()
}

/// `pose` turned to the turn about z nearest its rotation, its translation aligning the
/// clouds' centroids as the pose did.
pub(super) fn upright_start(pose: &Isometry3<f64>, source: &[Point3<f32>]) -> Isometry3<f64> {
    let turn = UnitQuaternion::from_rotation_matrix(&nearest_turn_about_z(&pose.rotation.to_rotation_matrix()));
    let source_centroid = centroid(source);
    let moved_centroid = pose * Point3::from(source_centroid);
    Isometry3::from_parts(Translation3::from(moved_centroid.coords - turn * source_centroid), turn)
}

/// The mean of `points` (the origin for none).
pub(super) fn centroid(points: &[Point3<f32>]) -> Vector3<f64> {
    points.iter().map(|p| p.coords.cast::<f64>()).sum::<Vector3<f64>>() / points.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn any_rotation_starts_from_168_and_about_up_from_12_upright_turns() {
        let any = RegistrationConfig::default();
        assert_eq!(start_rotations(&any).len(), 24 * 7);
        let up = RegistrationConfig {
            rotations: Rotations::AboutUp,
            ..RegistrationConfig::default()
        };
        let turns = start_rotations(&up);
        assert_eq!(turns.len(), 12, "one every 30°");
        assert!(turns.iter().all(|r| ((r * Vector3::z()).z - 1.0).abs() < 1e-12));
        let without_twists = RegistrationConfig { twists: 0, ..up };
        assert_eq!(start_rotations(&without_twists).len(), 4, "one every 90°");
    }
}
