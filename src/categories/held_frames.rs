//! Category frames that hold still. Objects do not move, so a subcategory's normalised frame
//! — its representative's box, which every member's frame is carried from by the member's
//! alignment — must not jump because the box was refitted on a grown cloud: a near-square
//! seat's box turns by 90° when its longer horizontal edge changes sides, and every member's
//! frame, with what the category field learned in it, turns along.
//!
//! [`FramePolicy`] says what a registration does with the representative's frame, given the frame
//! it held after the previous registration and its refitted box now:
//! - `keep_axes` (default): the refitted box, on the quarter turn about up that keeps the axes it
//!   had ([`nearest_quarter_turn`]) — centre and scale follow the refit, the axes never swap;
//! - `hold`: the held frame, its box grown to hold the cloud now ([`NocsFrame::covering`]),
//!   while the refit is within [`FrameHoldConfig`]'s tolerance (turn up to quarter turns, shift
//!   relative to the scale, change of scale); beyond it, the refitted box;
//! - `rebuild`: the refitted box as it comes (before issue 31).
//!
//! The other members' frames follow their alignments, which improve as clouds grow; a member
//! whose frame moves beyond the tolerance while it stays in its category field gets a fresh code
//! there (`field_set`), so that change goes through the field set rather than silently.
//! Holding every member's frame instead (tried first) lost 35 % of the chairs' accuracy on the
//! default scene: the frames of early, partial clouds are worse than the refits.

use nalgebra::{Point3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

use super::grown_box::RepresentativeBox;
use super::nocs::MemberScale;
use super::nocs::NocsFrame;
use crate::error::Result;

/// What a re-registration does with the frames members already have.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FramePolicy {
    /// A held representative frame stays while the refitted box is within the tolerance (this
    /// module).
    Hold,
    /// The representative's frame is its refitted box, turned by the quarter turn about up that
    /// keeps the axes it had: centre and scale follow the box, the axes never swap.
    #[default]
    KeepAxes,
    /// Every registration rebuilds every frame from the representative's current box (catmap
    /// before frames held still; kept for comparison).
    Rebuild,
}

/// How far a member's proposed frame may lie from the one it holds before it replaces it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrameHoldConfig {
    /// `keep_axes`, `hold` or `rebuild`.
    pub policy: FramePolicy,
    /// Largest turn between the held and the proposed frame that keeps the held one, radians
    /// (0.35 ≈ 20°).
    pub max_turn_rad: f32,
    /// Largest move of the frame's centre that keeps the held one, as a fraction of the held
    /// frame's scale (half its box's longest edge).
    pub max_shift: f32,
    /// Largest change of the frame's scale that keeps the held one, as a fraction (0.25 = 25 %).
    pub max_rescale: f32,
    /// `grown` (the representative's box grown to what its members saw,
    /// [`crate::categories::grown_box`]) or `own` (its own box, the paper).
    pub representative_box: RepresentativeBox,
    /// `representative` (every member at its representative's scale) or `own_box` (each at half
    /// its own box's longest edge, the paper; [`crate::categories::nocs`]).
    pub member_scale: MemberScale,
}

impl Default for FrameHoldConfig {
    fn default() -> Self {
        Self {
            policy: FramePolicy::KeepAxes,
            max_turn_rad: 0.35,
            max_shift: 0.2,
            max_rescale: 0.25,
            representative_box: RepresentativeBox::Grown,
            member_scale: MemberScale::Representative,
        }
    }
}

/// Which turns of a proposed frame count as no turn at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameSymmetry {
    /// None: the frame was carried by an alignment.
    None,
    /// Quarter turns about the box's up axis: the frame is a box fitted anew, whose horizontal
    /// axes are defined only up to them.
    QuarterTurnsAboutUp,
}

/// How a proposed frame differs from a held one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameChange {
    /// Angle of the relative rotation, radians (the smallest over the symmetry's turns).
    pub turn_rad: f32,
    /// Distance between the centres over the held scale.
    pub shift: f32,
    /// `|proposed scale / held scale − 1|`.
    pub rescale: f32,
}

/// How `proposed` differs from `held`, up to `symmetry`.
pub fn frame_change(held: &NocsFrame, proposed: &NocsFrame, symmetry: FrameSymmetry) -> FrameChange {
    let relative = held.world_from_nocs.isometry.rotation.inverse() * proposed.world_from_nocs.isometry.rotation;
    let quarter_turns = match symmetry {
        FrameSymmetry::None => 1,
        FrameSymmetry::QuarterTurnsAboutUp => 4,
    };
    let turn_rad = (0..quarter_turns)
        .map(|k| {
            let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), k as f32 * std::f32::consts::FRAC_PI_2);
            (relative * turn).angle()
        })
        .fold(f32::INFINITY, f32::min);
    let held_scale = held.world_from_nocs.scaling();
    let shift = (proposed.world_from_nocs.isometry.translation.vector
        - held.world_from_nocs.isometry.translation.vector)
        .norm()
        / held_scale;
    FrameChange {
        turn_rad,
        shift,
        rescale: (proposed.world_from_nocs.scaling() / held_scale - 1.0).abs(),
    }
}

impl FrameChange {
    /// Whether it is within `cfg`'s tolerance.
    pub fn within(&self, cfg: &FrameHoldConfig) -> bool {
        self.turn_rad <= cfg.max_turn_rad && self.shift <= cfg.max_shift && self.rescale <= cfg.max_rescale
    }
}

/// A representative's frame after a registration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RepresentativeFrame {
    /// It had none: its box's.
    New(NocsFrame),
    /// The held one, its box grown to hold the representative's cloud.
    Held(NocsFrame),
    /// The proposed box on the axes the held frame had ([`FramePolicy::KeepAxes`]).
    Refitted(NocsFrame),
    /// Its box's, replacing a held frame it lies too far from (or `rebuild`).
    Replaced(NocsFrame),
}

impl RepresentativeFrame {
    /// The frame.
    pub fn frame(&self) -> NocsFrame {
        match *self {
            Self::New(f) | Self::Held(f) | Self::Refitted(f) | Self::Replaced(f) => f,
        }
    }
}

/// The frame of the box `proposed` turned by the quarter turn about its up axis that lies
/// closest to `held` (x and y extents swapped for an odd turn): the same box, on the axes `held`
/// had.
pub fn nearest_quarter_turn(held: &NocsFrame, proposed: &NocsFrame) -> NocsFrame {
    let held_rotation = held.world_from_nocs.isometry.rotation;
    let turned = |k: u8| {
        let turn = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), f32::from(k) * std::f32::consts::FRAC_PI_2);
        proposed.world_from_nocs.isometry.rotation * turn
    };
    let best = (0..4u8)
        .min_by(|&a, &b| {
            let angle = |k| (held_rotation.inverse() * turned(k)).angle();
            angle(a).total_cmp(&angle(b))
        })
        .unwrap_or(0);
    let mut frame = *proposed;
    frame.world_from_nocs.isometry.rotation = turned(best);
    if best % 2 == 1 {
        frame.extents = Vector3::new(proposed.extents.y, proposed.extents.x, proposed.extents.z);
    }
    frame
}

/// The frame of a representative whose `cloud` (world) is boxed by `refit` now, given the frame
/// it `held` after the previous registration (module doc; turns measured up to the box's quarter
/// turns about up).
pub fn hold_frame(
    held: Option<&NocsFrame>,
    refit: NocsFrame,
    cloud: &[Point3<f32>],
    cfg: &FrameHoldConfig,
    min_extent: f32,
) -> Result<RepresentativeFrame> {
    let Some(held) = held else {
        return Ok(RepresentativeFrame::New(refit));
    };
    Ok(match cfg.policy {
        FramePolicy::Hold if frame_change(held, &refit, FrameSymmetry::QuarterTurnsAboutUp).within(cfg) => {
            RepresentativeFrame::Held(held.covering(cloud, min_extent)?)
        }
        FramePolicy::KeepAxes => RepresentativeFrame::Refitted(nearest_quarter_turn(held, &refit)),
        FramePolicy::Hold | FramePolicy::Rebuild => RepresentativeFrame::Replaced(refit),
    })
}

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3};

    use super::*;

    fn frame(x: f32, yaw: f32, extents: [f32; 3]) -> NocsFrame {
        NocsFrame::of_box(
            Isometry3::from_parts(
                Translation3::new(x, 1.0, 0.4),
                UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
            ),
            Vector3::from(extents),
        )
    }

    #[test]
    fn a_box_refitted_a_quarter_turn_off_is_no_turn_but_an_alignment_a_quarter_turn_off_is() {
        let held = frame(0.0, 0.1, [0.5, 0.48, 0.9]);
        let turned = frame(0.0, 0.1 + std::f32::consts::FRAC_PI_2, [0.48, 0.5, 0.9]);
        let refit = frame_change(&held, &turned, FrameSymmetry::QuarterTurnsAboutUp);
        assert!(refit.turn_rad < 1e-5, "a near-square box's x axis swapped: {refit:?}");
        let aligned = frame_change(&held, &turned, FrameSymmetry::None);
        assert!(
            (aligned.turn_rad - std::f32::consts::FRAC_PI_2).abs() < 1e-5,
            "{aligned:?}"
        );
        let moved = frame_change(&held, &frame(0.09, 0.1, [0.5, 0.48, 0.9]), FrameSymmetry::None);
        assert!(
            (moved.shift - 0.2).abs() < 1e-5 && moved.rescale < 1e-6,
            "9 cm at scale 0.45: {moved:?}"
        );
    }

    #[test]
    fn a_refitted_box_keeps_the_axes_it_had() {
        let held = frame(0.0, 0.1, [0.5, 0.48, 0.9]);
        // Refitted a little off, with the longer horizontal edge now on the other side.
        let refit = frame(0.01, 0.15 + std::f32::consts::FRAC_PI_2, [0.52, 0.5, 0.9]);
        let cfg = FrameHoldConfig::default();
        let RepresentativeFrame::Refitted(kept) = hold_frame(Some(&held), refit, &[], &cfg, 0.1).unwrap() else {
            panic!("the default refits on the held axes")
        };
        let turn = frame_change(&held, &kept, FrameSymmetry::None);
        assert!(
            (turn.turn_rad - 0.05).abs() < 1e-4,
            "only the refit's own turn: {turn:?}"
        );
        assert!(
            (kept.extents - Vector3::new(0.5, 0.52, 0.9)).norm() < 1e-6,
            "x and y extents follow their axes: {}",
            kept.extents
        );
        let corner = |f: &NocsFrame| f.world_from_nocs.isometry * Point3::from(f.extents / 2.0);
        let same_box = (0..4).any(|k| {
            let flip = |v: f32, bit: i32| if k & bit == 0 { v } else { -v };
            let c = Point3::new(flip(kept.extents.x, 1), flip(kept.extents.y, 2), kept.extents.z) / 2.0;
            ((kept.world_from_nocs.isometry * c) - corner(&refit)).norm() < 1e-5
        });
        assert!(same_box, "the same box in the world");
    }

    #[test]
    fn a_frame_within_the_tolerance_holds_and_grows_its_box_and_one_beyond_is_replaced() {
        let cfg = FrameHoldConfig {
            policy: FramePolicy::Hold,
            ..FrameHoldConfig::default()
        };
        let held = frame(0.0, 0.0, [0.4, 0.4, 0.8]);
        // The cloud grew: a point 0.3 m out along x, and the refit box moved 2 cm and grew.
        let cloud = [Point3::new(0.3, 1.0, 0.4), Point3::new(-0.1, 1.1, 0.1)];
        let refit = frame(0.02, 0.05, [0.6, 0.4, 0.8]);
        let kept = hold_frame(Some(&held), refit, &cloud, &cfg, 0.1).unwrap();
        let RepresentativeFrame::Held(kept) = kept else {
            panic!("within the tolerance: {kept:?}")
        };
        assert_eq!(kept.world_from_nocs, held.world_from_nocs, "pose and scale held");
        assert!(
            (kept.extents - Vector3::new(0.6, 0.4, 0.8)).norm() < 1e-5,
            "the box grows to hold the cloud: {}",
            kept.extents
        );
        let turned = frame(0.0, std::f32::consts::FRAC_PI_4, [0.4, 0.4, 0.8]);
        let replaced = hold_frame(Some(&held), turned, &cloud, &cfg, 0.1).unwrap();
        assert_eq!(
            replaced,
            RepresentativeFrame::Replaced(turned),
            "45° from every quarter turn"
        );
        let rescaled = frame(0.0, 0.0, [0.4, 0.4, 1.2]);
        assert!(matches!(
            hold_frame(Some(&held), rescaled, &cloud, &cfg, 0.1).unwrap(),
            RepresentativeFrame::Replaced(_)
        ));
        let rebuild = FrameHoldConfig {
            policy: FramePolicy::Rebuild,
            ..cfg
        };
        assert_eq!(
            hold_frame(Some(&held), refit, &cloud, &rebuild, 0.1).unwrap(),
            RepresentativeFrame::Replaced(refit)
        );
        assert_eq!(
            hold_frame(None, refit, &cloud, &cfg, 0.1).unwrap(),
            RepresentativeFrame::New(refit)
        );
    }
}
