//! Where a ray's free-space samples go, and how many of a field's samples inside its object's box
//! tell the field that space is empty ("carve" it).
//!
//! vMAP's sampler draws a ray's free-space samples stratified over `[0, d − band]` from the camera
//! (d the measured depth): on a ray that crosses the object's box for 30 cm out of 2 m, one such
//! sample lands inside the box about one time in seven, and the space the field is meshed in —
//! under a tabletop, behind a sofa's back as seen from the side — hears little of what the views
//! say is empty there. The carving sampler puts `box_free_samples` of them on the part of the
//! ray that crosses the object's box before the surface band, `[max(t_in, 0), min(t_out, d − band)]`
//! (t along the ray in camera depth); a ray that does not cross the box there (it meets the
//! surface where it enters the box, or misses the box) gets them stratified from the camera as
//! before, so every ray keeps the same number of samples.

use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::geometry::oriented_box::OrientedBox;

/// Samples of a field's steps inside its object's box: all of them, and those that lie before
/// their ray's surface band (free space the loss asks to be empty).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct CarveCounts {
    /// Samples inside the box.
    pub inside: u64,
    /// Of those, the samples before their ray's surface band (valid depth only).
    pub carving: u64,
}

impl std::ops::Add for CarveCounts {
    type Output = Self;

    /// The two counts summed.
    fn add(self, o: Self) -> Self {
        Self {
            inside: self.inside + o.inside,
            carving: self.carving + o.carving,
        }
    }
}

impl CarveCounts {
    /// The share of the samples inside the box that carve free space (0 with none inside).
    pub fn share(&self) -> f64 {
        if self.inside == 0 {
            0.0
        } else {
            self.carving as f64 / self.inside as f64
        }
    }
}

/// The parameters `t` (points `origin + t·dir`) where the ray is inside `b`, as `[t_in, t_out]`
/// (slab test in the box frame; `dir` need not be unit). `None` when the line misses the box.
pub fn ray_box_interval(b: &OrientedBox, origin: &Point3<f32>, dir: &Vector3<f32>) -> Option<(f32, f32)> {
    let o = b.world_from_box.inverse_transform_point(origin);
    let d = b.world_from_box.inverse_transform_vector(dir);
    let (mut t_in, mut t_out) = (f32::NEG_INFINITY, f32::INFINITY);
    for k in 0..3 {
        let h = b.half_extents[k];
        if d[k].abs() < 1e-12 {
            if o[k].abs() > h {
                return None;
            }
            continue;
        }
        let (a, c) = ((-h - o[k]) / d[k], (h - o[k]) / d[k]);
        t_in = t_in.max(a.min(c));
        t_out = t_out.min(a.max(c));
    }
    (t_in <= t_out).then_some((t_in, t_out))
}

/// The depth interval in which a ray carves its object's box: the part of `[0, free_end]` (free
/// space before the surface band) of the ray's `crossing` of the box ([`ray_box_interval`]), when
/// it is longer than `min_length`.
pub fn carving_interval(crossing: (f32, f32), free_end: f32, min_length: f32) -> Option<(f32, f32)> {
    let (near, far) = (crossing.0.max(0.0), crossing.1.min(free_end));
    (far - near > min_length).then_some((near, far))
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, UnitQuaternion};

    use super::*;

    fn unit_box_at(x: f32, yaw: f32) -> OrientedBox {
        OrientedBox {
            world_from_box: Isometry3::from_parts(
                nalgebra::Translation3::new(x, 0.0, 0.0),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            ),
            half_extents: Vector3::new(0.5, 0.5, 0.5),
        }
    }

    #[test]
    fn a_ray_through_a_box_enters_and_leaves_on_its_faces() {
        let b = unit_box_at(3.0, 0.0);
        let (t_in, t_out) = ray_box_interval(&b, &Point3::origin(), &Vector3::new(2.0, 0.0, 0.0)).unwrap();
        assert!(
            (t_in - 1.25).abs() < 1e-6 && (t_out - 1.75).abs() < 1e-6,
            "{t_in} {t_out}"
        );
        // Turned by 45° about z, the box's corner faces the ray: it enters at x = 3 − √2/2.
        let turned = unit_box_at(3.0, std::f32::consts::FRAC_PI_4);
        let (t_in, _) = ray_box_interval(&turned, &Point3::origin(), &Vector3::x()).unwrap();
        assert!((t_in - (3.0 - 0.5 * 2f32.sqrt())).abs() < 1e-5, "{t_in}");
        assert!(ray_box_interval(&b, &Point3::new(0.0, 0.6, 0.0), &Vector3::x()).is_none());
        assert!(ray_box_interval(&b, &Point3::new(0.0, 0.0, 2.0), &Vector3::x()).is_none());
    }

    #[test]
    fn the_carving_interval_stops_at_the_surface_band_and_starts_at_the_camera() {
        let b = unit_box_at(3.0, 0.0);
        let crossing = ray_box_interval(&b, &Point3::origin(), &Vector3::x()).expect("crosses");
        // The background 5 m away: the whole crossing carves.
        let (near, far) = carving_interval(crossing, 4.9, 0.01).unwrap();
        assert!((near - 2.5).abs() < 1e-6 && (far - 3.5).abs() < 1e-6);
        // The surface 2.8 m away: only the part before its band.
        let (_, far) = carving_interval(crossing, 2.7, 0.01).unwrap();
        assert!((far - 2.7).abs() < 1e-6);
        // The surface where the ray enters the box: nothing to carve.
        assert!(carving_interval(crossing, 2.4, 0.01).is_none());
        // A camera inside the box carves from itself.
        let inside = ray_box_interval(&b, &Point3::new(3.0, 0.0, 0.0), &Vector3::x()).expect("inside");
        let (near, _) = carving_interval(inside, 4.0, 0.01).unwrap();
        assert_eq!(near, 0.0);
    }

    #[test]
    fn the_share_is_of_the_samples_inside_the_box() {
        let c = CarveCounts { inside: 8, carving: 2 } + CarveCounts { inside: 2, carving: 1 };
        assert_eq!(c, CarveCounts { inside: 10, carving: 3 });
        assert!((c.share() - 0.3).abs() < 1e-12);
        assert_eq!(CarveCounts::default().share(), 0.0);
    }
}
