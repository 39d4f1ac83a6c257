//! Cloud stage: observed point clouds grow with each frame, and oriented boxes follow them.

use bevy_ecs::prelude::*;
use catmap::ids::ObjectId;
use catmap::objects::object_bounds::{MirrorSearch, refit_stale_boxes};
use rayon::prelude::*;

use crate::components::{Background, CameraFrame, FrameObservations, Object, ObjectBounds, ObjectCloud};
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
/// `bounds_refresh_growth` since its last fit, and of every grown one when the stream ends
/// (`catmap::objects::object_bounds::refit_stale_boxes`; results written back in query order).
pub fn refresh_object_bounds(
    settings: Res<Settings>,
    progress: Res<StreamProgress>,
    mut objects: Query<(Entity, &Object, &ObjectCloud, Option<&mut ObjectBounds>)>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let _timer = times.start("bounds");
    let clouds = objects.iter().map(|(entity, object, cloud, bounds)| {
        let mirror = bounds.and_then(|b| b.mirror);
        (
            (entity, object.id),
            bounds.map(|b| b.fitted_at_points),
            mirror,
            &cloud.0,
        )
    });
    let mirror_search = MirrorSearch::for_mirror_rays(settings.0.object_rays().mirror_rays());
    for ((entity, id), fitted) in
        refit_stale_boxes(clouds, progress.phase(), mirror_search, &settings.0.object_settings())
    {
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
