//! Furniture designs built from primitives, each in its own object frame: z up, origin at the
//! centre of the object's footprint on the floor, front facing +y. Sizes are in metres.
//!
//! Every design is a list of coloured parts; the parts' bounding boxes double as the coarse
//! collision shapes the layout uses, so a chair seat may slide under a table top but its back may not.

use std::f32::consts::{FRAC_PI_4, SQRT_2, TAU};

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use super::primitives::{beam, block, cylinder, frustum};
use crate::dataset::classes::replica;
use crate::geometry::mesh::TriangleMesh;
use crate::ids::ClassId;

/// A furniture design. Instances of one design are identical up to their pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Design {
    /// Wooden chair: four thin legs, thin seat, tall back of horizontal slats.
    LadderBackChair,
    /// Open-frame lounge armchair, 0.8 × 0.7 m: four posts carrying the arm rails, a wide low
    /// upholstered seat and a low solid back.
    Armchair,
    /// Four-legged table, 1.6 × 0.9 × 0.75 m, high enough for chairs to tuck under.
    DiningTable,
    /// Two-door cabinet on a plinth, 0.8 × 0.45 × 1.2 m.
    Cabinet,
    /// Cardboard storage box with a lid.
    StorageBox,
    /// Floor lamp: round base, thin pole, conical shade.
    FloorLamp,
    /// Bar stool: round top on four splayed legs with a footrest.
    Stool,
    /// Nightstand: carcass on short legs with two inset drawer fronts.
    Nightstand,
    /// Three-seat sofa, 2.0 × 0.9 × 0.82 m: an upholstered base on short feet, three seat
    /// cushions, a full-width back and two arms; stands with its back to a wall.
    Sofa,
    /// Double bed, 1.5 × 2.06 × 1.0 m: a frame on four legs 12 cm high, a mattress, a pillow and a
    /// tall headboard; stands with its headboard to a wall.
    Bed,
    /// Bookcase, 0.9 × 0.32 × 1.8 m: open front, four shelves, a back panel, a plinth and books
    /// on three shelves (not mirror-symmetric); stands with its back to a wall.
    Bookcase,
}

/// Where a design goes in a room.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placing {
    /// Anywhere in the room's furniture region, at any yaw.
    Anywhere,
    /// With its back (the −y side of its frame) a few centimetres from a wall, facing the room.
    AgainstWall,
}

const WOOD: [u8; 3] = [139, 94, 60];
const WOOD_LIGHT: [u8; 3] = [196, 160, 110];
const METAL_DARK: [u8; 3] = [48, 48, 54];

impl Design {
    /// Every design, in a fixed order.
    pub const ALL: [Design; 11] = [
        Self::LadderBackChair,
        Self::Armchair,
        Self::DiningTable,
        Self::Cabinet,
        Self::StorageBox,
        Self::FloorLamp,
        Self::Stool,
        Self::Nightstand,
        Self::Sofa,
        Self::Bed,
        Self::Bookcase,
    ];

    /// Stable snake_case name, as written to `scene.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::LadderBackChair => "ladder_back_chair",
            Self::Armchair => "armchair",
            Self::DiningTable => "dining_table",
            Self::Cabinet => "cabinet",
            Self::StorageBox => "storage_box",
            Self::FloorLamp => "floor_lamp",
            Self::Stool => "stool",
            Self::Nightstand => "nightstand",
            Self::Sofa => "sofa",
            Self::Bed => "bed",
            Self::Bookcase => "bookcase",
        }
    }

    /// Replica semantic class of the design.
    pub fn class(self) -> ClassId {
        match self {
            Self::LadderBackChair | Self::Armchair => replica::CHAIR,
            Self::DiningTable => replica::TABLE,
            Self::Cabinet => replica::CABINET,
            Self::StorageBox => replica::BOX,
            Self::FloorLamp => replica::LAMP,
            Self::Stool => replica::STOOL,
            Self::Nightstand => replica::NIGHTSTAND,
            Self::Sofa => replica::SOFA,
            Self::Bed => replica::BED,
            Self::Bookcase => replica::SHELF,
        }
    }

    /// Where the design goes in a room: the large pieces stand against a wall.
    pub fn placing(self) -> Placing {
        match self {
            Self::Sofa | Self::Bed | Self::Bookcase => Placing::AgainstWall,
            _ => Placing::Anywhere,
        }
    }

    /// True for the chair designs.
    pub fn is_chair(self) -> bool {
        self.class() == replica::CHAIR
    }

    /// The coloured parts in the object frame.
    pub fn parts(self) -> Vec<TriangleMesh> {
        match self {
            Self::LadderBackChair => ladder_back_chair(),
            Self::Armchair => armchair(),
            Self::DiningTable => dining_table(),
            Self::Cabinet => cabinet(),
            Self::StorageBox => storage_box(),
            Self::FloorLamp => floor_lamp(),
            Self::Stool => stool(),
            Self::Nightstand => nightstand(),
            Self::Sofa => sofa(),
            Self::Bed => bed(),
            Self::Bookcase => bookcase(),
        }
    }

    /// All parts merged into one mesh in the object frame.
    pub fn mesh(self) -> TriangleMesh {
        TriangleMesh::merged(&self.parts())
    }

    /// The surface of the design as ground truth: the parts without what lies inside another part
    /// ([`exterior_surface`](super::exterior::exterior_surface), pieces of at most 1 cm where
    /// parts meet).
    pub fn surface(self) -> TriangleMesh {
        super::exterior::exterior_surface(&self.parts(), 0.01)
    }
}

/// Paints `mesh` one colour.
fn paint(mesh: TriangleMesh, rgb: [u8; 3]) -> TriangleMesh {
    mesh.with_uniform_color(rgb)
}

fn ladder_back_chair() -> Vec<TriangleMesh> {
    let (leg, x, y) = (0.035, 0.2025, 0.19);
    let mut parts = vec![paint(block(0.0, 0.0, 0.43, [0.44, 0.42, 0.035]), [160, 110, 70])];
    for sx in [-x, x] {
        parts.push(paint(block(sx, y, 0.0, [leg, leg, 0.43]), WOOD)); // front leg
        parts.push(paint(block(sx, -y, 0.0, [leg, leg, 0.43]), WOOD)); // rear leg
        parts.push(paint(block(sx, -y, 0.465, [leg, leg, 0.485]), WOOD)); // back post
        parts.push(paint(block(sx, 0.0, 0.12, [0.02, 2.0 * y - leg, 0.03]), WOOD)); // side stretcher
    }
    // Three slats and a top rail flush with the posts' tops at 0.95 m.
    for (z, height) in [(0.58, 0.06), (0.70, 0.06), (0.82, 0.06), (0.895, 0.055)] {
        parts.push(paint(block(0.0, -y, z, [2.0 * x - leg, 0.02, height]), WOOD));
    }
    parts
}

fn armchair() -> Vec<TriangleMesh> {
    let fabric = [40, 70, 130];
    let (x, y, post) = (0.375, 0.325, 0.04);
    let mut parts = Vec::new();
    for sx in [-x, x] {
        parts.push(paint(block(sx, y, 0.0, [post, post, 0.6]), WOOD)); // front post
        parts.push(paint(block(sx, -y, 0.0, [post, post, 0.6]), WOOD)); // rear post
        parts.push(paint(block(sx, 0.0, 0.57, [0.07, 0.7, 0.03]), WOOD)); // arm rail
        parts.push(paint(block(sx, 0.0, 0.15, [0.03, 2.0 * y, 0.04]), WOOD)); // side stretcher
    }
    parts.push(paint(block(0.0, 0.0, 0.31, [0.7, 0.65, 0.05]), fabric)); // seat
    parts.push(paint(block(0.0, -y, 0.36, [0.7, 0.04, 0.36]), fabric)); // back, up to 0.72 m
    parts
}

fn dining_table() -> Vec<TriangleMesh> {
    let (x, y) = (0.73, 0.38);
    let mut parts = vec![paint(block(0.0, 0.0, 0.72, [1.6, 0.9, 0.03]), WOOD_LIGHT)];
    for (sx, sy) in [(-x, -y), (-x, y), (x, -y), (x, y)] {
        parts.push(paint(block(sx, sy, 0.0, [0.06, 0.06, 0.72]), WOOD));
    }
    for s in [-1.0, 1.0] {
        parts.push(paint(block(0.0, s * y, 0.62, [2.0 * x - 0.06, 0.02, 0.1]), WOOD));
        parts.push(paint(block(s * x, 0.0, 0.62, [0.02, 2.0 * y - 0.06, 0.1]), WOOD));
    }
    parts
}

fn cabinet() -> Vec<TriangleMesh> {
    let mut parts = vec![
        paint(block(0.0, -0.01, 0.0, [0.76, 0.41, 0.06]), [70, 70, 70]),
        paint(block(0.0, 0.0, 0.06, [0.8, 0.45, 1.14]), [225, 220, 205]),
    ];
    for s in [-1.0, 1.0] {
        parts.push(paint(
            block(s * 0.1975, 0.2325, 0.08, [0.385, 0.015, 1.1]),
            [236, 233, 222],
        ));
        parts.push(paint(block(s * 0.05, 0.255, 0.55, [0.02, 0.03, 0.15]), [60, 60, 60]));
    }
    parts
}

fn storage_box() -> Vec<TriangleMesh> {
    vec![
        paint(block(0.0, 0.0, 0.0, [0.5, 0.38, 0.3]), [185, 145, 95]),
        paint(block(0.0, 0.0, 0.3, [0.52, 0.40, 0.05]), [160, 120, 78]),
    ]
}

fn floor_lamp() -> Vec<TriangleMesh> {
    vec![
        paint(cylinder(Point3::origin(), 0.16, 0.03, 24), METAL_DARK),
        paint(cylinder(Point3::new(0.0, 0.0, 0.03), 0.013, 1.27, 8), [190, 190, 195]),
        paint(
            frustum(Point3::new(0.0, 0.0, 1.30), 0.22, 0.14, 0.32, 24),
            [240, 228, 195],
        ),
    ]
}

fn stool() -> Vec<TriangleMesh> {
    let metal = [70, 70, 75];
    let mut parts = vec![paint(
        cylinder(Point3::new(0.0, 0.0, 0.60), 0.17, 0.04, 24),
        [150, 50, 40],
    )];
    let corner = |r: f32, k: usize, z: f32| {
        let (s, c) = (FRAC_PI_4 + TAU * k as f32 / 4.0).sin_cos();
        Point3::new(r * c, r * s, z)
    };
    // Each splayed leg tilts diagonally to its square section: lift it so the lowest corner of
    // its 3 cm foot (half-diagonal 0.015·√2) touches the floor.
    let foot_lift = 0.015 * SQRT_2 * 0.08_f32.atan2(0.60).sin();
    for k in 0..4 {
        parts.push(paint(
            beam(corner(0.19, k, foot_lift), corner(0.11, k, 0.60), 0.03),
            metal,
        ));
        parts.push(paint(
            beam(corner(0.155, k, 0.25), corner(0.155, (k + 1) % 4, 0.25), 0.02),
            metal,
        ));
    }
    parts
}

fn nightstand() -> Vec<TriangleMesh> {
    let (carcass, drawer, brass) = ([105, 70, 45], [140, 100, 65], [200, 170, 80]);
    let mut parts = vec![
        paint(block(0.0, 0.0, 0.56, [0.45, 0.40, 0.02]), carcass),
        paint(block(0.0, 0.0, 0.08, [0.45, 0.40, 0.02]), carcass),
        paint(block(0.0, -0.19, 0.10, [0.41, 0.02, 0.46]), carcass),
        paint(block(0.0, 0.19, 0.32, [0.41, 0.02, 0.025]), carcass),
    ];
    for s in [-1.0, 1.0] {
        parts.push(paint(block(s * 0.215, 0.0, 0.10, [0.02, 0.40, 0.46]), carcass));
        for sy in [-1.0, 1.0] {
            parts.push(paint(block(s * 0.2, sy * 0.175, 0.0, [0.04, 0.04, 0.08]), carcass));
        }
    }
    // Drawer fronts sit 2 cm behind the carcass front; knobs reach forward to it.
    for z in [0.105, 0.35] {
        parts.push(paint(block(0.0, 0.17, z, [0.40, 0.02, 0.205]), drawer));
        parts.push(paint(block(0.0, 0.19, z + 0.09, [0.05, 0.02, 0.025]), brass));
    }
    parts
}

fn sofa() -> Vec<TriangleMesh> {
    let (fabric, cushion, feet) = ([92, 98, 112], [112, 120, 136], [40, 32, 28]);
    let mut parts = vec![
        paint(block(0.0, 0.0, 0.08, [2.0, 0.9, 0.2]), fabric), // base, up to 0.28 m
        paint(block(0.0, -0.35, 0.28, [1.76, 0.2, 0.54]), fabric), // back, up to 0.82 m
    ];
    for s in [-1.0, 1.0] {
        parts.push(paint(block(s * 0.94, 0.0, 0.28, [0.12, 0.9, 0.34]), fabric)); // arm
        for sy in [-1.0, 1.0] {
            parts.push(paint(block(s * 0.92, sy * 0.38, 0.0, [0.06, 0.06, 0.08]), feet));
        }
    }
    // Three seat cushions 2 cm apart, in front of the back and between the arms.
    for k in [-1.0, 0.0, 1.0] {
        parts.push(paint(block(k * 0.59, 0.08, 0.28, [0.57, 0.64, 0.13]), cushion));
    }
    parts
}

fn bed() -> Vec<TriangleMesh> {
    let (linen, pillow) = ([214, 206, 190], [236, 233, 226]);
    let mut parts = vec![
        paint(block(0.0, 0.03, 0.12, [1.5, 2.0, 0.2]), WOOD), // frame, 12 cm above the floor
        paint(block(0.0, 0.04, 0.32, [1.44, 1.94, 0.22]), linen), // mattress, up to 0.54 m
        paint(block(0.0, -0.72, 0.54, [0.9, 0.4, 0.1]), pillow),
        paint(block(0.0, -1.0, 0.0, [1.5, 0.06, 1.0]), WOOD), // headboard
    ];
    for sx in [-0.71, 0.71] {
        for sy in [-0.92, 0.98] {
            parts.push(paint(block(sx, sy, 0.0, [0.06, 0.06, 0.12]), WOOD));
        }
    }
    parts
}

fn bookcase() -> Vec<TriangleMesh> {
    let (board, back) = ([222, 214, 196], [200, 192, 176]);
    let covers: [[u8; 3]; 5] = [
        [150, 40, 40],
        [40, 80, 140],
        [60, 110, 60],
        [200, 170, 60],
        [90, 60, 110],
    ];
    let mut parts = vec![
        paint(block(0.0, 0.0, 1.78, [0.9, 0.32, 0.02]), board),   // top
        paint(block(0.0, 0.005, 0.0, [0.86, 0.31, 0.08]), board), // plinth
        paint(block(0.0, -0.15, 0.08, [0.86, 0.02, 1.7]), back),  // back panel
    ];
    for s in [-1.0, 1.0] {
        parts.push(paint(block(s * 0.44, 0.0, 0.0, [0.02, 0.32, 1.78]), board)); // side
    }
    for z in [0.44, 0.80, 1.16, 1.48] {
        parts.push(paint(block(0.0, 0.01, z, [0.86, 0.30, 0.02]), board)); // shelf
    }
    // Books standing in rows from a start x on the plinth and two shelves, 22 cm deep, 1 cm in
    // front of the back panel; a stack lying on the third shelf.
    let rows: [(f32, f32, &[(f32, f32)]); 2] = [
        (
            0.08,
            -0.42,
            &[(0.05, 0.28), (0.04, 0.30), (0.06, 0.26), (0.04, 0.29), (0.05, 0.27)],
        ),
        (
            0.46,
            0.05,
            &[
                (0.06, 0.24),
                (0.05, 0.27),
                (0.05, 0.25),
                (0.07, 0.28),
                (0.06, 0.22),
                (0.05, 0.26),
            ],
        ),
    ];
    let mut k = 0;
    for (z, start, books) in rows {
        let mut x = start;
        for &(width, height) in books {
            parts.push(paint(
                block(x + width / 2.0, -0.02, z, [width, 0.22, height]),
                covers[k % 5],
            ));
            x += width;
            k += 1;
        }
    }
    parts.push(paint(block(-0.12, -0.02, 0.82, [0.3, 0.22, 0.08]), covers[3]));
    parts.push(paint(block(0.3, -0.02, 1.18, [0.08, 0.2, 0.25]), covers[1]));
    parts
}

#[cfg(test)]
#[path = "furniture_tests.rs"]
mod tests;
