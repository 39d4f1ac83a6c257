//! The room: a floor and four walls around the world origin, z up, floor at z = 0.
//!
//! Floor and walls carry Replica background classes (40 floor, 93 wall) and instance ids ≥ 100,
//! so a reader has to merge them into the background by class, as it must for Replica itself.

use nalgebra::Point3;

use crate::dataset::classes::replica;
use crate::geometry::mesh::TriangleMesh;
use crate::ids::ClassId;

/// Instance id of the floor in the instance images.
pub const FLOOR_INSTANCE_ID: u16 = 100;
/// Instance id of the first wall (the others follow: 101..=104).
pub const FIRST_WALL_INSTANCE_ID: u16 = 101;

/// What a rendered surface is: its instance id in the instance image and its semantic class.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SurfaceLabel {
    /// Instance id (object id for objects, ≥ 100 for floor and walls).
    pub instance_id: u16,
    /// Semantic class.
    pub class: ClassId,
}

/// A box-shaped room spanning `[-half_x, half_x] × [-half_y, half_y] × [0, height]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Room {
    /// Half the room's extent along x, metres.
    pub half_x_m: f32,
    /// Half the room's extent along y, metres.
    pub half_y_m: f32,
    /// Wall height, metres.
    pub height_m: f32,
}

/// Where object centres may go: an axis-aligned rectangle on the floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorRegion {
    /// Smallest (x, y).
    pub min: [f32; 2],
    /// Largest (x, y).
    pub max: [f32; 2],
}

impl FloorRegion {
    /// True when `(x, y)` lies inside, shrunk by `margin` on every side.
    pub fn contains(&self, x: f32, y: f32, margin: f32) -> bool {
        x >= self.min[0] + margin && x <= self.max[0] - margin && y >= self.min[1] + margin && y <= self.max[1] - margin
    }
}

impl Room {
    /// The floor inside the walls.
    pub fn floor(&self) -> FloorRegion {
        FloorRegion {
            min: [-self.half_x_m, -self.half_y_m],
            max: [self.half_x_m, self.half_y_m],
        }
    }

    /// Where furniture centres go: away from the side (−y) the camera walks along, so that
    /// everything stays in view, and clear of the other walls.
    pub fn furniture_region(&self) -> FloorRegion {
        FloorRegion {
            min: [-self.half_x_m + 0.35, -self.half_y_m + 1.6],
            max: [self.half_x_m - 0.35, self.half_y_m - 0.3],
        }
    }

    /// Floor and the four walls with their labels, facing into the room.
    pub fn surfaces(&self) -> Vec<(SurfaceLabel, TriangleMesh)> {
        let (x, y, h) = (self.half_x_m, self.half_y_m, self.height_m);
        let p = Point3::new;
        let floor = quad(
            [p(-x, -y, 0.0), p(x, -y, 0.0), p(x, y, 0.0), p(-x, y, 0.0)],
            [150, 128, 100],
        );
        let walls = [
            [p(-x, -y, 0.0), p(-x, y, 0.0), p(-x, y, h), p(-x, -y, h)], // x = −x, facing +x
            [p(x, y, 0.0), p(x, -y, 0.0), p(x, -y, h), p(x, y, h)],     // x = +x, facing −x
            [p(x, -y, 0.0), p(-x, -y, 0.0), p(-x, -y, h), p(x, -y, h)], // y = −y, facing +y
            [p(-x, y, 0.0), p(x, y, 0.0), p(x, y, h), p(-x, y, h)],     // y = +y, facing −y
        ];
        let tints: [[u8; 3]; 4] = [[210, 204, 190], [200, 206, 196], [214, 208, 200], [196, 200, 208]];
        let floor_label = SurfaceLabel {
            instance_id: FLOOR_INSTANCE_ID,
            class: replica::FLOOR,
        };
        let mut out = vec![(floor_label, floor)];
        for (k, (corners, tint)) in walls.into_iter().zip(tints).enumerate() {
            let label = SurfaceLabel {
                instance_id: FIRST_WALL_INSTANCE_ID + k as u16,
                class: replica::WALL,
            };
            out.push((label, quad(corners, tint)));
        }
        out
    }
}

/// A single-colour quad from four corners in counter-clockwise order seen from its front.
fn quad(corners: [Point3<f32>; 4], rgb: [u8; 3]) -> TriangleMesh {
    TriangleMesh::new(corners.to_vec(), vec![[0, 1, 2], [0, 2, 3]]).with_uniform_color(rgb)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::classes::is_replica_background;

    #[test]
    fn room_surfaces_face_inwards_and_are_background() {
        let room = Room {
            half_x_m: 2.0,
            half_y_m: 1.5,
            height_m: 2.5,
        };
        let surfaces = room.surfaces();
        assert_eq!(surfaces.len(), 5, "floor and four walls");
        for (label, mesh) in &surfaces {
            assert!(is_replica_background(label.class) && label.instance_id >= 100);
            let [a, b, c] = mesh.corners(0);
            let normal = (b - a).cross(&(c - a));
            let to_centre = Point3::new(0.0, 0.0, 1.0) - a;
            assert!(
                normal.dot(&to_centre) > 0.0,
                "surface {} faces the room",
                label.instance_id
            );
        }
    }

    #[test]
    fn furniture_region_lies_inside_the_floor() {
        let room = Room {
            half_x_m: 3.5,
            half_y_m: 3.0,
            height_m: 2.7,
        };
        let r = room.furniture_region();
        assert!(room.floor().contains(r.min[0], r.min[1], 0.3) && room.floor().contains(r.max[0], r.max[1], 0.3));
    }
}
