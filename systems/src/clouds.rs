//! Cloud stage: observed point clouds grow with each frame, and oriented boxes follow them.

use bevy_ecs::prelude::*;
use catmap::object_bounds::{box_is_stale, fit_object_box};
use rayon::prelude::*;

use crate::components::{Background, CameraFrame, FrameObservations, Object, ObjectBounds, ObjectCloud};
use crate::resources::{Settings, StageTimes, StreamProgress};

/// Back-projects each object's masked depth pixels of the new frames into its cloud
/// (objects in parallel), and the thinned background pixels into the background cloud.
pub fn accumulate_clouds(
    frames: Query<(&CameraFrame, &FrameObservations), Added<FrameObservations>>,
    mut objects: Query<(&Object, &mut ObjectCloud), Without<Background>>,
    mut background: Query<&mut ObjectCloud, With<Background>>,
    mut times: ResMut<StageTimes>,
) {
    let _timer = times.start("clouds");
    for (frame, observations) in &frames {
        let mut work: Vec<(Mut<ObjectCloud>, &[u32])> = objects
            .iter_mut()
            .filter_map(|(object, cloud)| {
                observations
                    .0
                    .objects
                    .get(&object.id)
                    .map(|seen| (cloud, seen.pixels.as_slice()))
            })
            .collect();
        work.par_iter_mut().for_each(|(cloud, pixels)| {
            cloud.0.add_pixels(&frame.0, pixels);
        });
        if let Ok(mut cloud) = background.single_mut() {
            cloud.0.add_pixels(&frame.0, &observations.0.background_pixels);
        }
    }
}

/// Refits the oriented box of every object whose cloud has grown by more than
/// `bounds_refresh_growth` since its last fit, and of every grown one when the stream ends.
pub fn refresh_object_bounds(
    settings: Res<Settings>,
    progress: Res<StreamProgress>,
    mut objects: Query<(Entity, &Object, &ObjectCloud, Option<&mut ObjectBounds>)>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let _timer = times.start("bounds");
    let cfg = &settings.0.objects;
    let growth = if progress.ended.is_some() {
        0.0
    } else {
        cfg.bounds_refresh_growth
    };
    for (entity, object, cloud, bounds) in &mut objects {
        let fitted_at = bounds.as_ref().map(|b| b.fitted_at_points);
        if !box_is_stale(fitted_at, cloud.0.len(), growth) {
            continue;
        }
        let fitted = match fit_object_box(&cloud.0, cfg) {
            Ok(oriented_box) => ObjectBounds {
                oriented_box,
                fitted_at_points: cloud.0.len(),
            },
            Err(e) => {
                tracing::warn!(object = %object.id, error = %e, "cannot fit an oriented box yet");
                continue;
            }
        };
        match bounds {
            Some(mut bounds) => *bounds = fitted,
            None => {
                commands.entity(entity).insert(fitted);
            }
        }
    }
}
