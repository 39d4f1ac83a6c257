//! Rerun logging: the only place that talks to Rerun. Every system here only reads components.
//!
//! Entity tree (timeline `frame`):
//! - `world` — static view coordinates (right-handed, z up);
//! - `world/camera` — camera pose; `world/camera/image` — pinhole; `…/image/rgb` (JPEG),
//!   `…/image/depth` (u16 mm), `…/image/instances` (segmentation, labelled per object);
//! - `world/objects/{id}/points` — observed cloud, coloured by class;
//!   `world/objects/{id}/box` — minimum-volume oriented box, labelled with class and id;
//!   `world/objects/{id}/mesh` — the field's mesh (previews, then final), vertex-coloured;
//!   `world/objects/{id}/loss` — the field's training loss (scalar, once per tick);
//!   `world/objects/{id}/aligned_box` — the box in the representative's frame, coloured by
//!   subcategory, labelled "chair 3 · sub 0" (+ " · rep" for the representative);
//!   `world/objects/{id}/reliability` — the uncertainty sphere's points coloured by g(u);
//! - `world/background/mesh`, `world/background/loss` — the same for the background field.

use std::collections::BTreeMap;

use bevy_ecs::prelude::*;
use catmap::dataset::classes::replica_name;
use catmap::geometry::mesh::TriangleMesh;
use catmap::sensor::image_ops::{downscale_nearest, downscale_rgb};
use catmap::training::MeshSource;
use catmap::{ClassId, InstanceLabel, ObjectId, RgbdFrame};
use image::ImageEncoder;

use crate::components::{
    CameraFrame, FieldLoss, FieldMesh, Membership, Object, ObjectBounds, ObjectClass, ObjectCloud, Reliability,
};
use crate::rerun_paths::{self as paths, OwnerEntity};
use crate::resources::{Settings, StreamProgress};
use crate::stages::meshes::OwnerMesh;

/// The recording stream every log system writes to.
#[derive(Resource, Clone)]
pub struct Rerun(pub rerun::RecordingStream);

impl Rerun {
    /// Stamps what is logged next with frame `frame` and the wall clock (the `time` timeline).
    pub fn at_frame(&self, frame: u64) {
        self.0.set_time_sequence(paths::FRAME_TIMELINE, frame as i64);
        self.0.set_time(paths::WALL_CLOCK_TIMELINE, std::time::SystemTime::now());
    }
}

/// Logs the static view coordinates once.
pub fn log_world_setup(rerun: &rerun::RecordingStream) {
    warn_on_error(
        rerun.log_static(paths::WORLD, &rerun::ViewCoordinates::RIGHT_HAND_Z_UP()),
        paths::WORLD,
    );
}

/// Logs each new frame's pose, pinhole and (every `image_every` frames) its colour and instance
/// images, and its depth every `depth_every` frames.
pub fn log_camera_frames(rerun: Res<Rerun>, settings: Res<Settings>, frames: Query<&CameraFrame, Added<CameraFrame>>) {
    let cfg = &settings.0.rerun;
    for frame in &frames {
        let frame = &frame.0;
        rerun.at_frame(frame.index.0);
        log_camera_pose(&rerun.0, frame);
        if frame.index.0.is_multiple_of(u64::from(cfg.image_every)) {
            log_images(&rerun.0, frame, cfg.image_downscale, cfg.jpeg_quality);
        }
        if frame.index.0.is_multiple_of(u64::from(cfg.depth_every)) {
            log_depth(&rerun.0, frame, cfg.image_downscale);
        }
    }
}

fn log_camera_pose(rec: &rerun::RecordingStream, frame: &RgbdFrame) {
    let t = frame.world_from_camera.translation.vector;
    let r = frame.world_from_camera.rotation.to_rotation_matrix();
    let m = r.matrix();
    let columns = [
        [m[(0, 0)], m[(1, 0)], m[(2, 0)]],
        [m[(0, 1)], m[(1, 1)], m[(2, 1)]],
        [m[(0, 2)], m[(1, 2)], m[(2, 2)]],
    ];
    let transform =
        rerun::Transform3D::from_translation_mat3x3([t.x, t.y, t.z], rerun::datatypes::Mat3x3::from(columns));
    warn_on_error(rec.log(paths::CAMERA, &transform), paths::CAMERA);
}

fn log_images(rec: &rerun::RecordingStream, frame: &RgbdFrame, downscale: u32, jpeg_quality: u8) {
    let k = frame.intrinsics;
    let (rgb, w, h) = downscale_rgb(&frame.rgb, k.width, k.height, downscale);
    let small = k.scaled(w as f32 / k.width as f32);
    let pinhole = rerun::Pinhole::from_focal_length_and_resolution([small.fx, small.fy], [w as f32, h as f32])
        .with_principal_point([small.cx + 0.5, small.cy + 0.5]);
    warn_on_error(rec.log(paths::IMAGE, &pinhole), paths::IMAGE);

    let mut jpeg = Vec::new();
    let encoded = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, jpeg_quality.clamp(1, 100))
        .write_image(&rgb, w, h, image::ExtendedColorType::Rgb8);
    match encoded {
        Ok(()) => warn_on_error(
            rec.log(
                paths::RGB,
                &rerun::EncodedImage::from_file_contents(jpeg).with_media_type(rerun::MediaType::JPEG),
            ),
            paths::RGB,
        ),
        Err(e) => tracing::warn!(error = %e, "cannot encode the colour image for Rerun"),
    }

    let labels: Vec<u16> = (0..frame.instances.len())
        .map(|i| match frame.instances.label(i) {
            InstanceLabel::Object(ObjectId(id)) => u16::try_from(id).unwrap_or(u16::MAX),
            InstanceLabel::Background | InstanceLabel::Unknown => 0,
        })
        .collect();
    let (labels, _, _) = downscale_nearest(&labels, k.width, k.height, downscale);
    let format = rerun::components::ImageFormat::segmentation([w, h], rerun::ChannelDatatype::U16);
    let segmentation = rerun::SegmentationImage::new(to_le_bytes(&labels), format);
    warn_on_error(rec.log(paths::INSTANCES, &segmentation), paths::INSTANCES);
}

/// Logs the depth image (u16 millimetres, at the colour image's size).
fn log_depth(rec: &rerun::RecordingStream, frame: &RgbdFrame, downscale: u32) {
    let k = frame.intrinsics;
    let depth_mm: Vec<u16> = frame
        .depth_m
        .iter()
        .map(|d| (d * 1000.0).round().clamp(0.0, 65535.0) as u16)
        .collect();
    let (depth_mm, w, h) = downscale_nearest(&depth_mm, k.width, k.height, downscale);
    let depth = rerun::DepthImage::from_gray16(to_le_bytes(&depth_mm), [w, h]).with_meter(1000.0);
    warn_on_error(rec.log(paths::DEPTH, &depth), paths::DEPTH);
}

/// Logs the legend of the instance image (object id → class name and colour) when objects
/// appear or change class.
pub fn log_instance_legend(
    rerun: Res<Rerun>,
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
                object_label(object.id, class.0),
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
        .with_labels([object_label(object.id, class.0)]);
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

/// Logs the final meshes when the mapper records (run once, by `Mapper::extract_final_meshes`),
/// clustered on `rerun.final_mesh_cell_m` (the written .ply files keep every triangle).
pub fn log_final_meshes(
    InRef(meshes): InRef<[OwnerMesh]>,
    rerun: Option<Res<Rerun>>,
    settings: Res<Settings>,
    progress: Res<StreamProgress>,
    memberships: Query<&Membership>,
) {
    let Some(rerun) = rerun else { return };
    if let Some(frame) = progress.last_frame {
        rerun.at_frame(frame.0);
    }
    let cell = settings.0.rerun.final_mesh_cell_m;
    for owned in meshes {
        let membership = memberships.get(owned.entity).ok();
        let mesh = owned.mesh.clustered(cell);
        log_owner_mesh(&rerun, owned.object, &mesh, owned.source, membership);
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
    progress: Res<StreamProgress>,
    members: Query<(&Object, &Membership, Option<&Reliability>), Changed<Membership>>,
) {
    if let Some(frame) = progress.last_frame {
        rerun.at_frame(frame.0);
    }
    for (object, membership, reliability) in &members {
        let path = paths::of(Some(object.id), OwnerEntity::AlignedBox);
        warn_on_error(rerun.0.log(path.as_str(), &aligned_box(object.id, membership)), &path);
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
fn aligned_box(id: ObjectId, membership: &Membership) -> rerun::Boxes3D {
    let b = membership.member.nocs.oriented_box();
    let (c, q) = (b.center(), b.world_from_box.rotation);
    let [r, g, bl] = SUBCATEGORY_PALETTE[membership.subcategory % SUBCATEGORY_PALETTE.len()];
    let rep = if membership.representative == id { " · rep" } else { "" };
    let label = format!(
        "{} · sub {}{rep}",
        object_label(id, membership.class),
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
fn object_label(id: ObjectId, class: ClassId) -> String {
    match replica_name(class) {
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

fn to_le_bytes(values: &[u16]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

pub(crate) fn warn_on_error<E: std::fmt::Display>(result: Result<(), E>, path: &str) {
    if let Err(e) = result {
        tracing::warn!(path, error = %e, "Rerun logging failed");
    }
}
