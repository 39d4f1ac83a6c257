//! Semantic class ids used by the datasets and the synthetic scenes, and which of them are background.

use crate::ids::ClassId;

/// Replica classes the synthetic scenes use.
pub mod replica {
    use crate::ids::ClassId;
    /// Bed.
    pub const BED: ClassId = ClassId(7);
    /// Box.
    pub const BOX: ClassId = ClassId(15);
    /// Cabinet.
    pub const CABINET: ClassId = ClassId(18);
    /// Chair.
    pub const CHAIR: ClassId = ClassId(20);
    /// Floor (background).
    pub const FLOOR: ClassId = ClassId(40);
    /// Lamp.
    pub const LAMP: ClassId = ClassId(47);
    /// Nightstand.
    pub const NIGHTSTAND: ClassId = ClassId(54);
    /// Shelf (a bookcase).
    pub const SHELF: ClassId = ClassId(71);
    /// Sofa.
    pub const SOFA: ClassId = ClassId(76);
    /// Stool.
    pub const STOOL: ClassId = ClassId(78);
    /// Table.
    pub const TABLE: ClassId = ClassId(80);
    /// Wall (background).
    pub const WALL: ClassId = ClassId(93);
}

/// Replica classes merged into the background: beam, blinds, curtain, ceiling, floor, pillar,
/// switch, vent, wall, wall-plug, window, rug.
pub const REPLICA_BACKGROUND: [u32; 12] = [5, 12, 30, 31, 40, 60, 79, 92, 93, 95, 97, 98];

/// ScanNet raw label ids merged into the background (METHOD.md §1).
pub const SCANNET_BACKGROUND: [i64; 10] = [-1, 0, 1, 3, 16, 21, 41, 128, 161, 232];

/// True when `class` is a Replica background class.
pub fn is_replica_background(class: ClassId) -> bool {
    REPLICA_BACKGROUND.contains(&class.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_and_wall_are_background_but_chairs_are_not() {
        assert!(is_replica_background(replica::FLOOR));
        assert!(is_replica_background(replica::WALL));
        assert!(!is_replica_background(replica::CHAIR));
    }
}
