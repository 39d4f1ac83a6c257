//! Ray-cast rendering of one camera view: depth, colour, instance id and class per pixel.
//!
//! Pixel `(u, v)` casts `origin = camera centre`, `direction = R·((u − cx)/fx, (v − cy)/fy, 1)`,
//! so the nearest hit's ray parameter is the camera z of the surface: the depth image. Colour is
//! the surface's flat colour times Lambert shading from a fixed light, a little view-facing fill and
//! a deterministic texture: 3 cm value-noise cells in the surface plane, wooden planks on the floor.

use nalgebra::{Isometry3, Point3, Vector3};
use rayon::prelude::*;

use super::geometry::{SceneGeometry, SurfaceHit};
use crate::dataset::classes::{is_replica_background, replica};
use crate::ids::{ClassId, FrameIndex, ObjectId};
use crate::sensor::frame::{CameraIntrinsics, InstanceLabel, InstanceMask, RgbdFrame};

/// Farthest surface the renderer reports, metres along the camera z axis.
pub const MAX_DEPTH_M: f32 = 20.0;

/// One rendered view with the raw images a dataset writer needs.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderedFrame {
    /// Camera pose: maps camera coordinates to world coordinates.
    pub world_from_camera: Isometry3<f32>,
    /// Camera intrinsics.
    pub intrinsics: CameraIntrinsics,
    /// RGB per pixel, row-major.
    pub rgb: Vec<[u8; 3]>,
    /// Camera-z depth in metres; 0 where no surface was hit.
    pub depth_m: Vec<f32>,
    /// Instance id per pixel: object id, ≥ 100 for floor and walls, 0 where nothing was hit.
    pub instance_ids: Vec<u16>,
    /// Semantic class per pixel; `ClassId(0)` where nothing was hit.
    pub classes: Vec<ClassId>,
}

impl RenderedFrame {
    /// The frame as readers produce it: background classes and empty pixels become
    /// [`InstanceLabel::Background`], objects [`InstanceLabel::Object`].
    pub fn into_rgbd_frame(self, index: FrameIndex) -> RgbdFrame {
        let labels = self.instance_ids.iter().zip(&self.classes).map(|(&id, &class)| {
            if id == 0 || is_replica_background(class) {
                InstanceLabel::Background
            } else {
                InstanceLabel::Object(ObjectId(u32::from(id)))
            }
        });
        RgbdFrame {
            index,
            world_from_camera: self.world_from_camera,
            intrinsics: self.intrinsics,
            instances: InstanceMask::from_labels(labels),
            rgb: self.rgb,
            depth_m: self.depth_m,
            classes: self.classes,
        }
    }
}

/// What one pixel sees.
#[derive(Debug, Clone, Copy, Default)]
struct Pixel {
    rgb: [u8; 3],
    depth_m: f32,
    instance_id: u16,
    class: u32,
}

/// Renders the view of a camera at `world_from_camera`, rows in parallel.
pub fn render_view(
    geometry: &SceneGeometry,
    intrinsics: &CameraIntrinsics,
    world_from_camera: &Isometry3<f32>,
) -> RenderedFrame {
    let width = intrinsics.width as usize;
    let origin = Point3::from(world_from_camera.translation.vector);
    let rotation = world_from_camera.rotation.to_rotation_matrix();
    let light = Vector3::new(0.35, -0.45, 0.82).normalize();
    let mut pixels = vec![Pixel::default(); intrinsics.pixel_count()];
    pixels.par_chunks_mut(width.max(1)).enumerate().for_each(|(v, row)| {
        for (u, pixel) in row.iter_mut().enumerate() {
            let direction = rotation * intrinsics.ray_in_camera(u as f32, v as f32);
            if let Some(hit) = geometry.cast(origin, direction, MAX_DEPTH_M) {
                let point = origin + direction * hit.t;
                *pixel = Pixel {
                    rgb: shade(&hit, &point, &direction, &light),
                    depth_m: hit.t,
                    instance_id: hit.label.instance_id,
                    class: hit.label.class.0,
                };
            }
        }
    });
    RenderedFrame {
        world_from_camera: *world_from_camera,
        intrinsics: *intrinsics,
        rgb: pixels.iter().map(|p| p.rgb).collect(),
        depth_m: pixels.iter().map(|p| p.depth_m).collect(),
        instance_ids: pixels.iter().map(|p| p.instance_id).collect(),
        classes: pixels.iter().map(|p| ClassId(p.class)).collect(),
    }
}

/// Colour of a hit seen along `direction`, lit by the unit vector `light` (pointing to the light).
fn shade(hit: &SurfaceHit, point: &Point3<f32>, direction: &Vector3<f32>, light: &Vector3<f32>) -> [u8; 3] {
    let view = direction.normalize();
    let n = if hit.normal.dot(&view) > 0.0 {
        -hit.normal
    } else {
        hit.normal
    };
    let lambert = n.dot(light).max(0.0);
    let facing = (-n.dot(&view)).max(0.0);
    let brightness = (0.35 + 0.45 * lambert + 0.2 * facing) * texture(point, &n, hit.label.class);
    hit.color
        .map(|c| (f32::from(c) * brightness).round().clamp(0.0, 255.0) as u8)
}

/// Deterministic brightness factor around 1 at `point` on a surface with normal `n`.
fn texture(point: &Point3<f32>, n: &Vector3<f32>, class: ClassId) -> f32 {
    if class == replica::FLOOR {
        return floor_planks(point.x, point.y);
    }
    // Drop the coordinate along the dominant normal axis: cells then tile the face itself and
    // cannot flicker across a cell boundary that coincides with the face.
    let axis = n.iamax();
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let cell = |x: f32| (x / 0.03).floor() as i32;
    0.94 + 0.12 * hash2(cell(point[a]), cell(point[b]) ^ ((axis as i32) << 20))
}

/// Planks 16 cm wide along y with staggered 1.4 m boards and dark seams.
fn floor_planks(x: f32, y: f32) -> f32 {
    let across = x / 0.16;
    let plank = across.floor() as i32;
    let along = (y + 1.4 * hash2(plank, 7)) / 1.4;
    let board = along.floor() as i32;
    let seam = across - across.floor() < 0.04 || along - along.floor() < 0.01;
    let grain = 0.97 + 0.06 * hash2((x / 0.02).floor() as i32, (y / 0.08).floor() as i32);
    let tone = 0.85 + 0.25 * hash2(plank, board);
    if seam { 0.6 } else { tone * grain }
}

/// A hash of two integers to `[0, 1]`.
fn hash2(x: i32, y: i32) -> f32 {
    let mut h = (x as u32).wrapping_mul(0x8da6_b343) ^ (y as u32).wrapping_mul(0xd816_3841);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    (h & 0xffff) as f32 / 65535.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh::TriangleMesh;
    use crate::synth::room::SurfaceLabel;

    #[test]
    fn a_wall_in_front_of_the_camera_renders_at_its_depth() {
        // A large square at z = 2 in front of a camera at the origin looking along +z.
        let v = [[-5.0, -5.0, 2.0], [5.0, -5.0, 2.0], [5.0, 5.0, 2.0], [-5.0, 5.0, 2.0]].map(Point3::from);
        let wall = TriangleMesh::new(v.to_vec(), vec![[0, 1, 2], [0, 2, 3]]).with_uniform_color([200, 100, 50]);
        let label = SurfaceLabel {
            instance_id: 3,
            class: replica::CHAIR,
        };
        let geometry = SceneGeometry::build([], [(label, &wall)]);
        let k = CameraIntrinsics {
            width: 8,
            height: 6,
            fx: 6.0,
            fy: 6.0,
            cx: 3.5,
            cy: 2.5,
        };
        let view = render_view(&geometry, &k, &Isometry3::identity());
        assert!(
            view.depth_m.iter().all(|&d| (d - 2.0).abs() < 1e-5),
            "flat wall has constant camera-z depth"
        );
        assert!(view.instance_ids.iter().all(|&id| id == 3));
        assert!(
            view.rgb.iter().all(|c| c[0] > c[1] && c[1] > c[2]),
            "shading keeps the hue"
        );
        let frame = view.into_rgbd_frame(FrameIndex(4));
        assert_eq!(frame.validate(), Ok(()));
        assert_eq!(frame.instances.object_at(0), Some(ObjectId(3)));
    }

    #[test]
    fn missed_pixels_have_no_depth_and_no_instance() {
        let geometry = SceneGeometry::build([], []);
        let k = CameraIntrinsics {
            width: 4,
            height: 3,
            fx: 3.0,
            fy: 3.0,
            cx: 1.5,
            cy: 1.0,
        };
        let frame = render_view(&geometry, &k, &Isometry3::identity()).into_rgbd_frame(FrameIndex(0));
        assert!(frame.depth_m.iter().all(|&d| d == 0.0));
        assert!((0..frame.instances.len()).all(|i| frame.instances.label(i) == InstanceLabel::Background));
    }
}
