//! Every Rerun entity path and timeline the mapper logs to, in one place (a viewer blueprint
//! and the tests name entities through these).
//!
//! ```text
//! world                          view coordinates (right-handed, z up)
//! world/camera                   camera pose
//! world/camera/image             pinhole; rgb, depth, instances below it
//! world/background/{mesh,loss,steps}
//! world/objects/{id}/{points,box,aligned_box,reliability,mesh,loss,steps,shape_code_norm,texture_code_norm}
//! world/categories/{n}/loss      loss of the category field created n-th (its number holds
//!                                while the field continues under a new membership)
//! ```

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

/// The stream's timeline: the newest frame's index.
pub const FRAME_TIMELINE: &str = "frame";
/// The category phase's timeline: category steps run.
pub const CATEGORY_TIMELINE: &str = "category_step";

/// Root of one object's entities.
pub fn object(id: ObjectId) -> String {
    format!("world/objects/{id}")
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
    /// The last part of the path.
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
}

/// The path of `entity` of object `owner` (`None`: the background).
pub fn of(owner: Option<ObjectId>, entity: OwnerEntity) -> String {
    let root = owner.map_or_else(|| BACKGROUND.to_owned(), object);
    format!("{root}/{}", entity.name())
}

/// The loss of category field number `n` (its creation number, not its place in the batch).
pub fn category_loss(n: u32) -> String {
    format!("world/categories/{n}/loss")
}

/// The carving share of category field number `n`'s samples (see [`OwnerEntity::CarvingShare`]).
pub fn category_carving_share(n: u32) -> String {
    format!("world/categories/{n}/carving_share")
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
        assert_eq!(category_loss(2), "world/categories/2/loss");
        assert!(RGB.starts_with(IMAGE) && IMAGE.starts_with(CAMERA) && CAMERA.starts_with(WORLD));
    }
}
