//! Cloud stage: observed point clouds grow with each frame, and oriented boxes follow them.

use bevy_ecs::prelude::*;
use catmap::ids::ObjectId;
use catmap::objects::object_bounds::{MirrorSearch, refit_stale_boxes};
use catmap::training::class_sizes;
use rayon::prelude::*;

use crate::components::{Background, CameraFrame, Category, FrameObservations, Object, ObjectBounds, ObjectCloud};
use crate::resources::{Settings, StageTimes, StreamProgress};

/// Back-projects each object's masked depth pixels of the new frames into its cloud, the frame
/// voting on the cloud's voxels in view (`objects.voxel_votes`; objects in parallel), and the
/// thinned background pixels into the background cloud.
pub fn accumulate_clouds(
    settings: Res<Settings>,
    frames: Query<(&CameraFrame, &FrameObservations), Added<FrameObservations>>,
    mut objects: Query<(&Object, &mut ObjectCloud), Without<Background>>,
    mut background: Query<&mut ObjectCloud, With<Background>>,
    mut times: ResMut<StageTimes>,
) {
    let _timer = times.start("clouds");
    let votes = settings.0.objects.voxel_votes;
    let depth_noise = settings.0.dataset.depth_noise_per_m2;
    for (frame, observations) in &frames {
        let mut work: Vec<(Mut<ObjectCloud>, &[u32], Option<ObjectId>)> = objects
            .iter_mut()
            .filter_map(|(object, cloud)| {
                observations
                    .0
                    .objects
                    .get(&object.id)
                    .map(|seen| (cloud, seen.pixels.as_slice(), Some(object.id)))
            })
            .collect();
        if let Ok(cloud) = background.single_mut() {
            work.push((cloud, &observations.0.background_pixels, None));
        }
        work.par_iter_mut().for_each(|(cloud, pixels, owner)| match owner {
            Some(id) => {
                cloud.0.add_view(&frame.0, pixels, *id, votes, depth_noise);
            }
            None => {
                cloud.0.add_pixels(&frame.0, pixels);
            }
        });
    }
}

/// Refits the oriented box of every object whose cloud has grown by more than
/// `bounds_refresh_growth` since its last fit, and of every grown one when the stream ends; the
/// mirror plane only of objects whose sampler reflects rays across it (`MirrorSearch::for_object`:
/// alone in their class) (`catmap::objects::object_bounds::refit_stale_boxes`; results written
/// back in query order).
pub fn refresh_object_bounds(
    settings: Res<Settings>,
    progress: Res<StreamProgress>,
    mut objects: Query<(Entity, &Object, &ObjectCloud, Option<&mut ObjectBounds>)>,
    categories: Query<&Category>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let _timer = times.start("bounds");
    let class_sizes = class_sizes(categories.iter().map(|c| &c.members[..]));
    let mirror_rays = settings.0.fields.object_rays.mirror_rays();
    let clouds = objects.iter().map(|(entity, object, cloud, bounds)| {
        (
            (entity, object.id),
            bounds.map(|b| b.fitted_at_points),
            bounds.and_then(|b| b.mirror),
            MirrorSearch::for_object(mirror_rays, class_sizes.of(object.id)),
            &cloud.0,
        )
    });
    for ((entity, id), fitted) in refit_stale_boxes(clouds, progress.phase(), &settings.0.objects) {
        let fitted = match fitted {
            Ok(fitted) => ObjectBounds {
                oriented_box: fitted.oriented_box,
                fitted_at_points: fitted.fitted_at_points,
                mirror: fitted.mirror,
            },
            Err(e) => {
                tracing::warn!(object = %id, error = %e, "cannot fit an oriented box yet");
                continue;
            }
        };
        match objects.get_mut(entity).ok().and_then(|(_, _, _, bounds)| bounds) {
            Some(mut bounds) => *bounds = fitted,
            None => {
                commands.entity(entity).insert(fitted);
            }
        }
    }
}
