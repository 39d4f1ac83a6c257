//! A member's training rays, moved into its NOCS frame and appended to a category's samples.

use nalgebra::{Point3, Similarity3};

use super::CategorySamples;
use crate::error::{CatmapError, Result};
use crate::field::RaySamples;

impl CategorySamples {
    /// Appends `rays` of member `member`. Their sample points are relative to `field_origin`
    /// (as [`crate::field::sample_training_rays`] returns them); each becomes
    /// p_nocs = nocs_from_world · (p + field_origin). Depths stay metric: rendering and the depth
    /// loss compare them with the measured depth along the same ray. Errors when the samples per
    /// ray differ from those already held.
    pub fn push_member_rays(
        &mut self,
        mut rays: RaySamples,
        member: usize,
        field_origin: &Point3<f32>,
        nocs_from_world: &Similarity3<f32>,
    ) -> Result<()> {
        rays.validate()?;
        if self.rays.num_rays() > 0 && rays.samples_per_ray != self.rays.samples_per_ray {
            return Err(CatmapError::mismatch(
                "a member's samples per ray",
                self.rays.samples_per_ray,
                rays.samples_per_ray,
            ));
        }
        for p in &mut rays.points {
            let q = nocs_from_world * (Point3::from(*p) + field_origin.coords);
            *p = [q.x, q.y, q.z];
        }
        self.rays.samples_per_ray = rays.samples_per_ray;
        // Every member's prior rays carry its field's one weight (none without prior rays).
        self.rays.solid_weight = self.rays.solid_weight.max(rays.solid_weight);
        self.members.extend(std::iter::repeat_n(member, rays.num_rays()));
        self.rays.points.extend(rays.points);
        self.rays.z.extend(rays.z);
        self.rays.depth_m.extend(rays.depth_m);
        self.rays.rgb.extend(rays.rgb);
        self.rays.states.extend(rays.states);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Vector3};

    use super::*;
    use crate::objects::object_view::PixelState;

    #[test]
    fn points_land_in_nocs_and_members_are_recorded() {
        let rays = RaySamples {
            samples_per_ray: 2,
            points: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]],
            z: vec![1.0, 2.0],
            depth_m: vec![1.5],
            rgb: vec![[0.1, 0.2, 0.3]],
            states: vec![PixelState::ThisObject],
            ..RaySamples::default()
        };
        // World box centred at (1, 2, 3), scale 2: world (1, 2, 3) is the NOCS origin.
        let world_from_nocs = Similarity3::from_isometry(Isometry3::translation(1.0, 2.0, 3.0), 2.0);
        let mut samples = CategorySamples::default();
        samples
            .push_member_rays(rays.clone(), 4, &Point3::new(1.0, 2.0, 3.0), &world_from_nocs.inverse())
            .unwrap();
        assert_eq!(samples.members, vec![4]);
        assert_eq!(samples.rays.points[0], [0.0, 0.0, 0.0]);
        assert!((Vector3::from(samples.rays.points[1]) - Vector3::new(0.5, 0.0, 0.0)).norm() < 1e-6);
        assert_eq!(samples.rays.z, rays.z, "depths stay metric");
        assert_eq!(samples.rays.solid_weight, 0.0, "no prior rays, no prior weight");
        let prior = RaySamples {
            samples_per_ray: 2,
            points: vec![[1.0, 2.0, 3.0]; 2],
            z: vec![0.0, 1.0],
            depth_m: vec![0.0],
            rgb: vec![[0.0; 3]],
            states: vec![PixelState::HiddenSolid],
            solid_weight: 0.5,
            ..RaySamples::default()
        };
        samples
            .push_member_rays(prior, 5, &Point3::origin(), &world_from_nocs.inverse())
            .unwrap();
        samples
            .push_member_rays(rays.clone(), 4, &Point3::new(1.0, 2.0, 3.0), &world_from_nocs.inverse())
            .unwrap();
        assert_eq!(
            samples.rays.solid_weight, 0.5,
            "a member's prior rays keep their weight"
        );
        let mut three = rays;
        three.samples_per_ray = 1;
        three.depth_m.push(1.0);
        three.rgb.push([0.0; 3]);
        three.states.push(PixelState::ThisObject);
        assert!(
            samples
                .push_member_rays(three, 0, &Point3::origin(), &Similarity3::identity())
                .is_err()
        );
    }
}
