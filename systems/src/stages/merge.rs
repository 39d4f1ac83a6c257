//! Merge stage: an object the association found to be part of another (per-frame ids;
//! `catmap::objects::pair_evidence`) is taken into the object that keeps its id, after the
//! tick's views and clouds were recorded.

use bevy_ecs::prelude::*;
use catmap::objects::object_merge::{Sightings, absorb_sightings};

use crate::components::{
    CameraFrame, ClassVotes, FieldSlot, FrameObservations, Keyframes, LatestBox, ObjectBounds, ObjectClass,
    ObjectCloud, ObjectDepthCoverage, ObjectRng, VisibleFrames,
};
use crate::resources::{Fields, ObjectIndex, Settings, SmallInstances};

/// The parts of an object a merge changes.
type MergedParts = (
    &'static mut ClassVotes,
    &'static mut ObjectClass,
    &'static mut LatestBox,
    &'static mut Keyframes,
    &'static mut VisibleFrames,
    &'static mut ObjectDepthCoverage,
    &'static mut ObjectCloud,
    &'static mut ObjectRng,
    Option<&'static mut ObjectBounds>,
    Option<&'static FieldSlot>,
);

/// Takes each merged object into the one that keeps its id (frames in index order): its class
/// votes, keyframes, visible frames, depth coverage and cloud (`absorb_sightings`); the kept
/// object's box is fitted again and its class follows the votes. The merged object's entity goes,
/// its field stays in the batch without an owner, and its id is not given again.
pub fn merge_objects(
    settings: Res<Settings>,
    frames: Query<(&CameraFrame, &FrameObservations), Added<FrameObservations>>,
    mut index: ResMut<ObjectIndex>,
    mut fields: ResMut<Fields>,
    mut small: ResMut<SmallInstances>,
    mut objects: Query<MergedParts>,
    mut commands: Commands,
) {
    let mut merges: Vec<_> = (frames.iter())
        .flat_map(|(frame, observations)| observations.0.merges.iter().map(move |m| (frame.0.index, *m)))
        .collect();
    merges.sort_by_key(|(frame, _)| *frame);
    for (_, merge) in merges {
        let entities = (index.0.get(&merge.kept).copied()).zip(index.0.get(&merge.absorbed).copied());
        let Some((absorbed_entity, Ok([kept, absorbed]))) = entities.map(|(k, a)| (a, objects.get_many_mut([k, a])))
        else {
            tracing::warn!(kept = %merge.kept, absorbed = %merge.absorbed, "merged objects have no entities");
            continue;
        };
        let (mut votes, mut class, mut latest, mut keyframes, mut visible, mut coverage, mut cloud, mut rng, bounds, _) =
            kept;
        let (mut a_votes, _, a_latest, mut a_keyframes, mut a_visible, mut a_coverage, mut a_cloud, _, _, a_slot) =
            absorbed;
        let majority = absorb_sightings(
            Sightings {
                class_votes: &mut votes.0,
                keyframes: &mut keyframes.0,
                visible_frames: &mut visible.0,
                depth_coverage: &mut coverage.0,
                cloud: &mut cloud.0,
            },
            Sightings {
                class_votes: &mut a_votes.0,
                keyframes: &mut a_keyframes.0,
                visible_frames: &mut a_visible.0,
                depth_coverage: &mut a_coverage.0,
                cloud: &mut a_cloud.0,
            },
            &settings.0.keyframes,
            &mut rng.0,
        );
        if let Some(majority) = majority {
            class.set_if_neq(ObjectClass(majority));
        }
        if a_latest.frame > latest.frame {
            *latest = *a_latest;
        }
        if let Some(mut bounds) = bounds {
            bounds.fitted_at_points = 0;
        }
        if let Some(slot) = a_slot
            && let Some(owner) = fields.object_owners.get_mut(slot.index)
        {
            *owner = None;
        }
        if let Some(n) = small.0.remove(&merge.absorbed) {
            *small.0.entry(merge.kept).or_default() += n;
        }
        index.0.remove(&merge.absorbed);
        commands.entity(absorbed_entity).despawn();
        tracing::info!(kept = %merge.kept, absorbed = %merge.absorbed, frame = %merge.frame, "objects merged");
    }
}
