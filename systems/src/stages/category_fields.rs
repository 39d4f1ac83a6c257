//! Category phase (`catmap run --mode category`): once the classes are registered, every
//! subcategory with more than one member gets one category field (METHOD.md §5) whose members
//! are its objects, each sampled in its own NOCS frame; all category fields train as one batch
//! (`catmap::categories::field_set`). Single-member subcategories keep their per-object fields.

use bevy_ecs::prelude::*;
use catmap::FrameIndex;
use catmap::categories::field_set::MemberRays;
use catmap::categories::member_hidden::{
    MemberCells, MemberHiddenCache, MemberSight, hidden_in_every_member_of_fields,
};
use catmap::field::{RaySamplerConfig, sample_member_rays};
use catmap::meshing::ObjectMeshConfig;
use catmap::objects::hidden_space::CellRules;
use catmap::objects::object_view::ObjectView;
use rayon::prelude::*;

use crate::components::{
    CameraFrame, CategorySlot, FieldRng, FieldSlot, Keyframes, LatestBox, Object, ObjectBounds, Subcategories,
};
use crate::failed_step::{FailedStep, StepError, TrainingStep};
use crate::resources::{CategoryFields, Settings, StageTimes, StreamProgress, TrainingSchedule};

/// Keeps one category field per multi-member subcategory whenever a registration changed
/// (`CategoryFieldSet::follow`: fields continue under a new membership, members keep their
/// codes where they can); every member's slot follows its place and latest NOCS frame.
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
    let registered: Vec<_> = categories.iter().collect();
    let groups = registered.iter().flat_map(|s| &s.groups);
    let places = fields.follow(
        groups,
        settings.0.seed,
        cfg.member_codes(),
        &settings.0.categories.frames,
    );
    for (entity, object, slot) in &objects {
        match places.get(&object.id) {
            Some(place) if slot.map(|s| &s.0) != Some(place) => {
                commands.entity(entity).insert(CategorySlot(*place));
            }
            None if slot.is_some() => {
                commands.entity(entity).remove::<CategorySlot>();
            }
            _ => {}
        }
    }
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
        &'static ObjectBounds,
        &'static mut FieldRng,
    ),
>;

/// Runs the queued steps of the category fields the step scheduler plans for this tick: every
/// member of a planned field samples its rays from its keyframes (members in parallel, each from
/// its own generator), and the planned fields train in one batched step.
pub fn train_category_fields(
    settings: Res<Settings>,
    mut fields: ResMut<CategoryFields>,
    mut schedule: ResMut<TrainingSchedule>,
    frames: Query<&CameraFrame>,
    progress: Res<StreamProgress>,
    mut members: Members,
    objects: Query<(), (With<Object>, With<FieldSlot>)>,
    mut failed: ResMut<FailedStep>,
    mut times: ResMut<StageTimes>,
) {
    let (config, schedule) = (&settings.0, &mut *schedule);
    schedule.planned_categories = 0;
    let pending = std::mem::take(&mut fields.pending);
    if pending == 0 || fields.members.is_empty() || failed.is_set() {
        return;
    }
    let _timer = times.start("category_train");
    let tick: Vec<FrameIndex> = frames.iter().map(|f| f.0.index).collect();
    let seen = members
        .iter()
        .map(|(_, _, slot, latest, ..)| (slot.field, latest.last_seen()));
    let facts = fields.facts(seen, progress.phase(), &tick);
    let plan = schedule
        .scheduler
        .plan_batch(&facts, config.training_policy(), &config.schedule.plateau);
    schedule.planned_categories = plan.indices.len();
    let rays = fields.member_rays(
        objects.iter().count(),
        &config.category_fields,
        &config.fields.object_rays,
    );
    let meshing = &config.meshes.object;
    let prior = MemberPrior {
        solid_rays: config.category_fields.hidden_solid_rays,
        cells: CellRules {
            hidden: config.fields.object_rays.hidden_cells,
            unseen: config.category_fields.unseen_cells,
            // Members draw no seen-free cells: the library sets that rule itself.
            ..CellRules::default()
        },
        min_share: config.category_fields.min_hidden_share,
    };
    for _ in 0..pending {
        if plan.indices.is_empty() {
            continue;
        }
        let hidden = (&mut fields.member_hidden, prior);
        let sampled = sample_members(&mut members, &plan.indices, (&rays, meshing), hidden);
        match fields.train_step(&plan, sampled) {
            Ok(losses) => schedule.record_step(&plan.keys, &losses, &config.schedule.plateau),
            Err(error) => {
                let error = StepError {
                    fields: plan.keys.clone(),
                    error,
                };
                return failed.record(TrainingStep::CategoryFields, fields.steps_done, error);
            }
        }
        fields.steps_done += 1;
    }
}

/// The rays of every member of the `active` fields for one step, each drawn from its own
/// keyframes and generator with its field's settings `rays`, carving the region its mesh is
/// extracted in (its NOCS box, `meshing`'s fill), and with `prior.solid_rays` solid-prior rays in
/// the cells of its box no member of its field saw into (`caches` by object field index; members
/// in parallel).
fn sample_members(
    members: &mut Members,
    active: &[usize],
    (rays, meshing): (&[RaySamplerConfig], &ObjectMeshConfig),
    (caches, prior): (&mut Vec<MemberHiddenCache>, MemberPrior),
) -> Vec<MemberRays> {
    let mut work: Vec<_> = members
        .iter_mut()
        .filter(|(_, _, slot, ..)| active.binary_search(&slot.field).is_ok())
        .collect();
    work.sort_by_key(|(_, field_slot, ..)| field_slot.index);
    let mut shared = Vec::new();
    if prior.solid_rays > 0 {
        let cells: Vec<MemberCells> = work
            .iter()
            .map(|(keyframes, _, slot, _, bounds, _)| MemberCells {
                field: slot.field,
                member: slot.member,
                fitted_box: bounds.oriented_box,
                sight: MemberSight {
                    views: views_of(keyframes),
                    nocs: slot.0.nocs,
                },
            })
            .collect();
        let slots: Vec<usize> = work.iter().map(|(_, field_slot, ..)| field_slot.index).collect();
        let caches = caches_of(caches, &slots);
        shared = hidden_in_every_member_of_fields(&cells, caches, prior.cells, prior.min_share);
    }
    shared.resize(work.len(), None);
    work.par_iter_mut()
        .zip(shared)
        .map(|((keyframes, field_slot, slot, _, _, rng), shared)| MemberRays {
            place: slot.0,
            origin: field_slot.origin,
            rays: sample_member_rays(
                &keyframes.0,
                &field_slot.origin,
                &meshing.meshed_box(&slot.0.nocs.oriented_box()),
                shared,
                (&rays[slot.field], prior.solid_rays),
                &mut rng.0,
            ),
        })
        .collect()
}

/// The caches of the object fields `slots` (ascending), grown to hold them.
fn caches_of<'c>(caches: &'c mut Vec<MemberHiddenCache>, slots: &[usize]) -> Vec<&'c mut MemberHiddenCache> {
    if let Some(&last) = slots.last()
        && caches.len() <= last
    {
        caches.resize_with(last + 1, MemberHiddenCache::default);
    }
    caches
        .iter_mut()
        .enumerate()
        .filter(|(i, _)| slots.binary_search(i).is_ok())
        .map(|(_, cache)| cache)
        .collect()
}

/// The members' solid prior: rays per member and step, which hidden and unseen cells it takes,
/// and the share of its box the cells no member saw into must make up.
#[derive(Debug, Clone, Copy)]
struct MemberPrior {
    solid_rays: usize,
    cells: CellRules,
    min_share: f64,
}

/// A member's keyframe crops.
fn views_of(keyframes: &Keyframes) -> Vec<&ObjectView> {
    keyframes.0.slots().iter().map(|s| &s.data).collect()
}
