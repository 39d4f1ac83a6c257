//! A plain-data view of the map (objects, background, categories, stream), for tests, summaries
//! and tools. Taking one never changes the world.

use bevy_ecs::prelude::*;
use catmap::geometry::oriented_box::OrientedBox;
use catmap::{ClassId, FrameIndex, ObjectId};
use nalgebra::Point3;
use serde::Serialize;

use crate::components::{
    Background, Category, ClassVotes, Keyframes, LatestBox, Object, ObjectBounds, ObjectClass, ObjectCloud,
    ObjectDepthCoverage, VisibleFrames,
};
use crate::resources::{Association, DatasetClasses, StreamProgress};

/// One object as the mapper knows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObjectSnapshot {
    /// Dataset instance id.
    pub id: ObjectId,
    /// Majority class.
    pub class: ClassId,
    /// Its name in the dataset (`class {id}` when it has none).
    pub class_name: String,
    /// Votes per class.
    pub class_votes: Vec<(ClassId, u64)>,
    /// Frames the object was visible in.
    pub visible_frames: u64,
    /// Share of its mask pixels over its views that had a depth.
    pub depth_share: Option<f32>,
    /// Frames in its keyframe window, in slot order.
    pub keyframes: Vec<FrameIndex>,
    /// Latest 2D boxes.
    pub latest_box: LatestBox,
    /// Number of observed cloud points (voxels).
    pub cloud_points: usize,
    /// The observed cloud (not serialised).
    #[serde(skip)]
    pub points: Vec<Point3<f32>>,
    /// The oriented box, once the cloud is large enough.
    pub bounds: Option<OrientedBox>,
    /// The cloud's vertical mirror plane, if one was found.
    #[serde(default)]
    pub mirror_plane: Option<catmap::geometry::mirror_symmetry::MirrorPlane>,
    /// A second plane at right angles to the first, if the cloud is symmetric about it too.
    #[serde(default)]
    pub second_mirror_plane: Option<catmap::geometry::mirror_symmetry::MirrorPlane>,
}

/// The background as the mapper knows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BackgroundSnapshot {
    /// Frames seen.
    pub visible_frames: u64,
    /// Keyframes, in slot order.
    pub keyframes: Vec<FrameIndex>,
    /// Observed cloud points (coarse voxels).
    pub cloud_points: usize,
}

/// One category.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct CategorySnapshot {
    /// The class.
    pub class: ClassId,
    /// Its objects.
    pub members: Vec<ObjectId>,
}

/// The whole map.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MapSnapshot {
    /// Frames ingested.
    pub frames_ingested: u64,
    /// Frames skipped by the reader.
    pub frames_skipped: u64,
    /// Objects sorted by id.
    pub objects: Vec<ObjectSnapshot>,
    /// The background.
    pub background: Option<BackgroundSnapshot>,
    /// Categories sorted by class.
    pub categories: Vec<CategorySnapshot>,
    /// Objects found to be part of another (per-frame ids), in the order they were merged.
    pub merges: Vec<catmap::objects::instance_association::ObjectMerge>,
}

impl MapSnapshot {
    /// Reads the map out of `world`.
    pub fn of(world: &mut World) -> Self {
        let progress = world.resource::<StreamProgress>().clone();
        let names = world.resource::<DatasetClasses>().0.clone();
        let mut objects: Vec<ObjectSnapshot> = world
            .query::<(
                &Object,
                &ObjectClass,
                &ClassVotes,
                &VisibleFrames,
                &ObjectDepthCoverage,
                &Keyframes,
                &LatestBox,
                &ObjectCloud,
                Option<&ObjectBounds>,
            )>()
            .iter(world)
            .map(
                |(object, class, votes, visible, coverage, keyframes, latest, cloud, bounds)| ObjectSnapshot {
                    id: object.id,
                    class: class.0,
                    class_name: names.name(class.0),
                    class_votes: votes.0.iter().map(|(&c, &n)| (c, n)).collect(),
                    visible_frames: visible.0,
                    depth_share: coverage.0.share(),
                    keyframes: keyframes.0.frames(),
                    latest_box: *latest,
                    cloud_points: cloud.0.len(),
                    points: cloud.0.points(),
                    bounds: bounds.map(|b| b.oriented_box),
                    mirror_plane: bounds.and_then(|b| b.mirror?.plane),
                    second_mirror_plane: bounds.and_then(|b| b.mirror?.second),
                },
            )
            .collect();
        objects.sort_by_key(|o| o.id);
        let background = world
            .query_filtered::<(&VisibleFrames, &Keyframes, &ObjectCloud), With<Background>>()
            .iter(world)
            .next()
            .map(|(visible, keyframes, cloud)| BackgroundSnapshot {
                visible_frames: visible.0,
                keyframes: keyframes.0.frames(),
                cloud_points: cloud.0.len(),
            });
        let mut categories: Vec<CategorySnapshot> = world
            .query::<&Category>()
            .iter(world)
            .map(|c| CategorySnapshot {
                class: c.class,
                members: c.members.clone(),
            })
            .collect();
        categories.sort_by_key(|c| c.class);
        Self {
            frames_ingested: progress.frames_ingested,
            frames_skipped: progress.frames_skipped,
            objects,
            background,
            categories,
            merges: world.resource::<Association>().0.merges().to_vec(),
        }
    }

    /// The object with `id`, if the mapper has it.
    pub fn object(&self, id: ObjectId) -> Option<&ObjectSnapshot> {
        self.objects.iter().find(|o| o.id == id)
    }
}
