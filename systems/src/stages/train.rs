//! Train stage: objects with a box get a field, incoming frames queue training steps, and the
//! queued steps run — the object fields the step scheduler plans (`catmap::training`) as one
//! batched step, the background every n-th step.

use bevy_ecs::prelude::*;
use catmap::field::{
    BACKGROUND_HIDDEN, OBJECT_HIDDEN, OccupancyField, RaySamplerConfig, RaySamples, sample_window_rays,
};
use catmap::rng::{RngStream, seeded_rng};
use nalgebra::Point3;
use rayon::prelude::*;

use catmap::FrameIndex;
use catmap::meshing::ObjectMeshConfig;
use catmap::objects::hidden_space::HiddenSpaceCache;
use catmap::training::{
    BatchPlan, ClassShare, ClassSizes, FieldFacts, FieldKey, MeshSource, StreamPhase, class_sizes, object_field_facts,
    takes_shape_priors,
};

use crate::components::{
    Background, CameraFrame, Category, CategorySlot, FieldLoss, FieldRng, FieldSlot, Keyframes, LatestBox, Object,
    ObjectBounds,
};
use crate::failed_step::{FailedStep, StepError, TrainingStep};
use crate::resources::{Fields, Settings, StageTimes, StreamProgress, TrainingQueue, TrainingSchedule};

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
        fields.object_owners.push(Some(entity));
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

/// Which batch a step trains.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FieldOwner {
    /// The object fields.
    Objects,
    /// The background field.
    Background,
}

/// The owners of fields: whether it is the background, the object (and its latest sighting,
/// category membership and box), its keyframes, slot, generator and loss.
type FieldOwners<'w, 's> = Query<
    'w,
    's,
    (
        Has<Background>,
        Option<&'static Object>,
        Option<&'static LatestBox>,
        Has<CategorySlot>,
        Option<&'static ObjectBounds>,
        &'static Keyframes,
        &'static FieldSlot,
        &'static mut FieldRng,
        &'static mut FieldLoss,
    ),
>;

/// Runs the queued steps of the object fields the step scheduler plans for this tick (fields
/// in parallel, each sampling from its own generator; the planned ones in one batched step),
/// recording each one's loss; the background trains every `background_every`-th step.
pub fn train_fields(
    settings: Res<Settings>,
    mut fields: ResMut<Fields>,
    mut queue: ResMut<TrainingQueue>,
    mut schedule: ResMut<TrainingSchedule>,
    progress: Res<StreamProgress>,
    frames: Query<&CameraFrame>,
    categories: Query<&Category>,
    mut owners: FieldOwners,
    mut failed: ResMut<FailedStep>,
    mut times: ResMut<StageTimes>,
) {
    if queue.pending == 0 || failed.is_set() {
        return;
    }
    let _timer = times.start("train");
    let (config, cfg, schedule, fields) = (&settings.0, &settings.0.fields, &mut *schedule, &mut *fields);
    let tick: Vec<FrameIndex> = frames.iter().map(|f| f.0.index).collect();
    let class_sizes = class_sizes(categories.iter().map(|c| &c.members[..]));
    let facts = object_facts(&owners, progress.phase(), &tick, &class_sizes);
    let plan = schedule
        .scheduler
        .plan_batch(&facts, config.training_policy(), &config.schedule.plateau);
    schedule.planned_objects = plan.indices.len();
    let object_rays = config.fields.object_rays;
    for _ in 0..std::mem::take(&mut queue.pending) {
        if !plan.indices.is_empty() {
            let step = train_one(
                &mut owners,
                FieldOwner::Objects,
                &plan,
                (&mut fields.objects, &mut fields.hidden_spaces),
                (&object_rays, &class_sizes),
                &config.meshes.object,
            );
            match step {
                Ok(losses) => schedule.record_step(&plan.keys, &losses, &config.schedule.plateau),
                Err(e) => return failed.record(TrainingStep::ObjectFields, queue.steps_done, *e),
            }
        }
        if cfg.background_due(queue.steps_done) && !fields.background.is_empty() {
            let (plan, batch) = (BatchPlan::background(), (&mut fields.background, &mut Vec::new()));
            let (rays, meshing) = ((&cfg.background_rays, &ClassSizes::default()), &config.meshes.object);
            if let Err(e) = train_one(&mut owners, FieldOwner::Background, &plan, batch, rays, meshing) {
                return failed.record(TrainingStep::Background, queue.steps_done, *e);
            }
        }
        queue.steps_done += 1;
    }
}

/// The step scheduler's facts of every object field (the background's are not planned);
/// `class_sizes` are the objects of each object's class.
fn object_facts(
    owners: &FieldOwners,
    phase: StreamPhase,
    tick: &[FrameIndex],
    class_sizes: &ClassSizes,
) -> Vec<(usize, FieldFacts)> {
    owners
        .iter()
        .filter_map(|(_, object, latest, member, _, _, slot, ..)| {
            let id = object?.id;
            let last_seen = latest.map(LatestBox::last_seen);
            let mesh = MeshSource::of_category_member(member);
            let class = ClassShare::of_class_size(class_sizes.of(id));
            Some((slot.index, object_field_facts(id, last_seen, mesh, phase, tick, class)))
        })
        .collect()
}

/// One step of the fields `plan` names (ascending indices in `batch`; learning rates scaled by
/// its factors): samples their owners' rays (the background's, or the objects', carving the
/// region each object is meshed in) in parallel, trains, and records each owner's losses and
/// carving counts; returns their total losses, in index order. `hidden` keeps, per batch index,
/// the cells of each object's box no view saw into (the solid prior's; empty for the background);
/// `class_sizes` are the objects of each object's class (an object alone in its class takes the
/// priors of objects without a twin). Errors name every planned field, or the objects whose
/// slots lie outside the batch.
fn train_one(
    owners: &mut FieldOwners,
    owner: FieldOwner,
    plan: &BatchPlan,
    (batch, hidden): (&mut catmap::field::FieldBatch, &mut Vec<HiddenSpaceCache>),
    (rays, class_sizes): (&RaySamplerConfig, &ClassSizes),
    meshing: &ObjectMeshConfig,
) -> Result<Vec<f32>, Box<StepError>> {
    let indices = &plan.indices[..];
    let background = owner == FieldOwner::Background;
    let outside: Vec<FieldKey> = owners
        .iter()
        .filter(|(is_background, .., slot, _, _)| *is_background == background && slot.index >= batch.len())
        .map(|(_, object, ..)| object.map_or(FieldKey::Background, |o| FieldKey::Object(o.id)))
        .collect();
    let mut work: Vec<_> = owners
        .iter_mut()
        .filter(|(is_background, .., slot, _, _)| {
            *is_background == background && indices.binary_search(&slot.index).is_ok()
        })
        .map(|(_, object, _, _, bounds, keyframes, slot, rng, loss)| {
            let object_box = bounds.map(|b| meshing.meshed_box(&b.oriented_box));
            let class_size = |o: &Object| class_sizes.of(o.id);
            let priors = object.is_some_and(|o| takes_shape_priors(class_size(o)));
            let fitted_box = bounds.filter(|_| priors).map(|b| b.oriented_box);
            let mirror = bounds
                .filter(|_| priors)
                .and_then(|b| b.mirror)
                .map(|m| m.planes(rays.mirror_planes));
            (keyframes, slot, rng, loss, (object_box, fitted_box, mirror))
        })
        .collect();
    work.sort_by_key(|(_, slot, ..)| slot.index);
    let owned: Vec<usize> = work.iter().map(|(_, slot, ..)| slot.index).collect();
    if owned != indices || indices.last().is_some_and(|&i| i >= batch.len()) {
        let error = catmap::CatmapError::Invariant(format!(
            "{} fields but owners with slots {owned:?} for the planned {indices:?}",
            batch.len()
        ));
        let fields = if outside.is_empty() { plan.keys.clone() } else { outside };
        return Err(Box::new(StepError { fields, error }));
    }
    if !background && hidden.len() < batch.len() {
        hidden.resize_with(batch.len(), HiddenSpaceCache::default);
    }
    // The planned fields' caches, in `work`'s ascending index order (none for the background).
    let mut work_caches: Vec<Option<&mut HiddenSpaceCache>> = hidden
        .iter_mut()
        .enumerate()
        .filter(|(i, _)| owned.binary_search(i).is_ok())
        .map(|(_, cache)| Some(cache))
        .collect();
    work_caches.resize_with(work.len(), || None);
    let fields: Vec<RaySamples> = work
        .par_iter_mut()
        .zip(work_caches.par_iter_mut())
        .map(|((keyframes, slot, rng, _, (object_box, fitted_box, mirror)), cache)| {
            let hidden = cache.as_deref_mut().zip(fitted_box.as_ref());
            sample_window_rays(
                &keyframes.0,
                &slot.origin,
                object_box.as_ref(),
                hidden,
                mirror.as_deref().unwrap_or_default(),
                rays,
                &mut rng.0,
            )
        })
        .collect();
    let losses = batch
        .train_step_scaled(indices, &plan.learning_rate_scales, &fields)
        .map_err(|error| {
            Box::new(StepError {
                fields: plan.keys.clone(),
                error,
            })
        })?;
    for (((.., loss, _), latest), sampled) in work.iter_mut().zip(&losses).zip(&fields) {
        loss.latest = *latest;
        loss.steps += 1;
        loss.carve = loss.carve + sampled.carve;
    }
    Ok(losses.iter().map(|l| l.total).collect())
}
