//! The camera path: a walk along the room's −y side at about 1.4 m, looking into the room with a
//! gentle pan and tilt. Every object is seen from one side only, so its back and underside stay
//! unobserved, and identical chairs at different yaws show different faces.
//!
//! Poses are `world_from_camera` with the OpenCV camera convention (x right, y down, z forward).
//! A view direction is given by yaw ψ (about world z, 0 = looking along +y, positive turns toward
//! +x) and pitch φ (positive looks up): forward `f = (sin ψ cos φ, cos ψ cos φ, sin φ)`, right
//! `r = f × z / |f × z|`, down `d = f × r`; the rotation's columns are `r, d, f`.

use std::f32::consts::{PI, TAU};

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

use super::room::Room;

/// Camera height above the floor, metres.
const EYE_HEIGHT_M: f32 = 1.4;

/// `world_from_camera` rotation of an OpenCV camera looking along yaw `yaw` and pitch `pitch`
/// (radians; |pitch| < π/2).
pub fn look_rotation(yaw: f32, pitch: f32) -> UnitQuaternion<f32> {
    let forward = Vector3::new(yaw.sin() * pitch.cos(), yaw.cos() * pitch.cos(), pitch.sin());
    let right = forward.cross(&Vector3::z()).normalize();
    let down = forward.cross(&right);
    let matrix = Matrix3::from_columns(&[right, down, forward]);
    UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(matrix))
}

/// `frame_count` camera poses sweeping once along the −y wall of `room`.
pub fn camera_trajectory(room: &Room, frame_count: usize) -> Vec<Isometry3<f32>> {
    let span_x = room.half_x_m - 0.7;
    (0..frame_count)
        .map(|i| {
            let s = if frame_count > 1 {
                i as f32 / (frame_count - 1) as f32
            } else {
                0.5
            };
            let x = span_x * (2.0 * s - 1.0);
            let y = -room.half_y_m + 0.45 + 0.1 * (PI * s).sin();
            let z = EYE_HEIGHT_M + 0.04 * (TAU * 2.0 * s).sin();
            // Turn toward the room's centre line, with a slow pan on top; tilt ~20° down.
            let yaw = -0.35 * x / room.half_x_m + 0.4 * (TAU * 1.25 * s).sin();
            let pitch = -0.36 + 0.06 * (TAU * 1.7 * s).sin();
            Isometry3::from_parts(Translation3::new(x, y, z), look_rotation(yaw, pitch))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn look_rotation_follows_the_opencv_convention() {
        let r = look_rotation(0.0, 0.0);
        assert!(
            (r * Vector3::z() - Vector3::y()).norm() < 1e-6,
            "camera z looks along world +y"
        );
        assert!(
            (r * Vector3::x() - Vector3::x()).norm() < 1e-6,
            "camera x is world +x (right)"
        );
        assert!((r * Vector3::y() + Vector3::z()).norm() < 1e-6, "camera y points down");
        let tilted = look_rotation(0.3, -0.4) * Vector3::z();
        assert!(
            tilted.z < 0.0 && tilted.x > 0.0,
            "negative pitch looks down, positive yaw toward +x"
        );
    }

    #[test]
    fn cameras_stay_inside_the_room_at_eye_height_and_look_inwards() {
        let room = Room {
            half_x_m: 2.5,
            half_y_m: 2.25,
            height_m: 2.6,
        };
        let poses = camera_trajectory(&room, 30);
        assert_eq!(poses.len(), 30);
        for pose in &poses {
            let c = Point3::from(pose.translation.vector);
            assert!(
                room.floor().contains(c.x, c.y, 0.3) && (c.z - 1.4).abs() < 0.05,
                "camera at {c}"
            );
            let forward = pose.rotation * Vector3::z();
            assert!(
                forward.y > 0.5 && forward.z < 0.0,
                "looks into the room and down: {forward}"
            );
        }
    }
}
