//! Track stage: object entities appear for new instance ids and take in each frame's view of them.

use bevy_ecs::prelude::*;
use catmap::objects::frame_observation::majority_class;
use catmap::objects::keyframes::{Admission, KeyframeRole};
use catmap::objects::object_view::{ObjectView, ViewOwner};
use catmap::objects::observed_cloud::ObservedCloud;
use catmap::rng::{RngStream, seeded_rng};
use catmap::sensor::pixel_box::PixelBox;

use crate::components::{
    Background, CameraFrame, ClassVotes, FrameObservations, Keyframes, LatestBox, Object, ObjectClass, ObjectCloud,
    ObjectRng, VisibleFrames,
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
            if index.0.contains_key(&id) {
                continue;
            }
            let class = majority_class(
                &observation
                    .class_votes
                    .iter()
                    .map(|(&c, &n)| (c, u64::from(n)))
                    .collect(),
            )
            .expect("an observed object has at least one pixel");
            let entity = commands
                .spawn((
                    Object { id },
                    ObjectClass(class),
                    ClassVotes::default(),
                    LatestBox {
                        frame: frame.0.index,
                        tight: observation.tight_box,
                        sample: observation.sample_box,
                        became_keyframe: false,
                    },
                    Keyframes::default(),
                    VisibleFrames::default(),
                    ObjectCloud(ObservedCloud::new(config.objects.cloud_voxel_m)),
                    ObjectRng(seeded_rng(config.seed, RngStream::Object(id))),
                ))
                .id();
            tracing::debug!(object = %id, class = %class, frame = %frame.0.index, "new object");
            index.0.insert(id, entity);
        }
    }
}

/// Adds each new frame's view of an object: class votes, latest 2D box, visible-frame count and
/// keyframe window.
pub fn record_object_views(
    settings: Res<Settings>,
    frames: Query<(&CameraFrame, &FrameObservations), Added<FrameObservations>>,
    index: Res<ObjectIndex>,
    mut objects: Query<(
        &mut ClassVotes,
        &mut ObjectClass,
        &mut LatestBox,
        &mut Keyframes,
        &mut VisibleFrames,
        &mut ObjectRng,
    )>,
    mut times: ResMut<StageTimes>,
) {
    let _timer = times.start("objects");
    for (frame, observations) in &frames {
        for (id, observation) in &observations.0.objects {
            let Some((mut votes, mut class, mut latest, mut keyframes, mut visible, mut rng)) =
                index.0.get(id).and_then(|&e| objects.get_mut(e).ok())
            else {
                tracing::warn!(object = %id, "observed object has no entity");
                continue;
            };
            for (&c, &n) in &observation.class_votes {
                *votes.0.entry(c).or_insert(0) += u64::from(n);
            }
            if let Some(majority) = majority_class(&votes.0) {
                class.set_if_neq(ObjectClass(majority));
            }
            visible.0 += 1;
            let view = ObjectView::crop(&frame.0, observation.sample_box, ViewOwner::Object(*id));
            let admission = keyframes.0.offer(
                frame.0.index,
                view,
                KeyframeRole::Object,
                &settings.0.keyframes,
                &mut rng.0,
            );
            *latest = LatestBox {
                frame: frame.0.index,
                tight: observation.tight_box,
                sample: observation.sample_box,
                became_keyframe: admission.is_keyframe(),
            };
            if let Admission::Overwrote {
                replaced,
                keyframe: true,
            } = admission
            {
                tracing::trace!(object = %id, ?replaced, "keyframe window full, slot replaced");
            }
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
