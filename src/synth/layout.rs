//! Furniture placement: seeded yaw and position on the floor, no interpenetration.
//!
//! Every design's parts' bounding boxes (in the object frame) are its collision shape. Two placed
//! boxes collide when their height ranges overlap and their yawed footprints overlap (separating
//! axis test with a 2 cm clearance). Placement is rejection sampling: first the designs that
//! stand against a wall ([`Placing::AgainstWall`]: the back 6–10 cm from one of the three walls
//! the camera faces, beyond the camera's strip), then the table, then chairs pushed into slots
//! around it (so their seats slide under the top while their backs stay out), then everything
//! else anywhere in the room's furniture region.

use std::collections::BTreeMap;
use std::f32::consts::{FRAC_PI_2, PI, TAU};

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector2, Vector3};
use rand::{Rng, RngExt};

use super::furniture::{Design, Placing};
use super::preset::Furnishing;
use super::room::{FloorRegion, Room};
use crate::error::{CatmapError, Result};
use crate::geometry::mesh::Aabb;

/// Clearance between collision boxes, metres.
const CLEARANCE_M: f32 = 0.02;
/// Random poses tried per object before the whole layout is restarted.
const TRIES_PER_OBJECT: usize = 400;
/// Whole-layout restarts before giving up.
const RESTARTS: usize = 20;

/// A design placed in the world.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// What is placed.
    pub design: Design,
    /// Pose: object frame → world, a yaw about z plus a translation on the floor.
    pub world_from_object: Isometry3<f32>,
}

/// A collision box in the world: yawed footprint rectangle plus height range.
#[derive(Debug, Clone, Copy)]
struct Footprint {
    center: Vector2<f32>,
    axes: [Vector2<f32>; 2],
    half: [f32; 2],
    z: [f32; 2],
}

impl Footprint {
    fn new(local: &Aabb, x: f32, y: f32, yaw: f32) -> Self {
        let (s, c) = yaw.sin_cos();
        let axes = [Vector2::new(c, s), Vector2::new(-s, c)];
        let mid = local.center();
        let center = Vector2::new(x, y) + axes[0] * mid.x + axes[1] * mid.y;
        let e = local.extent() / 2.0;
        Self {
            center,
            axes,
            half: [e.x, e.y],
            z: [local.min.z, local.max.z],
        }
    }

    fn radius_along(&self, axis: &Vector2<f32>) -> f32 {
        self.half[0] * self.axes[0].dot(axis).abs() + self.half[1] * self.axes[1].dot(axis).abs()
    }

    fn collides(&self, other: &Footprint) -> bool {
        if self.z[1] <= other.z[0] || other.z[1] <= self.z[0] {
            return false;
        }
        let d = other.center - self.center;
        self.axes
            .iter()
            .chain(&other.axes)
            .all(|axis| d.dot(axis).abs() <= self.radius_along(axis) + other.radius_along(axis) + CLEARANCE_M)
    }

    fn corners(&self) -> impl Iterator<Item = Vector2<f32>> + '_ {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .into_iter()
            .map(|(a, b)| self.center + self.axes[0] * (a * self.half[0]) + self.axes[1] * (b * self.half[1]))
    }
}

/// Places `furnishing` in `room`; the result is in the furnishing's design order.
pub fn place_furniture<R: Rng + ?Sized>(furnishing: &Furnishing, room: &Room, rng: &mut R) -> Result<Vec<Placement>> {
    let shapes: BTreeMap<Design, Vec<Aabb>> = furnishing
        .designs
        .iter()
        .map(|&d| (d, d.parts().iter().filter_map(|p| p.bounds()).collect()))
        .collect();
    for _ in 0..RESTARTS {
        if let Some(placements) = try_layout(furnishing, room, &shapes, rng) {
            return Ok(placements);
        }
    }
    Err(CatmapError::NoRoom {
        objects: furnishing.designs.len(),
        width_m: 2.0 * room.half_x_m,
        depth_m: 2.0 * room.half_y_m,
    })
}

/// The layout being built: placed poses by position in the furnishing, and their footprints.
struct Draft<'a> {
    shapes: &'a BTreeMap<Design, Vec<Aabb>>,
    poses: Vec<Option<(f32, f32, f32)>>,
    footprints: Vec<Footprint>,
}

impl Draft<'_> {
    /// Adds `design` at `(x, y, yaw)` if it stays inside `within` and hits nothing placed.
    fn try_place(&mut self, slot: usize, design: Design, (x, y, yaw): (f32, f32, f32), within: &FloorRegion) -> bool {
        let new: Vec<Footprint> = self.shapes[&design]
            .iter()
            .map(|b| Footprint::new(b, x, y, yaw))
            .collect();
        let inside = new
            .iter()
            .flat_map(Footprint::corners)
            .all(|c| within.contains(c.x, c.y, 0.05));
        if !inside || new.iter().any(|f| self.footprints.iter().any(|g| f.collides(g))) {
            return false;
        }
        self.footprints.extend(new);
        self.poses[slot] = Some((x, y, yaw));
        true
    }
}

fn try_layout<R: Rng + ?Sized>(
    furnishing: &Furnishing,
    room: &Room,
    shapes: &BTreeMap<Design, Vec<Aabb>>,
    rng: &mut R,
) -> Option<Vec<Placement>> {
    let designs = &furnishing.designs;
    let region = room.furniture_region();
    let mut draft = Draft {
        shapes,
        poses: vec![None; designs.len()],
        footprints: Vec::new(),
    };
    let random_pose = |rng: &mut R| {
        let x = rng.random_range(region.min[0]..=region.max[0]);
        let y = rng.random_range(region.min[1]..=region.max[1]);
        (x, y, rng.random_range(0.0..TAU))
    };
    let floor = room.floor();
    // Wall pieces stay out of the camera's strip along the −y wall.
    let beside_walls = FloorRegion {
        min: [floor.min[0], region.min[1]],
        max: floor.max,
    };
    for (i, &design) in designs.iter().enumerate() {
        if design.placing() == Placing::AgainstWall {
            let back = shapes[&design].iter().map(|b| b.min.y).fold(f32::INFINITY, f32::min);
            (0..TRIES_PER_OBJECT)
                .find(|_| draft.try_place(i, design, wall_pose(&beside_walls, back, rng), &beside_walls))?;
        }
    }
    let table = designs.iter().position(|&d| d == Design::DiningTable);
    if let Some(t) = table {
        (0..TRIES_PER_OBJECT).find(|_| draft.try_place(t, Design::DiningTable, random_pose(rng), &floor))?;
        let table_pose = draft.poses[t]?;
        let mut chairs: Vec<usize> = (0..designs.len()).filter(|&i| designs[i].is_chair()).collect();
        shuffle(&mut chairs, rng);
        let mut slots = table_slots();
        shuffle(&mut slots, rng);
        let mut tucked = 0;
        for &chair in &chairs {
            if tucked == furnishing.tucked_chairs {
                break;
            }
            // A chair that fits no free slot (an armchair is wider than the gap between the table's
            // legs) goes elsewhere below, and the next chair tries.
            let fitting = slots.iter().position(|slot| {
                (0..40).any(|_| draft.try_place(chair, designs[chair], tucked_pose(table_pose, slot, rng), &floor))
            });
            if let Some(k) = fitting {
                slots.remove(k);
                tucked += 1;
            }
        }
    }
    for (i, &design) in designs.iter().enumerate() {
        if draft.poses[i].is_none() {
            (0..TRIES_PER_OBJECT).find(|_| draft.try_place(i, design, random_pose(rng), &floor))?;
        }
    }
    let placements = designs.iter().zip(&draft.poses).map(|(&design, pose)| {
        let (x, y, yaw) = (*pose)?;
        let rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
        Some(Placement {
            design,
            world_from_object: Isometry3::from_parts(Translation3::new(x, y, 0.0), rotation),
        })
    });
    placements.collect()
}

/// A pose against one of the walls bounding `region` on the +x, −x and +y sides (the camera walks
/// along −y), picked at random, anywhere along it: the design's back, at `back` (< 0) on its y
/// axis, 6–10 cm from the wall, its front (+y) facing into the room.
fn wall_pose<R: Rng + ?Sized>(region: &FloorRegion, back: f32, rng: &mut R) -> (f32, f32, f32) {
    let inset = rng.random_range(0.06..=0.10) - back;
    let along_x = rng.random_range(region.min[0]..=region.max[0]);
    let along_y = rng.random_range(region.min[1]..=region.max[1]);
    // The front faces the wall's inward normal n: yaw = atan2(−n.x, n.y).
    match rng.random_range(0..3) {
        0 => (region.max[0] - inset, along_y, FRAC_PI_2),
        1 => (region.min[0] + inset, along_y, 3.0 * FRAC_PI_2),
        _ => (along_x, region.max[1] - inset, PI),
    }
}

/// A chair slot at the table's edge: a point on the edge and the outward edge normal (table frame).
type TableSlot = (Vector2<f32>, Vector2<f32>);

/// Two slots on each long side and one at each end of the dining table.
fn table_slots() -> Vec<TableSlot> {
    let v = Vector2::new;
    vec![
        (v(-0.35, 0.45), v(0.0, 1.0)),
        (v(0.35, 0.45), v(0.0, 1.0)),
        (v(-0.35, -0.45), v(0.0, -1.0)),
        (v(0.35, -0.45), v(0.0, -1.0)),
        (v(0.8, 0.0), v(1.0, 0.0)),
        (v(-0.8, 0.0), v(-1.0, 0.0)),
    ]
}

/// A chair pose facing the table at `slot`, its centre between 16 cm under the edge and 12 cm out.
fn tucked_pose<R: Rng + ?Sized>(table: (f32, f32, f32), (edge, normal): &TableSlot, rng: &mut R) -> (f32, f32, f32) {
    let along = Vector2::new(-normal.y, normal.x) * rng.random_range(-0.05..=0.05);
    let local = edge + normal * rng.random_range(-0.16..=0.12) + along;
    let (s, c) = table.2.sin_cos();
    let world = Vector2::new(table.0 + c * local.x - s * local.y, table.1 + s * local.x + c * local.y);
    // The chair's front (+y) faces −normal: yaw = atan2(n.x, −n.y) in the table frame.
    let yaw = table.2 + normal.x.atan2(-normal.y) + rng.random_range(-0.12..=0.12);
    (world.x, world.y, yaw.rem_euclid(TAU))
}

/// Fisher–Yates shuffle driven by `rng`.
fn shuffle<T, R: Rng + ?Sized>(items: &mut [T], rng: &mut R) {
    for i in (1..items.len()).rev() {
        items.swap(i, rng.random_range(0..=i));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use std::f32::consts::PI;

    fn footprint_corners(design: Design, world_from_object: &Isometry3<f32>) -> Vec<Point3<f32>> {
        let b = design.mesh().bounds().expect("design has vertices");
        [
            (b.min.x, b.min.y),
            (b.max.x, b.min.y),
            (b.max.x, b.max.y),
            (b.min.x, b.max.y),
        ]
        .map(|(x, y)| world_from_object * Point3::new(x, y, 0.0))
        .to_vec()
    }

    #[test]
    fn overlapping_rotated_boxes_collide_and_separated_ones_do_not() {
        let unit = Aabb {
            min: Point3::new(-0.5, -0.5, 0.0),
            max: Point3::new(0.5, 0.5, 1.0),
        };
        let a = Footprint::new(&unit, 0.0, 0.0, 0.0);
        assert!(a.collides(&Footprint::new(&unit, 0.9, 0.0, 0.3)));
        assert!(!a.collides(&Footprint::new(&unit, 1.3, 0.0, 0.0)));
        // Rotated by 45° the square reaches 0.707 along x: 0.5 + 0.707 < 1.25.
        assert!(!a.collides(&Footprint::new(&unit, 1.25, 0.0, PI / 4.0)));
        let above = Aabb {
            min: Point3::new(-0.5, -0.5, 1.0),
            max: Point3::new(0.5, 0.5, 2.0),
        };
        assert!(
            !a.collides(&Footprint::new(&above, 0.0, 0.0, 0.0)),
            "stacked boxes only touch"
        );
    }

    #[test]
    fn placements_stay_in_the_room_and_tuck_chairs_under_the_table() {
        let room = Room {
            half_x_m: 3.5,
            half_y_m: 3.0,
            height_m: 2.7,
        };
        let furnishing = super::super::preset::Preset::Default.furnishing([0.9, 0.9]);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let placed = place_furniture(&furnishing, &room, &mut rng).expect("the default room has space");
        assert_eq!(placed.len(), furnishing.designs.len());
        for p in &placed {
            for c in footprint_corners(p.design, &p.world_from_object) {
                assert!(
                    room.floor().contains(c.x, c.y, 0.0),
                    "{} inside the walls",
                    p.design.name()
                );
            }
        }
        let table = placed
            .iter()
            .find(|p| p.design == Design::DiningTable)
            .expect("a table");
        let table_from_world = table.world_from_object.inverse();
        // A seat (half depth ≥ 0.21 m) whose centre is within 0.2 m of the top's outline is partly under it.
        let under_table = placed.iter().filter(|p| {
            let c = table_from_world * Point3::from(p.world_from_object.translation.vector);
            p.design.is_chair() && c.x.abs() < 0.8 + 0.2 && c.y.abs() < 0.45 + 0.2
        });
        assert!(under_table.count() >= 1, "some chair is pushed under the table");
    }

    #[test]
    fn wall_pieces_stand_with_their_backs_to_a_wall_the_camera_faces() {
        let preset = super::super::preset::Preset::Living;
        let room = preset.room();
        let mut walls_used = [0; 3];
        for seed in 0..10 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let furnishing = preset.furnishing([rng.random(), rng.random()]);
            let placed = place_furniture(&furnishing, &room, &mut rng).expect("the living room has space");
            for p in placed.iter().filter(|p| p.design.placing() == Placing::AgainstWall) {
                let b = p.design.mesh().bounds().expect("design has vertices");
                let back = p.world_from_object * Point3::new(0.0, b.min.y, 0.0);
                let front = p.world_from_object * nalgebra::Vector3::y();
                // Distances from the back's middle to the +x, −x and +y walls, and their normals.
                let walls = [
                    (room.half_x_m - back.x, Vector2::new(-1.0, 0.0)),
                    (room.half_x_m + back.x, Vector2::new(1.0, 0.0)),
                    (room.half_y_m - back.y, Vector2::new(0.0, -1.0)),
                ];
                let (k, (gap, normal)) = walls
                    .iter()
                    .enumerate()
                    .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
                    .expect("three walls");
                assert!(
                    (0.059..=0.101).contains(gap),
                    "{} seed {seed}: back {gap} m from the wall",
                    p.design.name()
                );
                assert!(
                    Vector2::new(front.x, front.y).dot(normal) > 0.999,
                    "{} faces the room",
                    p.design.name()
                );
                assert!(
                    back.y > room.furniture_region().min[1],
                    "{} is beyond the camera's strip",
                    p.design.name()
                );
                walls_used[k] += 1;
            }
        }
        assert!(
            walls_used.iter().all(|&n| n > 0),
            "every wall the camera faces is used: {walls_used:?}"
        );
    }

    #[test]
    fn every_preset_lays_out_for_many_seeds() {
        for preset in super::super::preset::Preset::ALL {
            for seed in 0..40 {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                let furnishing = preset.furnishing([rng.random(), rng.random()]);
                assert!(
                    place_furniture(&furnishing, &preset.room(), &mut rng).is_ok(),
                    "{preset} seed {seed}"
                );
            }
        }
    }
}
