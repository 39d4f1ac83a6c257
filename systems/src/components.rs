//! Components of the mapper's entities: camera frames, objects, the background and categories.

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;
use catmap::geometry::oriented_box::OrientedBox;
use catmap::objects::frame_observation::FrameObservation;
use catmap::objects::keyframes::KeyframeWindow;
use catmap::objects::object_bounds::MirrorFit;
use catmap::objects::object_view::ObjectView;
use catmap::objects::observed_cloud::ObservedCloud;
use catmap::sensor::pixel_box::PixelBox;
use catmap::{ClassId, FrameIndex, ObjectId, SharedFrame};
use rand_chacha::ChaCha8Rng;

/// A frame received from the stream. Lives for one tick; keyframe windows keep what they need.
#[derive(Component, Debug, Clone)]
pub struct CameraFrame(pub SharedFrame);

/// What the frame's masks say about each object (added by the segment stage).
#[derive(Component, Debug, Clone)]
pub struct FrameObservations(pub FrameObservation);

/// An object entity: one per dataset instance id.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Object {
    /// The dataset's instance id.
    pub id: ObjectId,
}

/// Marks the background entity (instance 0 and every background class).
#[derive(Component, Debug, Clone, Copy, Default)]
pub struct Background;

/// Pixel votes per semantic class, summed over all frames.
#[derive(Component, Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ClassVotes(pub BTreeMap<ClassId, u64>);

/// The object's class: the majority of its votes.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ObjectClass(pub ClassId);

/// The object's 2D boxes in the latest frame it was seen in.
#[derive(Component, Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct LatestBox {
    /// Frame the boxes come from.
    pub frame: FrameIndex,
    /// Tight box of the object's mask.
    pub tight: PixelBox,
    /// The box enlarged by 20 % (training samples pixels here).
    pub sample: PixelBox,
    /// Whether that frame became one of the object's keyframes.
    #[serde(default)]
    pub became_keyframe: bool,
}

impl LatestBox {
    /// The boxes of `observation` in `frame`, and whether the frame became a keyframe when
    /// offered to the window (`None`: not offered yet).
    pub fn of(
        frame: FrameIndex,
        observation: &catmap::objects::frame_observation::ObjectObservation,
        admission: Option<catmap::objects::keyframes::Admission>,
    ) -> Self {
        Self {
            frame,
            tight: observation.tight_box,
            sample: observation.sample_box,
            became_keyframe: admission.is_some_and(|a| a.is_keyframe()),
        }
    }

    /// The latest sighting, for the step scheduler.
    pub fn last_seen(&self) -> catmap::training::LastSeen {
        catmap::training::LastSeen {
            frame: self.frame,
            keyframe: self.became_keyframe,
        }
    }
}

/// The object's keyframe window; each slot keeps the crop of its frame inside the object's
/// enlarged 2D box (the background keeps whole frames).
#[derive(Component, Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Keyframes(pub KeyframeWindow<ObjectView>);

/// Number of frames the object (or background) was visible in.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct VisibleFrames(pub u64);

/// The object's mask pixels over its views and how many had a depth.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ObjectDepthCoverage(pub catmap::objects::frame_observation::DepthCoverage);

/// The object's observed points, accumulated in a voxel grid.
#[derive(Component, Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ObjectCloud(pub ObservedCloud);

/// The minimum-volume oriented box of the observed cloud, and the cloud size it was fitted at.
#[derive(Component, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObjectBounds {
    /// The box (edges at least `min_extent_m`).
    pub oriented_box: OrientedBox,
    /// Cloud voxels when the box was fitted.
    pub fitted_at_points: usize,
    /// The vertical mirror plane of the cloud, as last searched for.
    #[serde(default)]
    pub mirror: Option<MirrorFit>,
}

/// The object's own random generator, seeded from `(config.seed, object id)`.
#[derive(Component, Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ObjectRng(pub ChaCha8Rng);

/// A category entity: one per semantic class seen, listing its objects.
#[derive(Component, Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Category {
    /// The class.
    pub class: ClassId,
    /// Its objects, sorted.
    pub members: Vec<ObjectId>,
}

/// Where an entity's field lives in [`crate::resources::Fields`]: its index in the object batch
/// (the background has its own batch, index 0) and the world point its coordinates start at
/// (the object's box centre when the field was created; the world origin for the background).
#[derive(Component, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FieldSlot {
    /// Index in the batch.
    pub index: usize,
    /// Field coordinates are world coordinates minus this point.
    pub origin: nalgebra::Point3<f32>,
}

/// The random generator of an entity's field (initial weights, then training samples).
#[derive(Component, Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct FieldRng(pub ChaCha8Rng);

/// The field's losses at its latest training step.
#[derive(Component, Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FieldLoss {
    /// Losses of the latest step (before its update).
    pub latest: catmap::field::FieldLosses,
    /// Steps this field has taken.
    pub steps: u64,
    /// Its samples inside the object's meshed box over all those steps, and how many carved
    /// free space.
    pub carve: catmap::field::free_space::CarveCounts,
}

/// The latest preview mesh extracted from the entity's field (world coordinates), for live
/// viewing; the final meshes are returned by `Mapper::extract_final_meshes`, not stored.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct FieldMesh {
    /// The mesh.
    pub mesh: catmap::geometry::mesh::TriangleMesh,
    /// Which field it was extracted from.
    pub source: catmap::training::MeshSource,
}

/// The object's uncertainty sphere as its class's latest registration used it, and what it was
/// evaluated on (it is evaluated again only after material growth).
#[derive(Component, Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Reliability(pub catmap::categories::class_update::MemberReliability);

/// The object's place in its class: subcategory, representative, alignment and NOCS frame.
#[derive(Component, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Membership {
    /// The class.
    pub class: ClassId,
    /// Index of its subcategory within the class.
    pub subcategory: usize,
    /// The subcategory's representative.
    pub representative: ObjectId,
    /// Alignment to the representative and the object's box / NOCS frame.
    pub member: catmap::categories::class_registration::RegisteredMember,
}

/// A category's subcategories at its latest registration, and the cloud sizes it was computed at.
#[derive(Component, Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Subcategories {
    /// Subcategories in the order they were split off.
    pub groups: Vec<catmap::categories::class_registration::RegisteredSubcategory>,
    /// Cloud points of each member when registered.
    pub registered_points: BTreeMap<ObjectId, usize>,
    /// Every pair the registration answered (a pair on unchanged clouds is not searched again).
    #[serde(default)]
    pub pairs: catmap::categories::class_registration::PairCache,
}

impl Subcategories {
    /// The registration it records (what the next one starts from).
    pub fn registration(&self) -> catmap::categories::class_registration::ClassRegistration {
        catmap::categories::class_registration::ClassRegistration {
            groups: self.groups.clone(),
            pairs: self.pairs.clone(),
        }
    }
}

/// A member's place in a category field.
#[derive(Component, Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CategorySlot(pub catmap::categories::field_set::MemberPlace);

impl std::ops::Deref for CategorySlot {
    type Target = catmap::categories::field_set::MemberPlace;

    fn deref(&self) -> &Self::Target {
        &self.0
    }
}
