//! Rerun logging: with `log_camera` and `log_categories`, the only place that talks to Rerun.
//! Every system here only reads components.
//!
//! Entity tree (timelines `frame` and `time`; paths in [`crate::rerun_paths`]):
//! - `world` — static view coordinates (right-handed, z up); the camera: [`super::log_camera`];
//! - `world/objects/{id}/points` — observed cloud, coloured by class;
//!   `world/objects/{id}/box` — minimum-volume oriented box, labelled with class and id;
//!   `world/objects/{id}/mesh` — the field's mesh (previews, then final), vertex-coloured;
//!   `world/objects/{id}/aligned_box` — the box in the representative's frame, coloured by
//!   subcategory, labelled "chair 3 · sub 0" (+ " · rep" for the representative);
//!   `world/objects/{id}/reliability` — the uncertainty sphere's points coloured by g(u);
//! - `world/background/mesh` — the same for the background field;
//! - `objects/merges` — a text line per object merged into another (its entities are cleared);
//! - `training/{loss,steps,carving_share}/{objects/{id},background}` — each field's training
//!   (scalars, once per tick).

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;
use catmap::dataset::class_names::ClassNames;
use catmap::geometry::mesh::TriangleMesh;
use catmap::training::MeshSource;
use catmap::{ClassId, ObjectId};

use crate::components::{
    FieldLoss, FieldMesh, FrameObservations, Membership, Object, ObjectBounds, ObjectClass, ObjectCloud, Reliability,
};
use crate::recording::{Rerun, warn_on_error};
use crate::rerun_paths::{self as paths, OwnerEntity};
use crate::resources::{DatasetClasses, FinalMeshes, Settings, StreamProgress};

/// Logs the static view coordinates once.
pub fn log_world_setup(rerun: &rerun::RecordingStream) {
    warn_on_error(
        rerun.log_static(paths::WORLD, &rerun::ViewCoordinates::RIGHT_HAND_Z_UP()),
        paths::WORLD,
    );
}

/// Logs the depth and mask settings and what the probe found (`report`: Markdown), once.
pub fn log_sensor(rerun: &rerun::RecordingStream, report: &str) {
    warn_on_error(
        rerun.log_static(paths::SENSOR, &rerun::TextDocument::from_markdown(report)),
        paths::SENSOR,
    );
}

/// Logs the legend of the instance image (object id → class name and colour) when objects
/// appear or change class.
pub fn log_instance_legend(
    rerun: Res<Rerun>,
    names: Res<DatasetClasses>,
    changed: Query<(), Changed<ObjectClass>>,
    objects: Query<(&Object, &ObjectClass)>,
) {
    if changed.is_empty() {
        return;
    }
    let mut legend: Vec<(u16, String, rerun::Rgba32)> = objects
        .iter()
        .filter_map(|(object, class)| {
            let id = u16::try_from(object.id.0).ok()?;
            let [r, g, b] = class_color(class.0);
            Some((
                id,
                object_label(&names.0, object.id, class.0),
                rerun::datatypes::Rgba32::from_rgb(r, g, b),
            ))
        })
        .collect();
    legend.sort_by_key(|(id, _, _)| *id);
    let context = rerun::AnnotationContext::new(legend.iter().map(|(id, label, color)| (*id, label.as_str(), *color)));
    warn_on_error(rerun.0.log_static(paths::INSTANCES, &context), paths::INSTANCES);
}

/// Logs an object's cloud when it has grown by `cloud_log_growth` since it was last logged, and
/// every cloud once more when the stream ends.
pub fn log_object_clouds(
    rerun: Res<Rerun>,
    settings: Res<Settings>,
    progress: Res<StreamProgress>,
    objects: Query<(&Object, &ObjectClass, &ObjectCloud)>,
    mut logged_sizes: Local<BTreeMap<ObjectId, usize>>,
) {
    let cfg = &settings.0.rerun;
    let Some(frame) = progress.last_frame else { return };
    rerun.at_frame(frame.0);
    let ended = progress.ended.is_some();
    let mut objects: Vec<_> = objects.iter().collect();
    objects.sort_by_key(|(object, _, _)| object.id);
    for (object, class, cloud) in objects {
        let size = cloud.0.len();
        let last = logged_sizes.get(&object.id).copied().unwrap_or(0);
        let grown = size as f64 > last as f64 * (1.0 + f64::from(cfg.cloud_log_growth));
        if size == 0 || size == last || !(grown || ended) {
            continue;
        }
        let points = cloud.0.points();
        let step = points.len().div_ceil(cfg.max_points_per_object.max(1)).max(1);
        let positions: Vec<[f32; 3]> = points.iter().step_by(step).map(|p| [p.x, p.y, p.z]).collect();
        let [r, g, b] = class_color(class.0);
        let archetype = rerun::Points3D::new(positions)
            .with_colors([rerun::Color::from_rgb(r, g, b)])
            .with_radii([0.004]);
        let path = paths::of(Some(object.id), OwnerEntity::Points);
        warn_on_error(rerun.0.log(path.as_str(), &archetype), &path);
        logged_sizes.insert(object.id, size);
    }
}

/// Logs the oriented box of every object whose box was refitted this tick.
pub fn log_object_boxes(
    rerun: Res<Rerun>,
    names: Res<DatasetClasses>,
    objects: Query<(&Object, &ObjectClass, &ObjectBounds), Changed<ObjectBounds>>,
) {
    for (object, class, bounds) in &objects {
        let b = &bounds.oriented_box;
        let c = b.center();
        let q = b.world_from_box.rotation;
        let [r, g, bl] = class_color(class.0);
        let archetype = rerun::Boxes3D::from_centers_and_half_sizes(
            [[c.x, c.y, c.z]],
            [[b.half_extents.x, b.half_extents.y, b.half_extents.z]],
        )
        .with_quaternions([rerun::Quaternion::from_xyzw([q.i, q.j, q.k, q.w])])
        .with_colors([rerun::Color::from_rgb(r, g, bl)])
        .with_labels([object_label(&names.0, object.id, class.0)]);
        let path = paths::of(Some(object.id), OwnerEntity::Box);
        warn_on_error(rerun.0.log(path.as_str(), &archetype), &path);
    }
}

/// Logs each field's latest total loss and its steps so far (once per tick in which it trained).
pub fn log_field_losses(
    rerun: Res<Rerun>,
    progress: Res<StreamProgress>,
    owners: Query<(Option<&Object>, &FieldLoss), Changed<FieldLoss>>,
) {
    let Some(frame) = progress.last_frame else { return };
    rerun.at_frame(frame.0);
    for (object, loss) in &owners {
        if loss.steps == 0 {
            continue;
        }
        let owner = object.map(|o| o.id);
        let path = paths::of(owner, OwnerEntity::Loss);
        let scalar = rerun::Scalars::single(f64::from(loss.latest.total));
        warn_on_error(rerun.0.log(path.as_str(), &scalar), &path);
        let path = paths::of(owner, OwnerEntity::Steps);
        let steps = rerun::Scalars::single(loss.steps as f64);
        warn_on_error(rerun.0.log(path.as_str(), &steps), &path);
        if loss.carve.inside > 0 {
            let path = paths::of(owner, OwnerEntity::CarvingShare);
            let share = rerun::Scalars::single(loss.carve.share());
            warn_on_error(rerun.0.log(path.as_str(), &share), &path);
        }
    }
}

/// Logs each newly extracted preview mesh (see [`log_owner_mesh`]).
pub fn log_field_meshes(
    rerun: Res<Rerun>,
    progress: Res<StreamProgress>,
    owners: Query<(Option<&Object>, &FieldMesh, Option<&Membership>), Changed<FieldMesh>>,
) {
    if let Some(frame) = progress.last_frame {
        rerun.at_frame(frame.0);
    }
    for (object, mesh, membership) in &owners {
        log_owner_mesh(&rerun, object.map(|o| o.id), &mesh.mesh, mesh.source, membership);
    }
}

/// Logs the final meshes (the run's meshing phase), clustered on `rerun.final_mesh_cell_m`
/// (the written .ply files keep every triangle).
pub fn log_final_meshes(
    rerun: Res<Rerun>,
    finals: Res<FinalMeshes>,
    settings: Res<Settings>,
    progress: Res<StreamProgress>,
    memberships: Query<&Membership>,
) {
    if let Some(frame) = progress.last_frame {
        rerun.at_frame(frame.0);
    }
    let cell = settings.0.rerun.final_mesh_cell_m;
    for owned in finals.0.iter().flatten() {
        let membership = memberships.get(owned.entity).ok();
        let mesh = owned.mesh.clustered(cell);
        log_owner_mesh(&rerun, owned.object, &mesh, owned.source, membership);
    }
}

/// Clears the entities of every object merged into another this tick (`world/objects/{id}`
/// and below) and notes the merge in the stream's text log.
pub fn log_object_merges(rerun: Res<Rerun>, frames: Query<&FrameObservations, Added<FrameObservations>>) {
    for merge in frames.iter().flat_map(|f| &f.0.merges) {
        let path = paths::object(merge.absorbed);
        warn_on_error(rerun.0.log(path.as_str(), &rerun::Clear::recursive()), &path);
        let note = format!(
            "object {} merged into object {} (frame {})",
            merge.absorbed, merge.kept, merge.frame
        );
        warn_on_error(
            rerun.0.log(
                paths::MERGES,
                &rerun::TextLog::new(note).with_level(rerun::TextLogLevel::INFO),
            ),
            paths::MERGES,
        );
    }
}

/// Logs one field mesh at its owner's mesh path: with the field's colours, or, when it comes
/// from a category field, in the colour of the object's subcategory (as its aligned box); an
/// empty mesh clears the path.
fn log_owner_mesh(
    rerun: &Rerun,
    object: Option<ObjectId>,
    mesh: &TriangleMesh,
    source: MeshSource,
    membership: Option<&Membership>,
) {
    let path = paths::of(object, OwnerEntity::Mesh);
    if mesh.is_empty() {
        warn_on_error(rerun.0.log(path.as_str(), &rerun::Clear::flat()), &path);
        return;
    }
    let mut archetype = rerun::Mesh3D::new(mesh.vertices.iter().map(|v| [v.x, v.y, v.z]))
        .with_triangle_indices(mesh.triangles.iter().map(|t| rerun::TriangleIndices::from(*t)));
    match (membership.filter(|_| source == MeshSource::CategoryField), &mesh.colors) {
        (Some(membership), _) => {
            let [r, g, b] = SUBCATEGORY_PALETTE[membership.subcategory % SUBCATEGORY_PALETTE.len()];
            archetype = archetype.with_albedo_factor(rerun::datatypes::Rgba32::from_rgb(r, g, b));
        }
        (None, Some(colors)) => {
            archetype = archetype.with_vertex_colors(colors.iter().map(|[r, g, b]| rerun::Color::from_rgb(*r, *g, *b)));
        }
        (None, None) => {}
    }
    warn_on_error(rerun.0.log(path.as_str(), &archetype), &path);
}

/// Logs each re-registered object's aligned box (coloured by subcategory, the representative
/// labelled) and its uncertainty sphere (points coloured from red, g = 0, to green, g = 1).
pub fn log_memberships(
    rerun: Res<Rerun>,
    names: Res<DatasetClasses>,
    progress: Res<StreamProgress>,
    members: Query<(&Object, &Membership, Option<&Reliability>), Changed<Membership>>,
) {
    if let Some(frame) = progress.last_frame {
        rerun.at_frame(frame.0);
    }
    for (object, membership, reliability) in &members {
        let path = paths::of(Some(object.id), OwnerEntity::AlignedBox);
        warn_on_error(
            rerun
                .0
                .log(path.as_str(), &aligned_box(&names.0, object.id, membership)),
            &path,
        );
        if let Some(reliability) = reliability {
            let path = paths::of(Some(object.id), OwnerEntity::Reliability);
            warn_on_error(
                rerun.0.log(path.as_str(), &reliability_points(&reliability.0.sphere)),
                &path,
            );
        }
    }
}

/// A member's box in its NOCS frame, coloured by subcategory and labelled with its class,
/// subcategory and whether it is the representative.
fn aligned_box(names: &ClassNames, id: ObjectId, membership: &Membership) -> rerun::Boxes3D {
    let b = membership.member.nocs.oriented_box();
    let (c, q) = (b.center(), b.world_from_box.rotation);
    let [r, g, bl] = SUBCATEGORY_PALETTE[membership.subcategory % SUBCATEGORY_PALETTE.len()];
    let rep = if membership.representative == id { " · rep" } else { "" };
    let label = format!(
        "{} · sub {}{rep}",
        object_label(names, id, membership.class),
        membership.subcategory
    );
    rerun::Boxes3D::from_centers_and_half_sizes(
        [[c.x, c.y, c.z]],
        [[b.half_extents.x, b.half_extents.y, b.half_extents.z]],
    )
    .with_quaternions([rerun::Quaternion::from_xyzw([q.i, q.j, q.k, q.w])])
    .with_colors([rerun::Color::from_rgb(r, g, bl)])
    .with_labels([label])
}

/// Every fourth point of an uncertainty sphere, coloured from red (reliability 0) to green (1).
fn reliability_points(sphere: &catmap::categories::uncertainty::ObjectReliability) -> rerun::Points3D {
    let positions = sphere.sphere_points.iter().step_by(4).map(|p| [p.x, p.y, p.z]);
    let colors = sphere.reliability.iter().step_by(4).map(|g| {
        let t = g.clamp(0.0, 1.0);
        rerun::Color::from_rgb(((1.0 - t) * 255.0) as u8, (t * 255.0) as u8, 40)
    });
    rerun::Points3D::new(positions).with_colors(colors).with_radii([0.006])
}

/// Colours of subcategories 0, 1, 2, …
const SUBCATEGORY_PALETTE: [[u8; 3]; 6] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
];

/// "chair 3": the class name (or number) and the object id.
fn object_label(names: &ClassNames, id: ObjectId, class: ClassId) -> String {
    match names.get(class) {
        Some(name) => format!("{name} {id}"),
        None => format!("class {class} / {id}"),
    }
}

/// A fixed, distinct colour per class.
pub fn class_color(class: ClassId) -> [u8; 3] {
    const PALETTE: [[u8; 3]; 12] = [
        [230, 25, 75],
        [60, 180, 75],
        [255, 225, 25],
        [0, 130, 200],
        [245, 130, 48],
        [145, 30, 180],
        [70, 240, 240],
        [240, 50, 230],
        [210, 245, 60],
        [250, 190, 212],
        [0, 128, 128],
        [170, 110, 40],
    ];
    PALETTE[(class.0.wrapping_mul(2_654_435_761) >> 7) as usize % PALETTE.len()]
}
