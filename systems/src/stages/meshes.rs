//! Mesh stage: field meshes as previews every few frames, and at final resolution at the end.

use bevy_ecs::prelude::*;
use catmap::geometry::mesh::Aabb;
use catmap::meshing::{ObjectFrame, ObjectMeshConfig, mesh_category_member, mesh_occupancy_field};
use catmap::training::MeshSource;
use catmap::{FrameIndex, ObjectId};
use rayon::prelude::*;

use crate::components::CategorySlot;
use crate::components::{Background, FieldLoss, FieldMesh, FieldSlot, Object, ObjectBounds, ObjectCloud};
use crate::resources::CategoryFields;
use crate::resources::{Fields, FinalMeshes, OwnerMesh, Settings, SmallInstances, StageTimes, StreamProgress};

/// Fields that can be meshed: objects with a box, and the background with its cloud (members
/// of category fields are meshed from those instead).
type Meshable<'w, 's> = Query<
    'w,
    's,
    (
        Entity,
        Option<&'static Object>,
        Has<Background>,
        Has<CategorySlot>,
        &'static FieldSlot,
        &'static FieldLoss,
        Option<&'static ObjectBounds>,
        &'static ObjectCloud,
    ),
>;

/// Every `preview_every_frames` ingested frames, meshes each trained object field at the preview
/// spacing into its [`FieldMesh`] (for live viewing; the background is only meshed at the end).
/// Members of category fields (online category mode) are meshed from their category field.
pub fn extract_preview_meshes(
    settings: Res<Settings>,
    progress: Res<StreamProgress>,
    fields: Res<Fields>,
    category_fields: Res<CategoryFields>,
    owners: Meshable,
    members: Query<(Entity, &Object, &CategorySlot)>,
    mut last: Local<Option<FrameIndex>>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let every = settings.0.meshes.preview_every_frames;
    let frames = progress.frames_ingested;
    if every == 0 || frames == 0 || !frames.is_multiple_of(every) || *last == progress.last_frame {
        return;
    }
    *last = progress.last_frame;
    let _timer = times.start("meshes");
    let config = settings.0.meshes.preview();
    let meshes = mesh_fields(&fields, &owners, &config, &config, MeshPass::Preview);
    for OwnerMesh {
        entity, mesh, source, ..
    } in with_category_members(meshes, &category_fields, &members, &config)
    {
        commands.entity(entity).insert(FieldMesh { mesh, source });
    }
}

/// Meshes every field at final resolution (`meshes.object`; the background at
/// `meshes.background_voxel_m` over its cloud's bounds) into [`FinalMeshes`] (the run's
/// meshing phase).
pub fn final_meshes(
    settings: Res<Settings>,
    fields: Res<Fields>,
    category_fields: Res<CategoryFields>,
    owners: Meshable,
    members: Query<(Entity, &Object, &CategorySlot)>,
    mut finals: ResMut<FinalMeshes>,
    mut times: ResMut<StageTimes>,
) {
    let _timer = times.start("meshes");
    let cfg = &settings.0.meshes;
    let meshes = mesh_fields(&fields, &owners, &cfg.object, &cfg.background(), MeshPass::Final);
    finals.0 = Some(with_category_members(meshes, &category_fields, &members, &cfg.object));
}

/// Which meshes a meshing pass makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MeshPass {
    /// Object fields at the preview spacing, while the stream runs (no background).
    Preview,
    /// Every field, the background included, at final resolution.
    Final,
}

/// `meshes` with the category members' replaced by the meshes of their category fields.
fn with_category_members(
    mut meshes: Vec<OwnerMesh>,
    category_fields: &CategoryFields,
    members: &Query<(Entity, &Object, &CategorySlot)>,
    config: &ObjectMeshConfig,
) -> Vec<OwnerMesh> {
    let from_categories = mesh_category_members(category_fields, members, config);
    meshes.retain(|own| !from_categories.iter().any(|member| member.entity == own.entity));
    meshes.extend(from_categories);
    meshes
}

/// Meshes every member of a category field over its NOCS frame (members in id order).
fn mesh_category_members(
    fields: &CategoryFields,
    members: &Query<(Entity, &Object, &CategorySlot)>,
    config: &ObjectMeshConfig,
) -> Vec<OwnerMesh> {
    let mut work: Vec<_> = members.iter().collect();
    work.sort_by_key(|(_, object, _)| object.id);
    work.par_iter()
        .filter_map(|&(entity, object, slot)| {
            let field = fields.batch.field(slot.field)?;
            match mesh_category_member(field, slot.member, &slot.nocs, config) {
                Ok(mesh) => Some(OwnerMesh {
                    entity,
                    object: Some(object.id),
                    mesh,
                    source: MeshSource::CategoryField,
                }),
                Err(e) => {
                    tracing::warn!(object = %object.id, error = %e, "category meshing failed");
                    None
                }
            }
        })
        .collect()
}

/// Meshes of the fields of `owners` (objects in parallel); failures are logged and skipped.
fn mesh_fields(
    fields: &Fields,
    owners: &Meshable,
    object_config: &ObjectMeshConfig,
    background_config: &ObjectMeshConfig,
    pass: MeshPass,
) -> Vec<OwnerMesh> {
    let mut work: Vec<_> = owners
        .iter()
        .filter(|(_, _, is_background, member, _, loss, ..)| {
            loss.steps > 0 && !member && (pass == MeshPass::Final || !is_background)
        })
        .collect();
    work.sort_by_key(|(_, object, ..)| object.map(|o| o.id));
    work.par_iter()
        .filter_map(|&(entity, object, is_background, _, slot, _, bounds, cloud)| {
            let (field, frame, config) = if is_background {
                let frame = ObjectFrame::from_aabb(&Aabb::from_points(cloud.0.points().iter())?);
                (fields.background.field(slot.index)?, frame, background_config)
            } else {
                let frame = ObjectFrame::from_oriented_box(&bounds?.oriented_box);
                (fields.objects.field(slot.index)?, frame, object_config)
            };
            match mesh_occupancy_field(field, &slot.origin, &frame, config) {
                Ok(mesh) => Some(OwnerMesh {
                    entity,
                    object: object.map(|o| o.id),
                    mesh,
                    source: MeshSource::OwnField,
                }),
                Err(e) => {
                    let who = object.map_or_else(|| "background".to_owned(), |o| o.id.to_string());
                    tracing::warn!(owner = %who, error = %e, "meshing failed");
                    None
                }
            }
        })
        .collect()
}

/// Warns about a map without objects, about instances never mapped because their 2D box was
/// always too small, and about every object left without a final mesh (too little data to fit a
/// box or train its field).
pub fn warn_missing_meshes(
    settings: Res<Settings>,
    finals: Res<FinalMeshes>,
    small: Res<SmallInstances>,
    objects: Query<&Object>,
) {
    let mut ids: Vec<ObjectId> = objects.iter().map(|o| o.id).collect();
    ids.sort();
    if ids.is_empty() {
        tracing::warn!("the map has no objects: only the background is meshed");
    }
    let min_side = settings.0.objects.min_box_side_px;
    for (id, frames) in &small.0 {
        if ids.binary_search(id).is_err() {
            tracing::warn!(
                object = %id,
                frames,
                "never mapped: its 2D box was at most objects.min_box_side_px = {min_side} px in every frame"
            );
        }
    }
    let meshed: Vec<ObjectId> = finals.0.iter().flatten().filter_map(|m| m.object).collect();
    for id in ids.iter().filter(|id| !meshed.contains(id)) {
        tracing::warn!(object = %id, "no mesh: too little data for this object");
    }
}
