//! Mesh stage: field meshes as previews every few frames, and at final resolution at the end.

use bevy_ecs::prelude::*;
use catmap::geometry::mesh::{Aabb, TriangleMesh};
use catmap::meshing::{MapMeshes, ObjectFrame, ObjectMeshConfig, mesh_category_member, mesh_occupancy_field};
use catmap::{FrameIndex, ObjectId};
use rayon::prelude::*;

use crate::components::CategorySlot;
use crate::components::{Background, FieldLoss, FieldMesh, FieldSlot, Object, ObjectBounds, ObjectCloud};
use crate::resources::CategoryFields;
use crate::resources::{Fields, Settings, StageTimes, StreamProgress};

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
/// spacing (for live viewing; the background is only meshed at the end). Members of category
/// fields (online category mode) are meshed from their category field.
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
    insert_meshes(
        meshes,
        &category_fields,
        &members,
        &config,
        MeshPass::Preview,
        &mut commands,
    );
}

/// Meshes every field at final resolution (`meshes.object`; the background at
/// `meshes.background_voxel_m` over its cloud's bounds).
pub fn extract_final_meshes(
    settings: Res<Settings>,
    fields: Res<Fields>,
    category_fields: Res<CategoryFields>,
    owners: Meshable,
    members: Query<(Entity, &Object, &CategorySlot)>,
    mut times: ResMut<StageTimes>,
    mut commands: Commands,
) {
    let _timer = times.start("meshes");
    let cfg = &settings.0.meshes;
    let meshes = mesh_fields(&fields, &owners, &cfg.object, &cfg.background(), MeshPass::Final);
    insert_meshes(
        meshes,
        &category_fields,
        &members,
        &cfg.object,
        MeshPass::Final,
        &mut commands,
    );
}

/// Which meshes a meshing pass makes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MeshPass {
    /// Object fields at the preview spacing, while the stream runs (no background).
    Preview,
    /// Every field, the background included, at final resolution.
    Final,
}

/// Inserts `meshes` as the owners' [`FieldMesh`]es, the category members' replaced by the mesh
/// of their category field.
fn insert_meshes(
    mut meshes: Vec<(Entity, TriangleMesh, u64)>,
    category_fields: &CategoryFields,
    members: &Query<(Entity, &Object, &CategorySlot)>,
    config: &ObjectMeshConfig,
    pass: MeshPass,
    commands: &mut Commands,
) {
    let from_categories = mesh_category_members(category_fields, members, config);
    meshes.retain(|(entity, ..)| !from_categories.iter().any(|(e, ..)| e == entity));
    let tagged = meshes
        .into_iter()
        .map(|m| (m, false))
        .chain(from_categories.into_iter().map(|m| (m, true)));
    for ((entity, mesh, at_step), from_category) in tagged {
        commands.entity(entity).insert(FieldMesh {
            mesh,
            at_step,
            is_final: pass == MeshPass::Final,
            from_category,
        });
    }
}

/// Meshes every member of a category field over its NOCS frame (members in id order).
fn mesh_category_members(
    fields: &CategoryFields,
    members: &Query<(Entity, &Object, &CategorySlot)>,
    config: &ObjectMeshConfig,
) -> Vec<(Entity, TriangleMesh, u64)> {
    let mut work: Vec<_> = members.iter().collect();
    work.sort_by_key(|(_, object, _)| object.id);
    work.par_iter()
        .filter_map(|&(entity, object, slot)| {
            let field = fields.batch.field(slot.field)?;
            match mesh_category_member(field, slot.member, &slot.nocs, config) {
                Ok(mesh) => Some((entity, mesh, fields.steps_done)),
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
) -> Vec<(Entity, TriangleMesh, u64)> {
    let mut work: Vec<_> = owners
        .iter()
        .filter(|(_, _, is_background, member, _, loss, ..)| {
            loss.steps > 0 && !member && (pass == MeshPass::Final || !is_background)
        })
        .collect();
    work.sort_by_key(|(_, object, ..)| object.map(|o| o.id));
    work.par_iter()
        .filter_map(|&(entity, object, is_background, _, slot, loss, bounds, cloud)| {
            let (field, frame, config) = if is_background {
                let frame = ObjectFrame::from_aabb(&Aabb::from_points(cloud.0.points().iter())?);
                (fields.background.field(slot.index)?, frame, background_config)
            } else {
                let frame = ObjectFrame::from_oriented_box(&bounds?.oriented_box);
                (fields.objects.field(slot.index)?, frame, object_config)
            };
            match mesh_occupancy_field(field, &slot.origin, &frame, config) {
                Ok(mesh) => Some((entity, mesh, loss.steps)),
                Err(e) => {
                    let who = object.map_or_else(|| "background".to_owned(), |o| o.id.to_string());
                    tracing::warn!(owner = %who, error = %e, "meshing failed");
                    None
                }
            }
        })
        .collect()
}

/// The latest meshes of the map, by object id, and the background's.
pub fn collect_meshes(world: &mut World) -> MapMeshes {
    let mut meshes = MapMeshes::default();
    let mut query = world.query::<(Option<&Object>, Has<Background>, &FieldMesh)>();
    for (object, is_background, mesh) in query.iter(world) {
        match (object, is_background) {
            (Some(object), _) => {
                meshes.objects.insert(object.id, mesh.mesh.clone());
            }
            (None, true) => meshes.background = Some(mesh.mesh.clone()),
            (None, false) => {}
        }
    }
    meshes
}

/// Warns about a map without objects and about every object left without a final mesh (too
/// little data to fit a box or train its field); returns the ids of the latter, sorted.
pub fn warn_missing_meshes(world: &mut World, meshes: &MapMeshes) -> Vec<ObjectId> {
    let mut ids: Vec<ObjectId> = world.query::<&Object>().iter(world).map(|o| o.id).collect();
    ids.sort();
    if ids.is_empty() {
        tracing::warn!("the map has no objects: only the background is meshed");
    }
    let min_side = world.resource::<crate::resources::Settings>().0.objects.min_box_side_px;
    for (id, frames) in &world.resource::<crate::resources::SmallInstances>().0 {
        if ids.binary_search(id).is_err() {
            tracing::warn!(
                object = %id,
                frames,
                "never mapped: its 2D box was at most objects.min_box_side_px = {min_side} px in every frame"
            );
        }
    }
    let missing: Vec<ObjectId> = ids.into_iter().filter(|id| !meshes.objects.contains_key(id)).collect();
    for id in &missing {
        tracing::warn!(object = %id, "no mesh: too little data for this object");
    }
    missing
}
