//! Which parts of a cube around an object its views observed, on a coarse grid: the space where
//! the object's field speaks from evidence, and the space where it only extrapolates.
//!
//! Each cell's centre gets [`cell_evidence`] over the object's keyframe crops (margin: the
//! cell's half diagonal). A cell is **unobserved** when some view saw behind a surface there —
//! behind the object's own (hidden) or another's (occluded) — and none saw it free, at the
//! object's surface, or glimpsed through it; cells no view says anything of (outside every crop)
//! are not: far from the object, the field's emptiness is what its keyframe rays taught it.
//!
//! The uncertainty sphere ([`crate::categories::uncertainty`]) reads the field's occupancy as
//! ½ in unobserved cells: a field trained on one side of an object extrapolates its interior
//! into the never-seen side as a confident solid, and rays into that side would read as certain
//! hits.
//!
//! The same cells tell subcategorisation where a member's views looked
//! ([`ObservedSpace::looked_at`]): seen free, at its surface, or glimpsed through. A part of a
//! representative that lands elsewhere in a member was never in front of the member's cameras,
//! and its absence from the member's cloud says nothing of the member's design
//! ([`crate::categories::subcategories::ReversePoints`]).

use nalgebra::{Point3, Vector3};

use super::cell_evidence::{CellEvidence, cell_evidence};
use super::object_view::ObjectView;

/// Cells along each edge of the cube.
pub const OBSERVED_CELLS_PER_AXIS: usize = 24;

/// The unobserved cells of a cube (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct ObservedSpace {
    /// The cube's lowest corner (world).
    corner: Point3<f32>,
    /// Edge of one cell, metres.
    cell: f32,
    /// What the views say of each cell, x fastest.
    evidence: Vec<CellEvidence>,
}

impl ObservedSpace {
    /// The cube of half side `half_side` around `centre` (world), seen by `views`.
    pub fn of_views(views: &[&ObjectView], centre: &Point3<f32>, half_side: f32) -> Self {
        let n = OBSERVED_CELLS_PER_AXIS;
        let cell = 2.0 * half_side / n as f32;
        let corner = centre - Vector3::repeat(half_side);
        let margin = 0.5 * cell * 3f32.sqrt();
        let mut evidence = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let p = corner + Vector3::new(i as f32 + 0.5, j as f32 + 0.5, k as f32 + 0.5) * cell;
                    evidence.push(cell_evidence(views, &p, margin));
                }
            }
        }
        Self { corner, cell, evidence }
    }

    /// The evidence of the cell `p` (world) lies in; `None` outside the cube.
    fn evidence_at(&self, p: &Point3<f32>) -> Option<CellEvidence> {
        let n = OBSERVED_CELLS_PER_AXIS;
        let mut index = [0usize; 3];
        for a in 0..3 {
            let k = ((p[a] - self.corner[a]) / self.cell).floor();
            if !(0.0..n as f32).contains(&k) {
                return None;
            }
            index[a] = k as usize;
        }
        Some(self.evidence[(index[2] * n + index[1]) * n + index[0]])
    }

    /// Whether `p` (world) lies in an unobserved cell (outside the cube: no).
    pub fn unobserved(&self, p: &Point3<f32>) -> bool {
        matches!(self.evidence_at(p), Some(CellEvidence::Hidden | CellEvidence::Occluded))
    }

    /// Whether a view looked at `p` (world): its cell was seen free, at the object's surface or
    /// glimpsed through (outside the cube, outside every crop, hidden or occluded: no).
    pub fn looked_at(&self, p: &Point3<f32>) -> bool {
        matches!(
            self.evidence_at(p),
            Some(CellEvidence::SeenFree | CellEvidence::Surface | CellEvidence::Glimpsed)
        )
    }

    /// The share of the cube's cells that are unobserved.
    pub fn unobserved_share(&self) -> f32 {
        let unobserved = self
            .evidence
            .iter()
            .filter(|e| matches!(e, CellEvidence::Hidden | CellEvidence::Occluded))
            .count();
        unobserved as f32 / self.evidence.len() as f32
    }

    /// `alpha` (α per point of `points`) with α = 0 — occupancy ½ under the sphere's sharpening —
    /// at the unobserved points.
    pub fn unknown_where_unobserved(&self, points: &[Point3<f32>], mut alpha: Vec<f32>) -> Vec<f32> {
        for (a, p) in alpha.iter_mut().zip(points) {
            if self.unobserved(p) {
                *a = 0.0;
            }
        }
        alpha
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::objects::view_fixtures::{render, slab_and_box};

    #[test]
    fn space_behind_a_slab_seen_from_its_front_is_unobserved_and_space_before_it_is_not() {
        let (scene, _) = slab_and_box();
        let front = render([0.0, -1.0, 0.2], 0.0, &scene);
        let space = ObservedSpace::of_views(&[&front], &Point3::new(0.0, 1.0, 0.2), 0.5);
        assert!(space.unobserved(&Point3::new(0.0, 1.3, 0.2)), "behind the slab");
        assert!(
            !space.unobserved(&Point3::new(0.0, 0.7, 0.2)),
            "between the camera and the slab"
        );
        assert!(!space.unobserved(&Point3::new(0.0, 3.0, 0.2)), "outside the cube");
        assert!(
            !space.looked_at(&Point3::new(0.0, 1.3, 0.2)),
            "behind the slab: not looked at"
        );
        assert!(space.looked_at(&Point3::new(0.0, 0.7, 0.2)), "seen free");
        assert!(
            !space.looked_at(&Point3::new(0.0, 3.0, 0.2)),
            "outside the cube: not looked at"
        );
        let share = space.unobserved_share();
        assert!(share > 0.0 && share < 0.5, "{share}");
        let alpha = space.unknown_where_unobserved(
            &[Point3::new(0.0, 1.3, 0.2), Point3::new(0.0, 0.7, 0.2)],
            vec![5.0, -5.0],
        );
        assert_eq!(alpha, vec![0.0, -5.0]);
        // Seen from behind too, the space behind the slab is observed.
        let back = render([0.0, 3.0, 0.2], std::f32::consts::PI, &scene);
        let both = ObservedSpace::of_views(&[&front, &back], &Point3::new(0.0, 1.0, 0.2), 0.5);
        assert!(!both.unobserved(&Point3::new(0.0, 1.3, 0.2)));
    }
}
