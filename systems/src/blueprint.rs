//! The viewer layout sent with every recording and live stream: the map large on the left (a tab
//! beside it shows the objects alone, with their subcategory boxes — the representative
//! labelled "rep" — and uncertainty spheres); on the right the camera's view with its instance
//! masks, and one time series per training quantity (field losses, steps, the carving share),
//! so that convergence shows at a glance, a live stream's frames per second and drops, and what
//! the probe found of the camera and the masks.
//! Entity paths come from [`crate::rerun_paths`].

use rerun::blueprint::{
    Blueprint, BlueprintActivation, ContainerLike, Horizontal, Spatial2DView, Spatial3DView, Tabs, TextDocumentView,
    TimeSeriesView, Vertical,
};

use crate::rerun_paths::{self as paths, OwnerEntity};

/// The views of the layout, by their titles (what a viewer shows above each).
pub mod titles {
    /// The 3D map: meshes, clouds, boxes, the camera's frustum and image.
    pub const MAP: &str = "Map";
    /// The objects alone: meshes (a category member's in its subcategory's colour), boxes in
    /// their subcategory's colour, uncertainty spheres.
    pub const CATEGORIES: &str = "Categories";
    /// The camera's colour image with the instance masks over it.
    pub const CAMERA: &str = "Camera";
    /// Every field's loss.
    pub const LOSS: &str = "Field losses";
    /// Every field's step count.
    pub const STEPS: &str = "Field steps";
    /// The share of each field's box samples that carved free space.
    pub const CARVING: &str = "Carving share";
    /// A live stream's frames taken per second and frames dropped.
    pub const STREAM: &str = "Live stream";
    /// What the probe found of the camera and the masks, and the settings taken.
    pub const SENSOR: &str = "Sensor";
}

/// The mapper's viewer layout.
pub fn mapper_blueprint() -> Blueprint {
    let map = Spatial3DView::new(titles::MAP)
        .with_origin(format!("/{}", paths::WORLD))
        .into();
    let categories = Spatial3DView::new(titles::CATEGORIES)
        .with_origin(format!("/{}", paths::OBJECTS))
        .into();
    let scene = Tabs::new([map, categories]).into();
    // Depth would cover the colour image; the masks are drawn over it.
    let camera = Spatial2DView::new(titles::CAMERA)
        .with_origin(format!("/{}", paths::IMAGE))
        .with_contents(["+ $origin/**".to_owned(), format!("- /{}", paths::DEPTH)])
        .into();
    let series = |title: &str, quantity: OwnerEntity| -> ContainerLike {
        TimeSeriesView::new(title)
            .with_origin(format!("/{}", paths::time_series(quantity)))
            .into()
    };
    let plots = Tabs::new([
        series(titles::LOSS, OwnerEntity::Loss),
        series(titles::STEPS, OwnerEntity::Steps),
        series(titles::CARVING, OwnerEntity::CarvingShare),
        TimeSeriesView::new(titles::STREAM)
            .with_origin(format!("/{}", paths::STREAM))
            .into(),
        TextDocumentView::new(titles::SENSOR)
            .with_origin(format!("/{}", paths::SENSOR))
            .into(),
    ])
    .into();
    let side = Vertical::new([camera, plots]).with_row_shares([1.0, 1.0]).into();
    Blueprint::new(Horizontal::new([scene, side]).with_column_shares([3.0, 2.0]))
}

/// Sends [`mapper_blueprint`] to `recording`, active and the default layout of catmap's
/// recordings. A failure is logged: the layout is optional, the map is not.
pub fn send_mapper_blueprint(recording: &rerun::RecordingStream) {
    let activation = BlueprintActivation {
        make_active: true,
        make_default: true,
    };
    if let Err(err) = mapper_blueprint().send(recording, activation) {
        tracing::warn!(%err, "cannot send the viewer layout; the recording is written without it");
    }
}
