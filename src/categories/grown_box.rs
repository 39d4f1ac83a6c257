//! A subcategory's box: its representative's box grown, along its own axes, to what the members
//! saw of their design.
//!
//! The representative's frame is its box (METHOD.md §4), and every member's frame is that box
//! carried to the member ([`super::nocs`]). A representative seen from one side only has the box
//! of that side: under a Kinect-like camera and a segmenter's masks a ladder-back chair kept only
//! its front half (0.47 × 0.27 m for 0.48 × 0.50), the paper's uncertainty ranking made it the
//! representative of chairs seen whole, and every member's frame was centred 10 cm off its chair.
//!
//! Every member is registered onto the representative. In the representative's box frame a
//! member's aligned cloud spans `[lo, hi]` per axis (the floor slab under it only along the box's
//! upright axis, as a member's frame counts it). Each side of the box moves out to the median of
//! the members' sides when that lies beyond it — the lower median: with two members, the nearer
//! of their sides; with one, nothing moves ([`MIN_MEMBERS_TO_GROW`]). The box never shrinks, so a
//! representative seen whole keeps its box up to the members' registration error, and one poorly
//! registered member of three does not move it.

use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::geometry::oriented_box::OrientedBox;
use crate::geometry::upright_box::base_slab_top;

/// Fewest registered members (the representative aside) whose sides move the representative's
/// box: one member's registration alone does not (two nightstands, the front of neither ever
/// seen, grew each other's frame by their registration error and lost 0.5–0.7 cm of accuracy).
pub const MIN_MEMBERS_TO_GROW: usize = 2;

/// The box a subcategory's frames are built on (`categories.frames.representative_box`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RepresentativeBox {
    /// The representative's box grown to its members' sides ([`grown_box`]).
    #[default]
    Grown,
    /// The representative's own box (the paper).
    Own,
}

/// `representative`'s box grown to the median of its members' sides (module doc); `aligned`
/// holds each member's cloud mapped onto the representative (world frame). Members without points
/// say nothing.
pub fn grown_box(representative: &OrientedBox, aligned: &[Vec<Point3<f32>>]) -> OrientedBox {
    let sides: Vec<(Vector3<f32>, Vector3<f32>)> = aligned
        .iter()
        .filter_map(|c| sides_in(&representative.world_from_box, c))
        .collect();
    if sides.len() < MIN_MEMBERS_TO_GROW {
        return *representative;
    }
    let half = representative.half_extents;
    let (mut lo, mut hi) = (-half, half);
    for axis in 0..3 {
        let mut lows: Vec<f32> = sides.iter().map(|(l, _)| l[axis]).collect();
        let mut highs: Vec<f32> = sides.iter().map(|(_, h)| h[axis]).collect();
        lows.sort_by(|a, b| b.total_cmp(a));
        highs.sort_by(f32::total_cmp);
        let median = (sides.len() - 1) / 2;
        lo[axis] = lo[axis].min(lows[median]);
        hi[axis] = hi[axis].max(highs[median]);
    }
    let shift = representative.world_from_box.rotation * ((lo + hi) / 2.0);
    let mut grown = *representative;
    grown.world_from_box.translation.vector += shift;
    grown.half_extents = (hi - lo) / 2.0;
    grown
}

/// The lowest and highest coordinates of `cloud` (world) along the axes of the box at
/// `world_from_box`, its floor slab ([`base_slab_top`]) counting only along the axis nearest
/// world up (all of it when nothing lies above the slab): a mask grown onto the floor beside an
/// object's feet puts points there. `None` for an empty or non-finite cloud.
pub(super) fn sides_in(world_from_box: &Isometry3<f32>, cloud: &[Point3<f32>]) -> Option<(Vector3<f32>, Vector3<f32>)> {
    let box_from_world = world_from_box.inverse();
    let up = (box_from_world.rotation * Vector3::z()).iamax();
    let base_top = base_slab_top(cloud.iter().map(|p| f64::from(p.z)))?;
    let (mut lo, mut hi) = (Vector3::repeat(f32::INFINITY), Vector3::repeat(f32::NEG_INFINITY));
    let (mut lo_above, mut hi_above) = (lo, hi);
    for p in cloud {
        let q = (box_from_world * p).coords;
        if !q.iter().all(|c| c.is_finite()) {
            return None;
        }
        (lo, hi) = (lo.inf(&q), hi.sup(&q));
        if f64::from(p.z) > base_top {
            (lo_above, hi_above) = (lo_above.inf(&q), hi_above.sup(&q));
        }
    }
    if lo_above.x.is_finite() {
        (lo_above[up], hi_above[up]) = (lo[up], hi[up]);
        Some((lo_above, hi_above))
    } else {
        Some((lo, hi))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion};

    use super::*;

    /// A chair-sized box, 0.48 × 0.50 × 0.95 m, turned 30° about up, standing at (1, 2, 0).
    fn chair_box(half_y: f32, centre_y: f32) -> OrientedBox {
        let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 30f32.to_radians());
        OrientedBox {
            world_from_box: Isometry3::from_parts(
                Translation3::from(Vector3::new(1.0, 2.0, 0.475) + turn * Vector3::new(0.0, centre_y, 0.0)),
                turn,
            ),
            half_extents: Vector3::new(0.24, half_y, 0.475),
        }
    }

    /// The corners of `b`'s box and points on its edges, the lowest ones at the floor.
    fn seen_whole(b: &OrientedBox) -> Vec<Point3<f32>> {
        let h = b.half_extents;
        let mut local = Vec::new();
        for k in 0..=10 {
            let t = -1.0 + 0.2 * k as f32;
            for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                local.push(Vector3::new(sx * h.x, sy * h.y, t * h.z));
                local.push(Vector3::new(t * h.x, sy * h.y, h.z));
            }
        }
        local.iter().map(|v| b.world_from_box * Point3::from(*v)).collect()
    }

    #[test]
    fn a_representative_seen_from_one_side_grows_to_what_its_members_saw() {
        let whole = chair_box(0.25, 0.0);
        // The representative's box holds only the front half, 0.27 m deep.
        let front = chair_box(0.135, -0.115);
        let members = vec![seen_whole(&whole), seen_whole(&whole), seen_whole(&whole)];
        let grown = grown_box(&front, &members);
        assert!(
            (grown.extents() - whole.extents()).norm() < 1e-4,
            "{:?}",
            grown.extents()
        );
        assert!((grown.center() - whole.center()).norm() < 1e-4, "{:?}", grown.center());
        assert_eq!(
            grown.world_from_box.rotation, front.world_from_box.rotation,
            "its axes stay"
        );
    }

    #[test]
    fn a_whole_representative_keeps_its_box_and_one_stray_member_of_three_moves_nothing() {
        let whole = chair_box(0.25, 0.0);
        let inside = chair_box(0.2, 0.0);
        let off = chair_box(0.25, 0.4);
        let kept = grown_box(&whole, &[seen_whole(&inside), seen_whole(&whole), seen_whole(&off)]);
        assert!((kept.extents() - whole.extents()).norm() < 1e-4, "{:?}", kept.extents());
        assert!((kept.center() - whole.center()).norm() < 1e-4, "{:?}", kept.center());
        assert_eq!(grown_box(&whole, &[]), whole, "no members, no change");
        assert_eq!(
            grown_box(&whole, &[seen_whole(&off)]),
            whole,
            "one member alone moves nothing"
        );
    }

    #[test]
    fn floor_points_beside_a_members_feet_do_not_grow_the_box() {
        let whole = chair_box(0.25, 0.0);
        let turn = whole.world_from_box.rotation;
        let mut bled = seen_whole(&whole);
        bled.extend(
            (0..5).map(|k| Point3::new(1.0, 2.0, 0.0) + turn * Vector3::new(-0.2 + 0.1 * k as f32, 0.31, 0.005)),
        );
        let kept = grown_box(&whole, &[bled.clone(), bled]);
        assert!((kept.extents() - whole.extents()).norm() < 1e-4, "{:?}", kept.extents());
    }
}
