//! Cloud stage: observed point clouds grow with each frame, and oriented boxes follow them.

use bevy_ecs::prelude::*;
use catmap::ObjectId;
use catmap::objects::object_bounds::{box_is_stale, fit_object_box};
use catmap::objects::observed_cloud::ObservedCloud;
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
        if let Ok(cloud) = background.single_mut() {
            work.push((cloud, &observations.0.background_pixels));
        }
        work.par_iter_mut().for_each(|(cloud, pixels)| {
            cloud.0.add_pixels(&frame.0, pixels);
        });
    }
}

/// Refits the oriented box of every object whose cloud has grown by more than
/// `bounds_refresh_growth` since its last fit, and of every grown one when the stream ends
/// (stale objects are fitted in parallel; results are written back in query order).
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
    let stale: Vec<(Entity, ObjectId, &ObservedCloud)> = objects
        .iter()
        .filter(|(_, _, cloud, bounds)| box_is_stale(bounds.map(|b| b.fitted_at_points), cloud.0.len(), growth))
        .map(|(entity, object, cloud, _)| (entity, object.id, &cloud.0))
        .collect();
    let fits: Vec<(Entity, ObjectId, catmap::Result<ObjectBounds>)> = stale
        .into_par_iter()
        .map(|(entity, id, cloud)| {
            let fitted = fit_object_box(cloud, cfg).map(|oriented_box| ObjectBounds {
                oriented_box,
                fitted_at_points: cloud.len(),
            });
            (entity, id, fitted)
        })
        .collect();
    for (entity, id, fitted) in fits {
        let fitted = match fitted {
            Ok(fitted) => fitted,
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
