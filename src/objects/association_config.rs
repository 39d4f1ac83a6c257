//! How per-frame masks are associated into objects ([`crate::objects::instance_association`]):
//! where ids come from and the association's settings.

use serde::{Deserialize, Serialize};

/// Where object ids come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InstanceSource {
    /// The dataset's instance ids are one per object over the sequence (Replica, ScanNet).
    #[default]
    Consistent,
    /// Every frame numbers its masks anew; masks are associated into objects ([`crate::objects::instance_association`]).
    PerFrame,
}

/// How masks are associated into objects ([`crate::objects::instance_association`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AssociationConfig {
    /// `"consistent"` (the default) or `"per-frame"`.
    pub instances: InstanceSource,
    /// Edge of the voxels an object's points are kept in, metres.
    pub voxel_m: f32,
    /// Least share of a mask's points near an object for the object to take it.
    pub min_overlap: f32,
    /// A second object overlapping a mask by this share of the best overlap makes it ambiguous.
    pub ambiguity_ratio: f32,
    /// Frames a candidate must be seen in to become an object.
    pub min_frames: u32,
    /// A candidate not seen for this many frames is forgotten, and two objects are judged one
    /// only once the younger was first seen this many frames ago.
    pub candidate_window_frames: u64,
    /// A mask no object of its class takes, overlapping an object of another class by at least
    /// this share, is that object under a confused class and is held back ([`crate::objects::instance_association`]); above 1
    /// turns the check off.
    pub confused_class_overlap: f32,
    /// Points drawn from each mask (evenly over its pixels with depth).
    pub max_points_per_mask: usize,
    /// A mask with fewer valid points is held back.
    pub min_points: usize,
}

impl Default for AssociationConfig {
    fn default() -> Self {
        Self {
            instances: InstanceSource::Consistent,
            voxel_m: 0.05,
            min_overlap: 0.3,
            ambiguity_ratio: 0.5,
            min_frames: 3,
            candidate_window_frames: 30,
            confused_class_overlap: 0.5,
            max_points_per_mask: 400,
            min_points: 20,
        }
    }
}
