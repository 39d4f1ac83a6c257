//! The mapper's whole state as a checkpoint, and back: every entity's components (objects, the
//! background, categories), the fields with their optimiser moments and codes (as tensors), the
//! generators, the stream position, the training counters and the stage times. Preview meshes
//! are not kept (they are redrawn), camera frames never outlive a tick, and entities are
//! restored by object id so that nothing depends on the order they were spawned in.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use bevy_ecs::prelude::*;
use catmap::checkpoint::{
    CategoryFieldHeader, OccupancyFieldHeader, TensorStore, load_category_field, load_occupancy_field,
    store_category_field, store_occupancy_field,
};
use catmap::{CatmapError, ClassId, MapperConfig, ObjectId};
use serde::{Deserialize, Serialize};

use crate::components::CategorySlot;
use crate::components::{
    Background, Category, ClassVotes, FieldLoss, FieldRng, FieldSlot, Keyframes, LatestBox, Membership, Object,
    ObjectBounds, ObjectClass, ObjectCloud, ObjectDepthCoverage, ObjectRng, Reliability, Subcategories, VisibleFrames,
};
use crate::resources::CategoryFields;
use crate::resources::{
    Association, BorderHistory, CategoryIndex, Fields, ObjectIndex, Settings, StageTimes, StreamProgress,
    TrainingQueue, TrainingSchedule,
};
use crate::run_state::PhaseProgress;

/// An entity's field: slot, generator and losses.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct FieldState {
    slot: FieldSlot,
    rng: FieldRng,
    loss: FieldLoss,
}

/// One object entity.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct ObjectState {
    object: Object,
    class: ObjectClass,
    votes: ClassVotes,
    latest_box: LatestBox,
    keyframes: Keyframes,
    visible: VisibleFrames,
    #[serde(default)]
    depth_coverage: ObjectDepthCoverage,
    cloud: ObjectCloud,
    rng: ObjectRng,
    bounds: Option<ObjectBounds>,
    field: Option<FieldState>,
    reliability: Option<Reliability>,
    membership: Option<Membership>,
    category_slot: Option<CategorySlot>,
}

/// The background entity.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct BackgroundState {
    keyframes: Keyframes,
    visible: VisibleFrames,
    cloud: ObjectCloud,
    rng: ObjectRng,
    field: Option<FieldState>,
}

/// One category entity.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CategoryState {
    category: Category,
    subcategories: Option<Subcategories>,
}

/// The serde part of a checkpoint (the tensors go to the safetensors file).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(crate) struct MapperState {
    config: MapperConfig,
    progress: StreamProgress,
    /// The association of per-frame masks (empty with consistent ids).
    #[serde(default)]
    association: Association,
    /// The last frames' mask labels for the border votes (empty when they are off).
    #[serde(default)]
    border_history: BorderHistory,
    queue: TrainingQueue,
    schedule: TrainingSchedule,
    phases: PhaseProgress,
    stage_seconds: BTreeMap<String, f64>,
    background: BackgroundState,
    objects: Vec<ObjectState>,
    categories: Vec<CategoryState>,
    /// Owner of each object field, in batch order, and the fields' shapes.
    /// Object fields by batch index, with their owner (none: its object was merged into another).
    object_fields: Vec<(Option<ObjectId>, OccupancyFieldHeader)>,
    background_field: Option<OccupancyFieldHeader>,
    /// Category fields: shape and member objects in code order.
    category_fields: Vec<(CategoryFieldHeader, Vec<ObjectId>)>,
    category_pending: u64,
    category_steps: u64,
    category_losses: Vec<f32>,
    category_carve: Vec<catmap::field::free_space::CarveCounts>,
    category_fields_created: u32,
    category_remaps: u32,
    /// Each category field's creation number (its key in the step scheduler).
    category_ids: Vec<u32>,
    category_frames_replaced: u32,
    category_retired: Vec<catmap::categories::field_set::RetiredField>,
    /// What the caller stored beside the mapper (e.g. the command line), as JSON.
    extra: String,
}

/// Reads the world into a state and its tensors.
pub(crate) fn capture(world: &mut World, extra: String) -> Result<(MapperState, TensorStore), CatmapError> {
    let mut tensors = TensorStore::new();
    let mut objects: Vec<ObjectState> = world
        .query_filtered::<(Entity, &Object), Without<Background>>()
        .iter(world)
        .map(|(entity, _)| entity)
        .collect::<Vec<_>>()
        .into_iter()
        .map(|entity| object_state(world, entity))
        .collect::<Result<_, _>>()?;
    objects.sort_by_key(|o| o.object.id);
    let background_entity = world
        .query_filtered::<Entity, With<Background>>()
        .single(world)
        .map_err(|e| CatmapError::Invariant(format!("no single background entity: {e}")))?;
    let background = {
        let e = world.entity(background_entity);
        let need = || CatmapError::Invariant("the background lacks a component".to_owned());
        BackgroundState {
            keyframes: e.get::<Keyframes>().ok_or_else(need)?.clone(),
            visible: *e.get::<VisibleFrames>().ok_or_else(need)?,
            cloud: e.get::<ObjectCloud>().ok_or_else(need)?.clone(),
            rng: e.get::<ObjectRng>().ok_or_else(need)?.clone(),
            field: field_state(e),
        }
    };
    let mut categories: Vec<CategoryState> = world
        .query::<(&Category, Option<&Subcategories>)>()
        .iter(world)
        .map(|(category, subcategories)| CategoryState {
            category: category.clone(),
            subcategories: subcategories.cloned(),
        })
        .collect();
    categories.sort_by_key(|c| c.category.class);

    let id_of = |entity: &Entity| world.get::<Object>(*entity).map(|o| o.id);
    let fields = world.resource::<Fields>();
    let mut object_fields = Vec::new();
    for (index, (field, owner)) in fields.objects.fields().iter().zip(&fields.object_owners).enumerate() {
        let no_owner = || CatmapError::Invariant(format!("object field {index} has no owner"));
        let id = owner
            .as_ref()
            .map(|owner| id_of(owner).ok_or_else(no_owner))
            .transpose()?;
        object_fields.push((
            id,
            store_occupancy_field(field, &format!("objects/{index}"), &mut tensors),
        ));
    }
    let background_field = fields
        .background
        .field(0)
        .map(|field| store_occupancy_field(field, "background", &mut tensors));
    let category = world.resource::<CategoryFields>();
    let mut category_fields = Vec::new();
    for (k, (field, members)) in category.batch.fields().iter().zip(&category.members).enumerate() {
        let header = store_category_field(field, &format!("categories/{k}"), &mut tensors);
        category_fields.push((header, members.clone()));
    }
    let state = MapperState {
        config: world.resource::<Settings>().0.clone(),
        progress: world.resource::<StreamProgress>().clone(),
        association: world.resource::<Association>().clone(),
        border_history: world.resource::<BorderHistory>().clone(),
        queue: *world.resource::<TrainingQueue>(),
        schedule: world.resource::<TrainingSchedule>().clone(),
        phases: *world.resource::<PhaseProgress>(),
        stage_seconds: world
            .resource::<StageTimes>()
            .0
            .iter()
            .map(|(k, v)| (k.clone(), v.as_secs_f64()))
            .collect(),
        background,
        objects,
        categories,
        object_fields,
        background_field,
        category_fields,
        category_pending: category.pending,
        category_steps: category.steps_done,
        category_losses: category.losses.clone(),
        category_carve: category.carve.clone(),
        category_fields_created: category.fields_created,
        category_remaps: category.remaps,
        category_ids: category.ids.clone(),
        category_frames_replaced: category.frames_replaced,
        category_retired: category.retired.clone(),
        extra,
    };
    Ok((state, tensors))
}

fn field_state(e: EntityRef) -> Option<FieldState> {
    Some(FieldState {
        slot: *e.get::<FieldSlot>()?,
        rng: e.get::<FieldRng>()?.clone(),
        loss: *e.get::<FieldLoss>()?,
    })
}

fn object_state(world: &World, entity: Entity) -> Result<ObjectState, CatmapError> {
    let e = world.entity(entity);
    let need = |what: &str| CatmapError::Invariant(format!("an object lacks its {what}"));
    Ok(ObjectState {
        object: *e.get::<Object>().ok_or_else(|| need("id"))?,
        class: *e.get::<ObjectClass>().ok_or_else(|| need("class"))?,
        votes: e.get::<ClassVotes>().ok_or_else(|| need("votes"))?.clone(),
        latest_box: *e.get::<LatestBox>().ok_or_else(|| need("box"))?,
        keyframes: e.get::<Keyframes>().ok_or_else(|| need("keyframes"))?.clone(),
        visible: *e.get::<VisibleFrames>().ok_or_else(|| need("visible frames"))?,
        depth_coverage: *e.get::<ObjectDepthCoverage>().ok_or_else(|| need("depth coverage"))?,
        cloud: e.get::<ObjectCloud>().ok_or_else(|| need("cloud"))?.clone(),
        rng: e.get::<ObjectRng>().ok_or_else(|| need("generator"))?.clone(),
        bounds: e.get::<ObjectBounds>().copied(),
        field: field_state(e),
        reliability: e.get::<Reliability>().cloned(),
        membership: e.get::<Membership>().copied(),
        category_slot: e.get::<CategorySlot>().copied(),
    })
}

/// A checkpoint read back, before a mapper is built from it (`Mapper::from_checkpoint`): what
/// its caller needs to reopen the stream where the run stopped.
pub struct SavedMapper {
    loaded: catmap::checkpoint::LoadedCheckpoint<MapperState>,
    /// The state file (named in errors).
    file: PathBuf,
}

impl SavedMapper {
    /// Reads the latest complete checkpoint in `dir` (see `catmap::checkpoint`).
    pub fn load(dir: &Path) -> Result<Self, CatmapError> {
        let loaded = catmap::checkpoint::read_checkpoint::<MapperState>(dir)?;
        let file = dir.join(&loaded.manifest.state.name);
        Ok(Self { loaded, file })
    }

    /// The configuration it was taken with.
    pub fn config(&self) -> &MapperConfig {
        &self.loaded.state.config
    }

    /// What the caller stored beside the mapper (its JSON).
    pub fn extra(&self) -> &str {
        &self.loaded.state.extra
    }

    /// Where the run was when it was taken (e.g. "frame 40 of 120").
    pub fn label(&self) -> &str {
        &self.loaded.manifest.label
    }

    /// Stream positions consumed (frames ingested and skipped): the stream continues here.
    pub fn positions_consumed(&self) -> usize {
        let progress = &self.loaded.state.progress;
        (progress.frames_ingested + progress.frames_skipped) as usize
    }

    /// Whether the stream had ended.
    pub fn stream_ended(&self) -> bool {
        self.loaded.state.progress.ended.is_some()
    }

    /// Its parts: the state, the tensors and the state file's path.
    pub(crate) fn into_parts(self) -> (MapperState, TensorStore, PathBuf) {
        (self.loaded.state, self.loaded.tensors, self.file)
    }
}

/// Writes `state` and `tensors` into a mapper world freshly built from the state's config
/// (`file` names the checkpoint in errors).
pub(crate) fn restore(
    world: &mut World,
    state: MapperState,
    mut tensors: TensorStore,
    file: &Path,
) -> Result<(), CatmapError> {
    let bad = |reason: String| CatmapError::checkpoint(file, reason);
    let background_entity = world
        .query_filtered::<Entity, With<Background>>()
        .single(world)
        .map_err(|e| bad(format!("fresh mapper without background: {e}")))?;
    let b = state.background;
    let mut background = world.entity_mut(background_entity);
    background.insert((b.keyframes, b.visible, b.cloud, b.rng));
    if let Some(f) = b.field {
        background.insert((f.slot, f.rng, f.loss));
    }

    let mut index = BTreeMap::new();
    let mut places = BTreeMap::new();
    for o in state.objects {
        let mut e = world.spawn((
            o.object,
            o.class,
            o.votes,
            o.latest_box,
            o.keyframes,
            o.visible,
            o.depth_coverage,
            o.cloud,
            o.rng,
        ));
        if let Some(bounds) = o.bounds {
            e.insert(bounds);
        }
        if let Some(f) = o.field {
            e.insert((f.slot, f.rng, f.loss));
        }
        if let Some(reliability) = o.reliability {
            e.insert(reliability);
        }
        if let Some(membership) = o.membership {
            e.insert(membership);
        }
        if let Some(slot) = o.category_slot {
            places.insert(o.object.id, slot.0);
            e.insert(slot);
        }
        index.insert(o.object.id, e.id());
    }
    let mut categories = BTreeMap::<ClassId, Entity>::new();
    for c in state.categories {
        let class = c.category.class;
        let mut e = world.spawn(c.category);
        if let Some(subcategories) = c.subcategories {
            e.insert(subcategories);
        }
        categories.insert(class, e.id());
    }
    let entity_of = |id: &ObjectId| index.get(id).copied().ok_or_else(|| bad(format!("no object {id}")));

    let mut fields = world.resource_mut::<Fields>();
    for (i, (id, header)) in state.object_fields.iter().enumerate() {
        let field = load_occupancy_field(header, &format!("objects/{i}"), &mut tensors, file)?;
        fields.objects.push(field);
        fields.object_owners.push(id.as_ref().map(entity_of).transpose()?);
    }
    if let Some(header) = &state.background_field {
        fields
            .background
            .push(load_occupancy_field(header, "background", &mut tensors, file)?);
        fields.background_owner = Some(background_entity);
    }
    let mut category = world.resource_mut::<CategoryFields>();
    for (k, (header, ids)) in state.category_fields.iter().enumerate() {
        category.batch.push(load_category_field(
            header,
            &format!("categories/{k}"),
            &mut tensors,
            file,
        )?);
        for id in ids {
            entity_of(id)?;
        }
        category.members.push(ids.clone());
    }
    category.pending = state.category_pending;
    category.steps_done = state.category_steps;
    category.losses = state.category_losses;
    category.carve = state.category_carve;
    category.fields_created = state.category_fields_created;
    category.remaps = state.category_remaps;
    category.ids = state.category_ids;
    // The field set's places are its members' slots (`sync_category_fields` keeps them equal).
    category.places = places;
    category.frames_replaced = state.category_frames_replaced;
    category.retired = state.category_retired;
    if category.ids.len() != category.members.len() {
        return Err(bad(format!(
            "{} category fields but {} creation numbers",
            category.members.len(),
            category.ids.len()
        )));
    }
    if !tensors.is_empty() {
        let unused: Vec<_> = tensors.names().collect();
        return Err(bad(format!("tensors nobody owns: {unused:?}")));
    }

    world.insert_resource(ObjectIndex(index));
    world.insert_resource(CategoryIndex(categories));
    world.insert_resource(state.progress);
    world.insert_resource(state.association);
    world.insert_resource(state.border_history);
    world.insert_resource(state.queue);
    world.insert_resource(state.schedule);
    world.insert_resource(state.phases);
    world.insert_resource(StageTimes(
        state
            .stage_seconds
            .into_iter()
            .map(|(k, v)| (k, Duration::from_secs_f64(v.max(0.0))))
            .collect(),
    ));
    Ok(())
}
