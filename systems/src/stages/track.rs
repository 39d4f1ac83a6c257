//! Track stage: object entities appear for new instance ids and take in each frame's view of them.

use bevy_ecs::prelude::*;
use catmap::objects::frame_observation::add_class_votes;
use catmap::objects::keyframes::KeyframeRole;
use catmap::objects::object_view::{ObjectView, ViewOwner};
use catmap::objects::observed_cloud::ObservedCloud;
use catmap::rng::{RngStream, seeded_rng};
use catmap::sensor::pixel_box::PixelBox;

use crate::components::{
    Background, CameraFrame, ClassVotes, FrameObservations, Keyframes, LatestBox, Object, ObjectClass, ObjectCloud,
    ObjectDepthCoverage, ObjectRng, VisibleFrames,
};
use crate::resources::{ObjectIndex, Settings, StageTimes};

/// Spawns an object entity for every instance id seen for the first time.
pub fn spawn_new_objects(
    settings: Res<Settings>,
    frames: Query<(&CameraFrame, &FrameObservations), Added<FrameObservations>>,
    mut index: ResMut<ObjectIndex>,
    mut commands: Commands,
) {
    let config = &settings.0;
    for (frame, observations) in &frames {
        for (&id, observation) in &observations.0.objects {
            let Some(class) = observation.majority_class() else {
                continue; // no pixels (the observer never makes such an observation)
            };
            if index.0.contains_key(&id) {
                continue;
            }
            let entity = commands
                .spawn((
                    Object { id },
                    ObjectClass(class),
                    ClassVotes::default(),
                    LatestBox::of(frame.0.index, observation, None),
                    Keyframes::default(),
                    VisibleFrames::default(),
                    ObjectDepthCoverage::default(),
                    ObjectCloud(ObservedCloud::new(config.objects.cloud_voxel_m)),
                    ObjectRng(seeded_rng(config.seed, RngStream::Object(id))),
                ))
                .id();
            tracing::debug!(object = %id, class = %class, frame = %frame.0.index, "new object");
            index.0.insert(id, entity);
        }
    }
}

/// The per-object state a new view updates.
type ViewedObjects<'w, 's> = Query<
    'w,
    's,
    (
        &'static mut ClassVotes,
        &'static mut ObjectClass,
        &'static mut LatestBox,
        &'static mut Keyframes,
        &'static mut VisibleFrames,
        &'static mut ObjectDepthCoverage,
        &'static mut ObjectRng,
    ),
>;

/// Adds each new frame's view of an object: class votes (the class follows the majority),
/// latest 2D box, visible-frame count, depth coverage and keyframe window.
pub fn record_object_views(
    settings: Res<Settings>,
    frames: Query<(&CameraFrame, &FrameObservations), Added<FrameObservations>>,
    index: Res<ObjectIndex>,
    mut objects: ViewedObjects,
    mut times: ResMut<StageTimes>,
) {
    let _timer = times.start("objects");
    for (frame, observations) in &frames {
        for (id, observation) in &observations.0.objects {
            let Some((mut votes, mut class, mut latest, mut keyframes, mut visible, mut coverage, mut rng)) =
                index.0.get(id).and_then(|&e| objects.get_mut(e).ok())
            else {
                tracing::warn!(object = %id, "observed object has no entity");
                continue;
            };
            if let Some(majority) = add_class_votes(&mut votes.0, &observation.class_votes) {
                class.set_if_neq(ObjectClass(majority));
            }
            visible.0 += 1;
            coverage.0.add(observation, &frame.0.depth_m);
            let view = ObjectView::crop(&frame.0, observation.sample_box, ViewOwner::Object(*id))
                .with_depth_noise(settings.0.dataset.depth_noise_per_m2);
            let keyframes_cfg = &settings.0.keyframes;
            let admission = keyframes
                .0
                .offer(frame.0.index, view, KeyframeRole::Object, keyframes_cfg, &mut rng.0);
            *latest = LatestBox::of(frame.0.index, observation, Some(admission));
        }
    }
}

/// Offers every new frame to the background's keyframe window (the background is always visible).
pub fn record_background_views(
    settings: Res<Settings>,
    frames: Query<&CameraFrame, Added<FrameObservations>>,
    mut background: Query<(&mut Keyframes, &mut VisibleFrames, &mut ObjectRng), With<Background>>,
) {
    let Ok((mut keyframes, mut visible, mut rng)) = background.single_mut() else {
        return;
    };
    for frame in &frames {
        let k = frame.0.intrinsics;
        let whole_image = PixelBox {
            u_min: 0,
            v_min: 0,
            u_max: k.width - 1,
            v_max: k.height - 1,
        };
        let view = ObjectView::crop(&frame.0, whole_image, ViewOwner::Background);
        keyframes.0.offer(
            frame.0.index,
            view,
            KeyframeRole::Background,
            &settings.0.keyframes,
            &mut rng.0,
        );
        visible.0 += 1;
    }
}
