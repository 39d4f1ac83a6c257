//! Normalised object frames (NOCS) of a category's members (METHOD.md §4).
//!
//! The representative's frame is its minimum-volume oriented box: `world_from_nocs = [R·s | c]`
//! with `s = max(extent)/2`, so the box fits in the unit cube `[-1, 1]³`. Every other member is
//! registered to the representative (`template_from_object`, rigid); in the representative's box
//! frame its aligned cloud gets a box symmetric about the representative's centre, with extent
//! `2·max(|max|, |min|)` per axis (at least `min_extent`; the floor slab under it counts only
//! along its upright axis, see `symmetric_cover`). Its NOCS frame has that box's pose and, by
//! [`MemberScale`], the representative's scale (the default: a rigid registration says the
//! member has its representative's size) or its own box's (METHOD.md: `s = max(extent)/2`, which
//! a Kinect-like camera's stray points grew by up to 2.7 % on an armchair, drawing it 2 cm too
//! wide). All members of a category thus share axes and centre.

use nalgebra::{Isometry3, Point3, Similarity3, Vector3};
use serde::{Deserialize, Serialize};

use super::grown_box::sides_in;
use crate::error::{CatmapError, Result};
use crate::geometry::oriented_box::OrientedBox;

/// The scale of a registered member's NOCS frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MemberScale {
    /// The representative's: the rigid registration aligned the member to the representative's
    /// shape, so it has its size.
    #[default]
    Representative,
    /// Its own box's, half its longest edge (METHOD.md): stray points grow it.
    OwnBox,
}

/// A member's box and normalised frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NocsFrame {
    /// Maps the unit cube (NOCS) to the object's box in world coordinates.
    pub world_from_nocs: Similarity3<f32>,
    /// The box's edge lengths along its axes, metres.
    pub extents: Vector3<f32>,
}

impl NocsFrame {
    /// The frame of a box: rotation and centre of the box, scale = max(extent)/2.
    pub fn of_box(world_from_box: Isometry3<f32>, extents: Vector3<f32>) -> Self {
        Self {
            world_from_nocs: Similarity3::from_isometry(world_from_box, extents.max() / 2.0),
            extents,
        }
    }

    /// The same frame (pose and scale) with its box grown, about its centre, until it holds
    /// every point of `cloud` (world) and every edge is at least `min_extent` long; the box never
    /// shrinks. NOCS coordinates of the grown part may exceed the unit cube.
    pub fn covering(&self, cloud: &[Point3<f32>], min_extent: f32) -> Result<Self> {
        let cover = symmetric_cover(&self.world_from_nocs.isometry, cloud)?;
        Ok(Self {
            world_from_nocs: self.world_from_nocs,
            extents: self.extents.sup(&cover).map(|e| e.max(min_extent)),
        })
    }

    /// The box as an [`OrientedBox`].
    pub fn oriented_box(&self) -> OrientedBox {
        OrientedBox {
            world_from_box: self.world_from_nocs.isometry,
            half_extents: self.extents / 2.0,
        }
    }
}

/// The representative's frame: its oriented box.
pub fn representative_frame(representative_box: &OrientedBox) -> NocsFrame {
    NocsFrame::of_box(representative_box.world_from_box, representative_box.extents())
}

/// The frame of a member whose `cloud` (world) is aligned to the representative by the rigid
/// `template_from_object` (maps the member's points onto the representative's), scaled by `scale`.
pub fn aligned_member_frame(
    cloud: &[Point3<f32>],
    template_from_object: &Isometry3<f32>,
    representative: &NocsFrame,
    (min_extent, scale): (f32, MemberScale),
) -> Result<NocsFrame> {
    if cloud.is_empty() {
        return Err(CatmapError::too_few("points of an aligned member", 1, 0));
    }
    let rep_box = representative.world_from_nocs.isometry;
    // The member's box: the representative's box carried back to the member's pose.
    let world_from_box = template_from_object.inverse() * rep_box;
    let extents = symmetric_cover(&world_from_box, cloud)?.map(|e| e.max(min_extent));
    Ok(match scale {
        MemberScale::Representative => NocsFrame {
            world_from_nocs: Similarity3::from_isometry(world_from_box, representative.world_from_nocs.scaling()),
            extents,
        },
        MemberScale::OwnBox => NocsFrame::of_box(world_from_box, extents),
    })
}

/// Edge lengths of the smallest box with pose `world_from_box` that holds `cloud` and is
/// symmetric about its centre: `2·max |p|` per axis in the box frame, its floor slab counting only
/// along the box's upright axis ([`super::grown_box::sides_in`]): a mask grown onto the floor
/// beside an armchair's feet made its frame 0.82 m deep for 0.70.
fn symmetric_cover(world_from_box: &Isometry3<f32>, cloud: &[Point3<f32>]) -> Result<Vector3<f32>> {
    if cloud.iter().any(|p| !p.coords.iter().all(|c| c.is_finite())) {
        return Err(CatmapError::NonFinitePoint {
            what: "an aligned cloud".into(),
        });
    }
    Ok(sides_in(world_from_box, cloud).map_or_else(Vector3::zeros, |(lo, hi)| (-lo).sup(&hi) * 2.0))
}

#[cfg(test)]
mod tests {
    use nalgebra::{Translation3, UnitQuaternion};

    use super::*;

    /// An armchair's frame: a box 0.82 × 0.70 × 0.72 m standing on the floor at the origin.
    fn armchair_frame() -> NocsFrame {
        NocsFrame::of_box(Isometry3::translation(0.0, 0.0, 0.36), Vector3::new(0.82, 0.70, 0.72))
    }

    /// The corners of [`armchair_frame`]'s box at height `low` and at its top.
    fn armchair_corners(low: f32) -> Vec<Point3<f32>> {
        [(-0.41, -0.35), (0.41, -0.35), (-0.41, 0.35), (0.41, 0.35)]
            .iter()
            .flat_map(|&(x, y)| [Point3::new(x, y, low), Point3::new(x, y, 0.72)])
            .collect()
    }

    #[test]
    fn the_representative_box_fits_the_unit_cube() {
        let b = OrientedBox {
            world_from_box: Isometry3::from_parts(
                Translation3::new(1.0, 2.0, 0.4),
                UnitQuaternion::from_euler_angles(0.0, 0.0, 0.6),
            ),
            half_extents: Vector3::new(0.2, 0.4, 0.3),
        };
        let frame = representative_frame(&b);
        assert!(
            (frame.world_from_nocs.scaling() - 0.4).abs() < 1e-6,
            "s = max(extent)/2"
        );
        let corner = frame.world_from_nocs * Point3::new(0.5, 1.0, 0.75);
        let want = b.world_from_box * Point3::new(0.2, 0.4, 0.3);
        assert!((corner - want).norm() < 1e-5, "NOCS (0.5, 1, 0.75) is the box corner");
    }

    #[test]
    fn floor_points_beside_a_members_feet_stay_out_of_its_frame_but_not_out_of_its_height() {
        let rep = armchair_frame();
        // An armchair's feet and top (its frame's half extents 0.41, 0.35, 0.36), and a mask grown
        // onto the floor 6 cm beyond its side.
        let mut cloud = armchair_corners(0.0);
        let clean =
            aligned_member_frame(&cloud, &Isometry3::identity(), &rep, (0.1, MemberScale::OwnBox)).expect("frame");
        cloud.extend((0..5).map(|k| Point3::new(-0.2 + 0.1 * k as f32, 0.41, 0.005)));
        let bled =
            aligned_member_frame(&cloud, &Isometry3::identity(), &rep, (0.1, MemberScale::OwnBox)).expect("frame");
        assert!(
            (bled.extents - Vector3::new(0.82, 0.70, 0.72)).norm() < 1e-5,
            "the floor points leave the frame alone: {}",
            bled.extents
        );
        assert_eq!(bled, clean);
        // Seen only at the floor's height, every point counts.
        let flat = [Point3::new(0.3, 0.0, 0.0), Point3::new(0.0, 0.2, 0.0)];
        let rug = aligned_member_frame(&flat, &Isometry3::identity(), &rep, (0.1, MemberScale::OwnBox)).expect("frame");
        assert!(
            (rug.extents - Vector3::new(0.6, 0.4, 0.72)).norm() < 1e-5,
            "{}",
            rug.extents
        );
    }

    #[test]
    fn an_aligned_member_gets_a_symmetric_box_in_its_own_pose() {
        let rep = NocsFrame::of_box(Isometry3::translation(0.0, 0.0, 0.5), Vector3::new(0.4, 0.4, 1.0));
        // The member is the representative moved by 2 m along x and turned 90° about z; its cloud
        // covers only one side (x from -0.1 to 0.2 in the representative's frame).
        let object_from_template = Isometry3::from_parts(
            Translation3::new(2.0, 0.0, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f32::consts::FRAC_PI_2),
        );
        let template_cloud = [
            Point3::new(-0.1, 0.05, 0.3),
            Point3::new(0.2, -0.15, 0.9),
            Point3::new(0.0, 0.0, 0.02),
        ];
        let cloud: Vec<Point3<f32>> = template_cloud.iter().map(|p| object_from_template * p).collect();
        let frame = aligned_member_frame(
            &cloud,
            &object_from_template.inverse(),
            &rep,
            (0.1, MemberScale::OwnBox),
        )
        .expect("frame");
        let e = frame.extents;
        assert!(
            (e - Vector3::new(0.4, 0.3, 0.96)).norm() < 1e-5,
            "2·max(|max|, |min|) per axis: {e}"
        );
        let centre = frame.world_from_nocs.isometry.translation.vector;
        assert!(
            (centre - Vector3::new(2.0, 0.0, 0.5)).norm() < 1e-5,
            "centre follows the member: {centre}"
        );
        let x_axis = frame.world_from_nocs.isometry.rotation * Vector3::x();
        assert!(
            (x_axis - Vector3::y()).norm() < 1e-5,
            "axes follow the member's rotation"
        );
        let all_inside = cloud.iter().all(|p| {
            let q = frame.world_from_nocs.inverse() * p;
            q.coords.iter().all(|c| c.abs() <= 1.0 + 1e-5)
        });
        assert!(all_inside, "the member's cloud lies in its unit cube");
    }

    #[test]
    fn a_member_keeps_its_representatives_scale_whatever_strays_its_cloud_holds() {
        let rep = armchair_frame();
        // A member seen whole, and one stray point 4 cm beyond its widest side.
        let mut cloud = armchair_corners(0.05);
        cloud.push(Point3::new(0.45, 0.0, 0.4));
        let own =
            aligned_member_frame(&cloud, &Isometry3::identity(), &rep, (0.1, MemberScale::OwnBox)).expect("frame");
        let shared = aligned_member_frame(&cloud, &Isometry3::identity(), &rep, (0.1, MemberScale::Representative))
            .expect("frame");
        assert!(
            (own.world_from_nocs.scaling() - 0.45).abs() < 1e-6,
            "its own box's half longest edge: {}",
            own.world_from_nocs.scaling()
        );
        assert_eq!(shared.world_from_nocs.scaling(), rep.world_from_nocs.scaling());
        assert_eq!(shared.extents, own.extents, "the box still holds the whole cloud");
        assert_eq!(shared.world_from_nocs.isometry, own.world_from_nocs.isometry);
    }
}
