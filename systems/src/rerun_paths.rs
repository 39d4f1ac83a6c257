//! Every Rerun entity path and timeline the mapper logs to, in one place (a viewer blueprint
//! and the tests name entities through these). The entity tree, with what is logged where and
//! when, is docs/RERUN.md (a test below keeps it to these paths).

use catmap::ObjectId;

/// Root of the 3D scene.
pub const WORLD: &str = "world";
/// Camera pose.
pub const CAMERA: &str = "world/camera";
/// Pinhole of the logged images.
pub const IMAGE: &str = "world/camera/image";
/// Colour image.
pub const RGB: &str = "world/camera/image/rgb";
/// Depth image.
pub const DEPTH: &str = "world/camera/image/depth";
/// Instance segmentation.
pub const INSTANCES: &str = "world/camera/image/instances";
/// Root of the background's entities.
pub const BACKGROUND: &str = "world/background";
/// Root of the training's time series.
pub const TRAINING: &str = "training";
/// A live stream's scalars.
pub const STREAM: &str = "stream";
/// A live stream's frames taken per second (scalar, once a second).
pub const STREAM_RATE: &str = "stream/frames_per_second";
/// A live stream's frames dropped so far (scalar, once a second).
pub const STREAM_DROPPED: &str = "stream/frames_dropped";

/// What the probe of the dataset found and the settings taken (Markdown, static).
pub const SENSOR: &str = "sensor";

/// The stream's timeline: the newest frame's index.
pub const FRAME_TIMELINE: &str = "frame";
/// The wall clock, beside every other timeline.
pub const WALL_CLOCK_TIMELINE: &str = "time";
/// The category phase's timeline: category steps run.
pub const CATEGORY_TIMELINE: &str = "category_step";

/// A text line per object merged into another (per-frame ids).
pub const MERGES: &str = "objects/merges";

/// Root of every object's entities.
pub const OBJECTS: &str = "world/objects";

/// Root of one object's entities.
pub fn object(id: ObjectId) -> String {
    format!("{OBJECTS}/{id}")
}

/// What is logged under an object (or, for fields, the background).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OwnerEntity {
    /// Its observed cloud.
    Points,
    /// Its oriented box.
    Box,
    /// Its box in its subcategory's frame, coloured by subcategory.
    AlignedBox,
    /// Its uncertainty sphere.
    Reliability,
    /// Its field's latest mesh.
    Mesh,
    /// Its field's latest loss.
    Loss,
    /// Its field's steps.
    Steps,
    /// The share of its field's samples inside its meshed box that carved free space.
    CarvingShare,
    /// The norm of its shape code in its category field.
    ShapeCodeNorm,
    /// The norm of its texture code in its category field.
    TextureCodeNorm,
}

impl OwnerEntity {
    /// The last part of the path (of a scene entity), or the time series' quantity.
    fn name(self) -> &'static str {
        match self {
            Self::Points => "points",
            Self::Box => "box",
            Self::AlignedBox => "aligned_box",
            Self::Reliability => "reliability",
            Self::Mesh => "mesh",
            Self::Loss => "loss",
            Self::Steps => "steps",
            Self::CarvingShare => "carving_share",
            Self::ShapeCodeNorm => "shape_code_norm",
            Self::TextureCodeNorm => "texture_code_norm",
        }
    }

    /// Whether it is logged in the 3D scene (under `world`) or as a time series (under
    /// `training/{quantity}`).
    fn place(self) -> EntityPlace {
        match self {
            Self::Points | Self::Box | Self::AlignedBox | Self::Reliability | Self::Mesh => EntityPlace::Scene,
            Self::Loss | Self::Steps | Self::CarvingShare | Self::ShapeCodeNorm | Self::TextureCodeNorm => {
                EntityPlace::TimeSeries
            }
        }
    }
}

/// Where an owner's entity lives in the tree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum EntityPlace {
    /// `world/objects/{id}/{name}` or `world/background/{name}`.
    Scene,
    /// `training/{name}/objects/{id}` or `training/{name}/background`.
    TimeSeries,
}

/// The time series root of `quantity` (e.g. `training/loss`), the origin of its plot.
pub fn time_series(quantity: OwnerEntity) -> String {
    format!("{TRAINING}/{}", quantity.name())
}

/// The path of `entity` of object `owner` (`None`: the background).
pub fn of(owner: Option<ObjectId>, entity: OwnerEntity) -> String {
    match entity.place() {
        EntityPlace::Scene => {
            let root = owner.map_or_else(|| BACKGROUND.to_owned(), object);
            format!("{root}/{}", entity.name())
        }
        EntityPlace::TimeSeries => {
            let field = owner.map_or_else(|| "background".to_owned(), |id| format!("objects/{id}"));
            format!("{}/{field}", time_series(entity))
        }
    }
}

/// The loss of category field number `n` (its creation number, not its place in the batch).
pub fn category_loss(n: u32) -> String {
    format!("{}/categories/{n}", time_series(OwnerEntity::Loss))
}

/// The carving share of category field number `n`'s samples (see [`OwnerEntity::CarvingShare`]).
pub fn category_carving_share(n: u32) -> String {
    format!("{}/categories/{n}", time_series(OwnerEntity::CarvingShare))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn owners_and_categories_have_their_own_subtrees() {
        assert_eq!(
            of(Some(ObjectId(7)), OwnerEntity::AlignedBox),
            "world/objects/7/aligned_box"
        );
        assert_eq!(of(None, OwnerEntity::Mesh), "world/background/mesh");
        assert_eq!(of(Some(ObjectId(7)), OwnerEntity::Loss), "training/loss/objects/7");
        assert_eq!(of(None, OwnerEntity::Steps), "training/steps/background");
        assert_eq!(category_loss(2), "training/loss/categories/2");
        assert!(RGB.starts_with(IMAGE) && IMAGE.starts_with(CAMERA) && CAMERA.starts_with(WORLD));
    }

    /// Every owner entity; listing a new variant here is what the `match` below asks for.
    fn every_owner_entity() -> Vec<OwnerEntity> {
        use OwnerEntity::{
            AlignedBox, Box, CarvingShare, Loss, Mesh, Points, Reliability, ShapeCodeNorm, Steps, TextureCodeNorm,
        };
        let all = vec![
            Points,
            Box,
            AlignedBox,
            Reliability,
            Mesh,
            Loss,
            Steps,
            CarvingShare,
            ShapeCodeNorm,
            TextureCodeNorm,
        ];
        for entity in &all {
            match entity {
                Points | Box | AlignedBox | Reliability | Mesh | Loss | Steps | CarvingShare | ShapeCodeNorm
                | TextureCodeNorm => {}
            }
        }
        all
    }

    /// Every entity path the mapper logs to, as a pattern: `{id}` for an object's id, `{n}` for
    /// a category field's number.
    fn every_path_pattern() -> Vec<String> {
        const ID: u32 = 424_242;
        const N: u32 = 31_337;
        let object = |path: String| path.replace(&ID.to_string(), "{id}");
        let mut paths: Vec<String> = [
            WORLD,
            CAMERA,
            IMAGE,
            RGB,
            DEPTH,
            INSTANCES,
            STREAM_RATE,
            STREAM_DROPPED,
            SENSOR,
            MERGES,
        ]
        .iter()
        .map(|p| (*p).to_owned())
        .collect();
        paths.extend(
            every_owner_entity()
                .into_iter()
                .map(|entity| object(of(Some(ObjectId(ID)), entity))),
        );
        // The background has a field and a mesh, no cloud, box, registration or codes.
        paths.extend(
            [
                OwnerEntity::Mesh,
                OwnerEntity::Loss,
                OwnerEntity::Steps,
                OwnerEntity::CarvingShare,
            ]
            .into_iter()
            .map(|entity| of(None, entity)),
        );
        let category = |path: String| path.replace(&N.to_string(), "{n}");
        paths.extend([category(category_loss(N)), category(category_carving_share(N))]);
        paths
    }

    #[test]
    fn docs_rerun_md_has_a_row_for_every_entity_path_and_no_other() {
        let page = include_str!("../../docs/RERUN.md");
        let rows: Vec<&str> = page
            .lines()
            .filter(|line| line.starts_with("| `"))
            .filter_map(|row| row.split('`').nth(1))
            .collect();
        let paths = every_path_pattern();
        let missing: Vec<&String> = paths.iter().filter(|p| !rows.contains(&p.as_str())).collect();
        assert!(
            missing.is_empty(),
            "entity paths without a row in docs/RERUN.md: {missing:?}"
        );
        let stale: Vec<&&str> = rows.iter().filter(|r| !paths.iter().any(|p| p == *r)).collect();
        assert!(
            stale.is_empty(),
            "rows of docs/RERUN.md naming no entity path: {stale:?}"
        );
        assert_eq!(rows.len(), paths.len(), "one row per path: {rows:?}");
        for timeline in [FRAME_TIMELINE, CATEGORY_TIMELINE, WALL_CLOCK_TIMELINE] {
            assert!(
                page.contains(&format!("`{timeline}` (")),
                "docs/RERUN.md names the timeline {timeline}"
            );
        }
    }
}
