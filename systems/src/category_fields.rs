//! Category phase (`catmap run --mode category`): once the classes are registered, every
//! subcategory with more than one member gets one category field (METHOD.md §5) whose members
//! are its objects, each sampled in its own NOCS frame; all category fields train as one batch.
//! Single-member subcategories keep their per-object fields.

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;
use catmap::ObjectId;
use catmap::categories::field_plan::plan_category_fields;
use catmap::categories::nocs::NocsFrame;
use catmap::field::category::{CategoryField, CategorySamples};
use catmap::field::sample_training_rays;
use catmap::rng::{RngStream, seeded_rng};
use rayon::prelude::*;

use catmap::FrameIndex;
use catmap::training::{FieldFacts, LastSeen, category_field_facts};

use crate::components::{CameraFrame, CategorySlot, FieldRng, FieldSlot, Keyframes, LatestBox, Object, Subcategories};
use crate::resources::{CategoryFields, Settings, StageTimes, StreamProgress, TrainingSchedule};

/// Keeps one category field per multi-member subcategory (subcategories ordered by
/// representative), whenever a registration changed: creates the fields the first time and,
/// when a re-registration changes the membership (online), continues each field with the
/// subcategory sharing most of its members (`catmap::categories::field_plan`): members keep their
/// codes where they can, and no other field or object loses its training. Every member's slot
/// follows its latest NOCS frame.
pub fn sync_category_fields(
    settings: Res<Settings>,
    mut fields: ResMut<CategoryFields>,
    categories: Query<Ref<Subcategories>>,
    objects: Query<(Entity, &Object, Option<&CategorySlot>)>,
    mut commands: Commands,
) {
    let cfg = &settings.0.category_fields;
    if !cfg.enabled || !categories.iter().any(|s| s.is_changed()) {
        return;
    }
    let mut groups: Vec<(ObjectId, Vec<(ObjectId, NocsFrame)>)> = categories
        .iter()
        .flat_map(|s| {
            s.groups
                .iter()
                .filter(|g| g.members.len() > 1)
                .map(|g| {
                    (
                        g.representative,
                        g.members.iter().map(|(id, m)| (*id, m.nocs)).collect(),
                    )
                })
                .collect::<Vec<_>>()
        })
        .collect();
    groups.sort_by_key(|(representative, _)| *representative);
    let wanted: Vec<Vec<ObjectId>> = groups
        .iter()
        .map(|(_, m)| m.iter().map(|(id, _)| *id).collect())
        .collect();
    let seed = settings.0.seed;
    let fields = &mut *fields;
    if wanted != fields.members {
        let plan = plan_category_fields(&fields.members, &wanted);
        let mut old: Vec<Option<CategoryField>> = Vec::new();
        while let Some(field) = fields.batch.remove(0) {
            old.push(Some(field));
        }
        let mut codes_rng = seeded_rng(seed, RngStream::CategoryCodes(fields.remaps));
        fields.remaps += 1;
        let old_ids = std::mem::take(&mut fields.ids);
        for planned in &plan {
            let continued = planned
                .continues
                .and_then(|i| Some((old.get_mut(i).and_then(Option::take)?, *old_ids.get(i)?)));
            let (field, id) = match continued {
                Some((mut field, id)) => match field.remap_members(&planned.codes, &mut codes_rng) {
                    Ok(()) => (field, id),
                    Err(e) => {
                        tracing::warn!(error = %e, "category field restarted");
                        new_field(seed, cfg.code_dim, planned.members.len(), &mut fields.fields_created)
                    }
                },
                None => new_field(seed, cfg.code_dim, planned.members.len(), &mut fields.fields_created),
            };
            fields.batch.push(field);
            fields.ids.push(id);
            tracing::info!(
                field = fields.batch.len() - 1,
                members = ?planned.members,
                continues = ?planned.continues,
                "category field"
            );
        }
        fields.members = wanted;
        fields.losses = vec![f32::NAN; fields.members.len()];
    }
    let nocs: BTreeMap<ObjectId, NocsFrame> = groups.into_iter().flat_map(|(_, m)| m).collect();
    let places: BTreeMap<ObjectId, (usize, usize)> = fields
        .members
        .iter()
        .enumerate()
        .flat_map(|(k, m)| m.iter().enumerate().map(move |(j, id)| (*id, (k, j))))
        .collect();
    for (entity, object, slot) in &objects {
        match (places.get(&object.id), nocs.get(&object.id)) {
            (Some(&(field, member)), Some(&nocs)) => {
                let wanted = CategorySlot { field, member, nocs };
                if slot != Some(&wanted) {
                    commands.entity(entity).insert(wanted);
                }
            }
            _ if slot.is_some() => {
                commands.entity(entity).remove::<CategorySlot>();
            }
            _ => {}
        }
    }
}

/// A fresh category field (the `created`-th one) with `members` members, and its number.
fn new_field(seed: u64, code_dim: usize, members: usize, created: &mut u32) -> (CategoryField, u32) {
    let id = *created;
    let mut rng = seeded_rng(seed, RngStream::CategoryField(id));
    *created += 1;
    let field = CategoryField::new(
        catmap::field::category::CATEGORY_HIDDEN,
        code_dim,
        1.0,
        members,
        &mut rng,
    );
    (field, id)
}

/// The members of category fields: their keyframes, slots, generators and latest sightings.
type Members<'w, 's> = Query<
    'w,
    's,
    (
        &'static Keyframes,
        &'static FieldSlot,
        &'static CategorySlot,
        &'static LatestBox,
        &'static mut FieldRng,
    ),
>;

/// Runs the queued category steps of the category fields the step scheduler plans for this
/// tick: every member samples its rays from its keyframes (members in parallel, each from its
/// own generator; the reference's ray budget per category, shared by its members), moves them
/// into its NOCS frame, and the planned fields train in one batched step.
pub fn train_category_fields(
    settings: Res<Settings>,
    mut fields: ResMut<CategoryFields>,
    mut schedule: ResMut<TrainingSchedule>,
    frames: Query<&CameraFrame>,
    progress: Res<StreamProgress>,
    mut members: Members,
    objects: Query<(), (With<Object>, With<FieldSlot>)>,
    mut times: ResMut<StageTimes>,
) {
    if fields.pending == 0 || fields.members.is_empty() {
        fields.pending = 0;
        schedule.planned_categories = 0;
        return;
    }
    let _timer = times.start("category_train");
    let config = &settings.0;
    let tick: Vec<FrameIndex> = frames.iter().map(|f| f.0.index).collect();
    let phase = progress.phase();
    let fields = &mut *fields;
    let mut last_seen: Vec<Vec<LastSeen>> = vec![Vec::new(); fields.members.len()];
    for (.., slot, latest, _) in &members {
        if let Some(seen) = last_seen.get_mut(slot.field) {
            seen.push(latest.last_seen());
        }
    }
    let facts: Vec<(usize, FieldFacts)> = fields
        .ids
        .iter()
        .zip(last_seen)
        .map(|(&id, seen)| category_field_facts(id, seen.into_iter().map(Some), phase, &tick))
        .enumerate()
        .collect();
    let schedule = &mut *schedule;
    let plan = schedule
        .scheduler
        .plan_batch(&facts, config.training_policy(), &config.schedule.plateau);
    schedule.planned_categories = plan.indices.len();
    let active = &plan.indices;
    let objects = objects.iter().count();
    let member_count: usize = fields.members.iter().map(Vec::len).sum();
    let categories = fields.members.len() + objects.saturating_sub(member_count);
    let rays_cfg: Vec<_> = fields
        .members
        .iter()
        .map(|m| {
            let rays = config.category_fields.rays_per_member(m.len(), objects, categories);
            config.fields.object_rays.with_rays_per_step(rays)
        })
        .collect();
    for _ in 0..std::mem::take(&mut fields.pending) {
        if active.is_empty() {
            continue;
        }
        let mut work: Vec<_> = members
            .iter_mut()
            .filter(|(_, _, slot, ..)| active.binary_search(&slot.field).is_ok())
            .collect();
        work.sort_by_key(|(_, _, slot, ..)| (slot.field, slot.member));
        let sampled: Vec<_> = work
            .par_iter_mut()
            .map(|(keyframes, field_slot, slot, _, rng)| {
                let window = &keyframes.0;
                let views: Vec<_> = window.slots().iter().map(|s| &s.data).collect();
                let cfg = &rays_cfg[slot.field];
                let rays = sample_training_rays(&views, window.recent_slots(), &field_slot.origin, cfg, &mut rng.0);
                (slot.field, slot.member, field_slot.origin, slot.nocs, rays)
            })
            .collect();
        let mut samples = vec![CategorySamples::default(); active.len()];
        for (field, member, origin, nocs, rays) in sampled {
            let k = active
                .binary_search(&field)
                .expect("only active fields' members sample");
            let nocs_from_world = nocs.world_from_nocs.inverse();
            if let Err(e) = samples[k].push_member_rays(rays, member, &origin, &nocs_from_world) {
                tracing::warn!(field, member, error = %e, "member rays skipped");
            }
        }
        match fields
            .batch
            .train_step_scaled(active, &plan.learning_rate_scales, &samples)
        {
            Ok(losses) => {
                for ((&k, &key), loss) in active.iter().zip(&plan.keys).zip(losses) {
                    fields.losses[k] = loss.total;
                    schedule.scheduler.record(key, loss.total, &config.schedule.plateau);
                }
            }
            Err(e) => tracing::warn!(error = %e, "category training step skipped"),
        }
        fields.steps_done += 1;
    }
}
