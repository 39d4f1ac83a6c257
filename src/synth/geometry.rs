//! Everything a ray can hit in a synthetic scene: BVHs over the labelled meshes, plus each
//! triangle's label, colour and unit normal.

use nalgebra::{Point3, Vector3};

use super::bvh::{Bvh, Ray};
use super::room::SurfaceLabel;
use crate::geometry::mesh::TriangleMesh;

/// Colour of triangles whose mesh has no vertex colours.
const UNCOLOURED: [u8; 3] = [180, 180, 180];

/// Per-triangle attributes the renderer needs.
#[derive(Debug, Clone, Copy)]
struct TriangleAttributes {
    normal: Vector3<f32>,
    color: [u8; 3],
    label: SurfaceLabel,
}

/// The nearest surface along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceHit {
    /// Ray parameter of the hit (camera depth for camera rays with z = 1).
    pub t: f32,
    /// Unit geometric normal of the triangle hit (either orientation).
    pub normal: Vector3<f32>,
    /// Base colour of the triangle hit.
    pub color: [u8; 3],
    /// What was hit.
    pub label: SurfaceLabel,
}

/// Labelled triangles behind one BVH.
#[derive(Debug, Clone)]
struct Layer {
    bvh: Bvh,
    attributes: Vec<TriangleAttributes>,
}

impl Layer {
    fn build<'a>(surfaces: impl IntoIterator<Item = (SurfaceLabel, &'a TriangleMesh)>) -> Self {
        let mut corners = Vec::new();
        let mut attributes = Vec::new();
        for (label, mesh) in surfaces {
            for (t, tri) in mesh.triangles.iter().enumerate() {
                let c = mesh.corners(t);
                let normal = (c[1] - c[0])
                    .cross(&(c[2] - c[0]))
                    .try_normalize(1e-12)
                    .unwrap_or_else(Vector3::z);
                let color = mesh
                    .colors
                    .as_ref()
                    .map_or(UNCOLOURED, |colors| colors[tri[0] as usize]);
                corners.push(c);
                attributes.push(TriangleAttributes { normal, color, label });
            }
        }
        Self {
            bvh: Bvh::build(&corners),
            attributes,
        }
    }

    fn cast(&self, ray: &Ray, t_max: f32) -> Option<SurfaceHit> {
        let hit = self.bvh.nearest_hit(ray, t_max)?;
        let a = &self.attributes[hit.triangle as usize];
        Some(SurfaceHit {
            t: hit.t,
            normal: a.normal,
            color: a.color,
            label: a.label,
        })
    }
}

/// The scene's labelled triangles in two layers: the few large background surfaces (room), cast
/// first, and the many small object triangles, cast only up to the background hit. The object
/// BVH's root then bounds the furniture alone, so rays aimed above it finish after one box test.
#[derive(Debug, Clone)]
pub struct SceneGeometry {
    background: Layer,
    objects: Layer,
}

impl SceneGeometry {
    /// Builds the geometry from labelled background and object meshes (world coordinates).
    pub fn build<'a, 'b>(
        background: impl IntoIterator<Item = (SurfaceLabel, &'a TriangleMesh)>,
        objects: impl IntoIterator<Item = (SurfaceLabel, &'b TriangleMesh)>,
    ) -> Self {
        Self {
            background: Layer::build(background),
            objects: Layer::build(objects),
        }
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.background.attributes.len() + self.objects.attributes.len()
    }

    /// The nearest surface hit by `origin + t·direction` with `t < t_max`.
    pub fn cast(&self, origin: Point3<f32>, direction: Vector3<f32>, t_max: f32) -> Option<SurfaceHit> {
        let ray = Ray { origin, direction };
        let background = self.background.cast(&ray, t_max);
        self.objects
            .cast(&ray, background.map_or(t_max, |hit| hit.t))
            .or(background)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::ClassId;

    #[test]
    fn cast_reports_the_label_and_colour_of_the_nearest_mesh() {
        let square = |z: f32| {
            let v = [[-1.0, -1.0, z], [1.0, -1.0, z], [1.0, 1.0, z], [-1.0, 1.0, z]].map(Point3::from);
            TriangleMesh::new(v.to_vec(), vec![[0, 1, 2], [0, 2, 3]])
        };
        let near = square(1.0).with_uniform_color([9, 8, 7]);
        let far = square(2.0);
        let (near_label, far_label) = (
            SurfaceLabel {
                instance_id: 1,
                class: ClassId(20),
            },
            SurfaceLabel {
                instance_id: 2,
                class: ClassId(80),
            },
        );
        let geometry = SceneGeometry::build([(far_label, &far)], [(near_label, &near)]);
        assert_eq!(geometry.triangle_count(), 4);
        let hit = geometry
            .cast(Point3::origin(), Vector3::new(0.1, 0.2, 1.0), f32::INFINITY)
            .expect("hits");
        assert_eq!((hit.label, hit.color), (near_label, [9, 8, 7]));
        assert!((hit.t - 1.0).abs() < 1e-6 && (hit.normal.norm() - 1.0).abs() < 1e-6);
        let behind = geometry
            .cast(Point3::new(0.0, 0.0, 1.5), Vector3::z(), f32::INFINITY)
            .expect("hits");
        assert_eq!((behind.label, behind.color), (far_label, UNCOLOURED));
    }
}
