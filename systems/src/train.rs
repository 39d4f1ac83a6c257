//! Train stage: objects with a box get a field, incoming frames queue training steps, and the
//! queued steps run — all object fields as one batched step, the background every n-th step.

use bevy_ecs::prelude::*;
use catmap::field::{
    BACKGROUND_HIDDEN, OBJECT_HIDDEN, OccupancyField, RaySamplerConfig, RaySamples, SampleBatch, sample_training_rays,
};
use catmap::rng::{RngStream, seeded_rng};
use nalgebra::Point3;
use rayon::prelude::*;

use crate::category_fields::CategoryFields;
use crate::components::{Background, CameraFrame, FieldLoss, FieldRng, FieldSlot, Keyframes, Object, ObjectBounds};
use crate::resources::{Fields, Settings, StageTimes, TrainingQueue};

/// Gives every object that has a box (and the background, once it has keyframes) its field,
/// in object-id order so that batch indices do not depend on query order.
pub fn attach_fields(
    settings: Res<Settings>,
    mut fields: ResMut<Fields>,
    objects: Query<(Entity, &Object, &ObjectBounds), Without<FieldSlot>>,
    background: Query<(Entity, &Keyframes), (With<Background>, Without<FieldSlot>)>,
    mut commands: Commands,
) {
    let cfg = &settings.0.fields;
    if !cfg.enabled {
        return;
    }
    let mut new: Vec<_> = objects.iter().collect();
    new.sort_by_key(|(_, object, _)| object.id);
    for (entity, object, bounds) in new {
        let mut rng = seeded_rng(settings.0.seed, RngStream::ObjectField(object.id));
        let field = OccupancyField::new(OBJECT_HIDDEN, cfg.object_scale(), &mut rng);
        let index = fields.objects.push(field);
        fields.object_owners.push(entity);
        let origin = bounds.oriented_box.center();
        commands
            .entity(entity)
            .insert((FieldSlot { index, origin }, FieldRng(rng), FieldLoss::default()));
        tracing::debug!(object = %object.id, index, "field created");
    }
    if cfg.background_every == 0 {
        return;
    }
    if let Ok((entity, keyframes)) = background.single()
        && !keyframes.0.is_empty()
    {
        let mut rng = seeded_rng(settings.0.seed, RngStream::BackgroundField);
        let field = OccupancyField::new(BACKGROUND_HIDDEN, cfg.background_scale(), &mut rng);
        let index = fields.background.push(field);
        fields.background_owner = Some(entity);
        let origin = Point3::origin();
        commands
            .entity(entity)
            .insert((FieldSlot { index, origin }, FieldRng(rng), FieldLoss::default()));
    }
}

/// Online schedule: every frame ingested this tick queues `steps_per_frame` steps of the
/// object fields and, in category mode, as many of the category fields.
pub fn queue_online_steps(
    settings: Res<Settings>,
    frames: Query<(), Added<CameraFrame>>,
    mut queue: ResMut<TrainingQueue>,
    mut category: ResMut<CategoryFields>,
) {
    let cfg = &settings.0.fields;
    if cfg.enabled && !cfg.offline {
        let steps = frames.iter().count() as u64 * cfg.steps_per_frame as u64;
        queue.pending += steps;
        if settings.0.category_fields.enabled {
            category.pending += steps;
        }
    }
}

/// The owners of fields: whether it is the background, its keyframes, slot, generator and loss.
type FieldOwners<'w, 's> = Query<
    'w,
    's,
    (
        Has<Background>,
        &'static Keyframes,
        &'static FieldSlot,
        &'static mut FieldRng,
        &'static mut FieldLoss,
    ),
>;

/// Runs the queued steps: each step samples every field's rays (fields in parallel, each from
/// its own generator) and trains all object fields in one batched step; the background trains
/// every `background_every`-th step.
pub fn train_fields(
    settings: Res<Settings>,
    mut fields: ResMut<Fields>,
    mut queue: ResMut<TrainingQueue>,
    mut owners: FieldOwners,
    mut times: ResMut<StageTimes>,
) {
    if queue.pending == 0 {
        return;
    }
    let _timer = times.start("train");
    let cfg = &settings.0.fields;
    let fields = &mut *fields;
    for _ in 0..std::mem::take(&mut queue.pending) {
        if !fields.objects.is_empty() {
            let losses = train_one(&mut owners, false, &mut fields.objects, &cfg.object_rays);
            if let Err(e) = losses {
                tracing::warn!(error = %e, "object training step skipped");
            }
        }
        let background_due = cfg.background_every > 0 && queue.steps_done.is_multiple_of(cfg.background_every as u64);
        if background_due && !fields.background.is_empty() {
            let losses = train_one(&mut owners, true, &mut fields.background, &cfg.background_rays);
            if let Err(e) = losses {
                tracing::warn!(error = %e, "background training step skipped");
            }
        }
        queue.steps_done += 1;
    }
}

/// One step of `batch`: samples the rays of its owners (the background's, or the objects') in
/// parallel, trains, and records each owner's losses.
fn train_one(
    owners: &mut FieldOwners,
    background: bool,
    batch: &mut catmap::field::FieldBatch,
    rays: &RaySamplerConfig,
) -> catmap::Result<()> {
    let mut work: Vec<_> = owners
        .iter_mut()
        .filter(|(is_background, ..)| *is_background == background)
        .collect();
    work.sort_by_key(|(_, _, slot, _, _)| slot.index);
    if work.len() != batch.len() || work.iter().enumerate().any(|(i, (_, _, slot, _, _))| slot.index != i) {
        return Err(catmap::CatmapError::Degenerate(format!(
            "{} fields but {} owners with matching slots",
            batch.len(),
            work.len()
        )));
    }
    let fields: Vec<RaySamples> = work
        .par_iter_mut()
        .map(|(_, keyframes, slot, rng, _)| {
            let window = &keyframes.0;
            let views: Vec<_> = window.slots().iter().map(|s| &s.data).collect();
            sample_training_rays(&views, window.recent_slots(), &slot.origin, rays, &mut rng.0)
        })
        .collect();
    let losses = batch.train_step(&SampleBatch { fields })?;
    for ((.., loss), latest) in work.iter_mut().zip(losses) {
        loss.latest = latest;
        loss.steps += 1;
    }
    Ok(())
}
