//! The mesh of one occupancy field over a box: marching cubes at the configured occupancy level,
//! vertex colours from the field's colour head, in world coordinates.

use nalgebra::Point3;

use super::object_grid::{ObjectFrame, ObjectMeshConfig, extract_object_mesh, paint_vertices};
use crate::categories::nocs::NocsFrame;
use crate::error::Result;
use crate::field::OccupancyField;
use crate::field::category::CategoryField;
use crate::geometry::mesh::TriangleMesh;

/// Meshes `field` (defined relative to `field_origin`, i.e. at world point `p` it is evaluated at
/// `p − field_origin`) over the grid of `frame`. An unoccupied field gives an empty mesh.
pub fn mesh_occupancy_field(
    field: &OccupancyField,
    field_origin: &Point3<f32>,
    frame: &ObjectFrame,
    config: &ObjectMeshConfig,
) -> Result<TriangleMesh> {
    let mut mesh = extract_object_mesh(frame, config, |points| field.eval_occupancy_world(field_origin, points))?;
    if !mesh.is_empty() {
        paint_vertices(&mut mesh, |points| {
            field
                .eval_world(field_origin, points)
                .colour
                .iter()
                .map(|c| to_rgb8(*c))
                .collect()
        })?;
    }
    Ok(mesh)
}

/// Meshes member `member` of a category field over its NOCS frame: the grid covers the member's
/// box (enlarged by 1/`box_fill`), world points are mapped into NOCS before evaluation, and the
/// mesh comes out in world coordinates. An unoccupied member gives an empty mesh.
pub fn mesh_category_member(
    field: &CategoryField,
    member: usize,
    nocs: &NocsFrame,
    config: &ObjectMeshConfig,
) -> Result<TriangleMesh> {
    let scale = nocs.world_from_nocs.scaling();
    let frame = ObjectFrame {
        world_from_object: nocs.world_from_nocs,
        extents: nocs.extents / scale,
    };
    let nocs_from_world = nocs.world_from_nocs.inverse();
    let to_nocs = |points: &[Point3<f32>]| -> Vec<[f32; 3]> {
        points
            .iter()
            .map(|p| {
                let q = nocs_from_world * p;
                [q.x, q.y, q.z]
            })
            .collect()
    };
    let mut failure = None;
    let mut mesh = extract_object_mesh(&frame, config, |points| {
        field.eval_occupancy(member, &to_nocs(points)).unwrap_or_else(|e| {
            failure = Some(e);
            vec![0.0; points.len()]
        })
    })?;
    if !mesh.is_empty() && failure.is_none() {
        paint_vertices(&mut mesh, |points| match field.eval(member, &to_nocs(points)) {
            Ok(eval) => eval.colour.iter().map(|c| to_rgb8(*c)).collect(),
            Err(e) => {
                failure = Some(e);
                vec![[0; 3]; points.len()]
            }
        })?;
    }
    match failure {
        Some(e) => Err(e),
        None => Ok(mesh),
    }
}

/// A field colour in [0, 1] as 8-bit RGB.
fn to_rgb8(c: [f32; 3]) -> [u8; 3] {
    c.map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Similarity3, Translation3, Vector3};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::field::{AdamWConfig, FieldBatch, RaySamples};
    use crate::objects::object_view::PixelState;

    /// Rays along +z from z = −1 hitting a plane at z = 0 (in the field frame), over a 0.4 m square.
    fn plane_rays(rng: &mut ChaCha8Rng) -> RaySamples {
        use rand::RngExt;
        let mut rays = RaySamples {
            samples_per_ray: 10,
            ..Default::default()
        };
        for _ in 0..120 {
            let (x, y) = (rng.random_range(-0.2..0.2f32), rng.random_range(-0.2..0.2f32));
            for s in 0..10 {
                let z = if s == 0 {
                    rng.random_range(0.0..0.9f32)
                } else {
                    0.9 + 0.02 * s as f32
                };
                rays.points.push([x, y, z - 1.0]);
                rays.z.push(z);
            }
            rays.depth_m.push(1.0);
            rays.rgb.push([0.9, 0.1, 0.1]);
            rays.states.push(PixelState::ThisObject);
        }
        rays
    }

    #[test]
    fn a_field_trained_on_a_wall_meshes_near_the_wall_in_world_coordinates() {
        let mut rng = ChaCha8Rng::seed_from_u64(2);
        let mut batch = FieldBatch::new(AdamWConfig {
            lr: 5e-3,
            ..AdamWConfig::default()
        });
        batch.push(OccupancyField::new(32, 2.0, &mut rng));
        for _ in 0..300 {
            let samples = vec![plane_rays(&mut rng)];
            batch.train_step(&samples).expect("train");
        }
        let origin = Point3::new(3.0, 0.0, 0.0);
        let frame = ObjectFrame {
            world_from_object: Similarity3::from_isometry(
                Isometry3::from_parts(Translation3::new(3.0, 0.0, 0.0), Default::default()),
                1.0,
            ),
            extents: Vector3::new(0.3, 0.3, 0.4),
        };
        let cfg = ObjectMeshConfig {
            voxel_size_m: 0.02,
            ..ObjectMeshConfig::default()
        };
        let mesh = mesh_occupancy_field(&batch.fields()[0], &origin, &frame, &cfg).expect("mesh");
        assert!(!mesh.is_empty(), "the trained wall is occupied behind z = 0");
        // The occupied slab behind the wall is closed by the grid, so only its front face must
        // sit on the wall: nothing lies in the free space in front of it.
        let in_free_space = mesh.vertices.iter().filter(|v| v.z < -0.06).count();
        assert_eq!(in_free_space, 0, "no surface in front of the wall");
        let on_wall = mesh
            .vertices
            .iter()
            .filter(|v| v.z.abs() < 0.03 && (v.x - 3.0).abs() < 0.1)
            .count();
        assert!(
            on_wall > 50,
            "the front face lies on the wall (x near 3 m): {on_wall} vertices"
        );
        let colors = mesh.colors.as_ref().expect("painted");
        let reddish = colors.iter().filter(|c| c[0] > c[1] && c[0] > c[2]).count();
        assert!(reddish * 2 > colors.len(), "colours come from the colour head");
    }
}
