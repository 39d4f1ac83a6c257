//! [`ObjectConfig`] and [`KeyframeConfig`]: how objects are built from instance masks, and their
//! keyframe windows.

use serde::{Deserialize, Serialize};

use crate::geometry::face_normals_turn::BoxTurn;
use crate::objects::border_votes::BorderVotes;
use crate::objects::instance_association::AssociationConfig;
use crate::objects::mask_trim::BandInFront;
use crate::objects::observed_cloud::VoxelVotes;

/// Object entities built from instance masks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ObjectConfig {
    /// An instance whose 2D box is at most this many pixels wide or high is ignored in that frame.
    pub min_box_side_px: u32,
    /// Growth of the 2D box: each side moves out by half this fraction of the box size (0.2 = 20 % larger).
    pub box_enlargement: f32,
    /// Edge of the voxel grid that accumulates each object's observed point cloud, metres.
    pub cloud_voxel_m: f32,
    /// Smallest extent of an object's oriented box, metres.
    pub min_extent_m: f32,
    /// The oriented box is recomputed when the cloud has grown by more than this fraction since
    /// the last computation (0.1 = 10 %).
    pub bounds_refresh_growth: f32,
    /// Voxel edge used to thin the cloud before fitting the oriented box, metres.
    pub bounds_voxel_m: f32,
    /// Cloud voxels holding fewer points than this are left out of the object's shape — its box
    /// fit and its registration to its class
    /// ([`crate::objects::object_bounds::shape_points`]): a depth camera's stray points each
    /// land in a voxel of their own, while a surface fills its voxels frame after frame. All voxels count while fewer than
    /// [`crate::objects::object_bounds::MIN_POINTS_FOR_BOX`] hold enough.
    pub box_min_voxel_points: u32,
    /// Which of those voxels make the object's shape
    /// ([`crate::objects::object_bounds::shape_points`]): `uncontested` (exact masks: every voxel
    /// no view contests) or `mostly_own_main_parts` (a segmenter's masks: those at least half
    /// their views saw as the object's, in the connected parts that hold a large share of them).
    /// Set by [`ObjectConfig::with_mask_borders`].
    pub shape_voxels: ShapeVoxels,
    /// Radius of the local surface (a quadric over the local plane) each point the object's box
    /// and mirror plane are fitted to is moved onto, metres ([`crate::geometry::local_surfaces`];
    /// the points of its shape, [`crate::objects::object_bounds::shape_points`]): a depth
    /// camera's noise makes a face seen from afar a shell centimetres thick, and a box fitted to
    /// it, or a mirror plane matched on it, reads the shell's extremes. 0 (the default, exact
    /// depth): the points stay as observed; [`CAMERA_BOX_SMOOTHING_M`] under `--depth camera`.
    /// Registration reads them unmoved (moved, members registered worse: docs/ROBUSTNESS.md).
    pub box_smoothing_m: f32,
    /// Whether the frames that segment an object vote on its cloud's voxels: a voxel more views
    /// see as something else (a mask bled onto the floor or the wall) is left out of the
    /// object's points ([`crate::objects::observed_cloud`]; `by_views`, the default, or `off`).
    pub voxel_votes: VoxelVotes,
    /// Only every n-th background pixel in each direction feeds the background cloud.
    pub background_pixel_stride: u32,
    /// Voxel edge of the background's observed cloud, metres.
    pub background_voxel_m: f32,
    /// How the oriented box is fitted to the thinned cloud (`paper`: the minimum-volume box).
    pub box_fit: BoxFit,
    /// How an upright box (`box_fit` `upright_on_faces`) is turned once its rectangle is fitted:
    /// `rectangle` (the default, exact depth), or `face_normals` under `--depth camera` — an
    /// object made mostly of upright faces turned to their normals' median turn (a depth
    /// camera's noise turns the rectangle; [`crate::geometry::face_normals_turn`]).
    pub box_turn: BoxTurn,
    /// Whether a round object whose mirror search finds no plane at right angles to its first
    /// takes the plane through its axis of revolution instead (`across_axis`, the default: a
    /// lamp seen from one side gets its unseen back; [`crate::geometry::round_axis`]) or none
    /// (`off`).
    pub round_objects: RoundObjects,
    /// A mask pixel whose depth lies more than `bleed_depth_m` beyond the nearest pixel of its
    /// object within this many pixels is a mask bleeding onto what lies behind, and becomes
    /// unsure ([`crate::objects::mask_trim`]); 0 (the default) turns the check off: at 2 px it
    /// left the Kinect-like scene's boxes metres too large (holes at depth edges leave a bleed
    /// pixel no valid pixel of its object within reach).
    pub bleed_radius_px: u32,
    /// See `bleed_radius_px`, metres.
    pub bleed_depth_m: f32,
    /// Added to `bleed_depth_m` per metre of the pixel's depth: a surface seen at a grazing angle
    /// falls away by more than a few centimetres within a few pixels far off.
    pub bleed_depth_per_m: f32,
    /// Pixels within this many pixels of a border between a mask and anything else are unsure:
    /// no field learns from them ([`crate::objects::mask_trim::mark_unsure_borders`]). A
    /// segmenter's masks are often a pixel or two too large or too small, and a pixel on the
    /// wrong side teaches a field surface metres behind the object or carves its rim. 0 (the
    /// default): every pixel counts.
    pub mask_border_px: u32,
    /// How the band's pixels are decided: `frames = 0` leaves them unsure; else the labels of
    /// the last frames vote ([`crate::objects::border_votes`]).
    pub border_votes: BorderVotes,
    /// Whether band pixels of a mask in front of everything across its border keep their
    /// object's label (`kept`, the default) or are unsure like the rest of the band
    /// ([`crate::objects::mask_trim::spare_pixels_in_front`]).
    pub band_in_front: BandInFront,
    /// How far beyond a band pixel's depth z everything across its border must lie for it to
    /// count as in front: `bleed_depth_m` + this × z metres. A grown pixel shows the surface
    /// behind at the depth of the pixels across its border, so the allowance only has to cover
    /// the depth's noise and a surface falling away at a grazing angle within a few pixels
    /// (0.1 m + 0.03 × 3 m = 0.19 m at 3 m, where the bleed trim's 0.1 per metre asks 0.4 m and
    /// an armchair's side stretcher 0.3 m before the floor lost its band).
    pub in_front_depth_per_m: f32,
    /// Where object ids come from: the dataset's (consistent) ids, or per-frame masks associated
    /// into objects ([`crate::objects::instance_association`]).
    pub association: AssociationConfig,
}

/// `objects.box_smoothing_m` for a depth camera's images (`catmap run --depth camera`): of 3, 5,
/// 6.5, 8 and 12 cm, 8 cm maps the Kinect-like default scene best over three mapper seeds
/// (docs/ROBUSTNESS.md).
pub const CAMERA_BOX_SMOOTHING_M: f32 = 0.08;

/// Which of an object's cloud voxels (of at least `box_min_voxel_points` points) make its shape:
/// its box and its registration ([`crate::objects::object_bounds::shape_points`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ShapeVoxels {
    /// Every voxel no view contests ([`crate::objects::observed_cloud::ViewVotes::contested`]).
    #[default]
    Uncontested,
    /// Those at least half the views that saw them saw as the object's, in the connected parts
    /// holding a large share of them: what a segmenter gave the object in a frame or two — a
    /// neighbour merged into its mask, a mask bled onto a wall behind, a spurious mask — is left
    /// out.
    MostlyOwnMainParts,
}

/// What the masks' borders are like (`catmap run --masks`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaskBorders {
    /// Exact, as rendered or annotated (Replica, ScanNet, the synthetic scenes).
    Exact,
    /// A 2D segmenter's: a pixel or two too large or too small, and filling an object's narrow
    /// gaps with what lies behind them.
    Segmenter,
}

impl ObjectConfig {
    /// These settings for masks with `borders`: a segmenter's masks get the trim of bleeding
    /// pixels within 4 px (with 0.1 m of allowance per metre of depth) and a 2 px unsure band
    /// around every border — on the Kinect-like default scene 4.18 / 3.94 / 81.7 → 3.31 / 2.46 /
    /// 90.9 (docs/ROBUSTNESS.md) — and boxes fitted to the cloud voxels that hold at least 3
    /// points (a pixel the band missed across a slanting edge lands in a voxel of its own) that
    /// most of their views saw as the object's, in its large connected parts
    /// ([`ShapeVoxels::MostlyOwnMainParts`]; docs/ROBUSTNESS.md); exact masks get none of it (the
    /// band costs thin parts every pixel).
    pub fn with_mask_borders(self, borders: MaskBorders) -> Self {
        let (bleed_radius_px, bleed_depth_per_m, mask_border_px, box_min_voxel_points, shape_voxels) = match borders {
            MaskBorders::Exact => (0, 0.0, 0, 1, ShapeVoxels::Uncontested),
            MaskBorders::Segmenter => (4, 0.1, 2, 3, ShapeVoxels::MostlyOwnMainParts),
        };
        Self {
            bleed_radius_px,
            bleed_depth_per_m,
            mask_border_px,
            box_min_voxel_points,
            shape_voxels,
            ..self
        }
    }
}

/// What a round object's second mirror plane is (`objects.round_objects`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RoundObjects {
    /// The vertical plane through its axis of revolution at right angles to its first plane,
    /// when no plane there matches and its points lie on circles about an axis in the first.
    #[default]
    AcrossAxis,
    /// Only a plane whose reflections match (the mirror search alone).
    Off,
}

/// How an object's oriented box is fitted to its observed cloud.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxFit {
    /// The minimum-volume box (METHOD.md §2): it leans when a partly seen object's cloud does.
    MinimumVolume,
    /// The upright box of least footprint (z along world z): furniture stands upright.
    Upright,
    /// The upright box turned so that the observed faces lie on its sides where the least
    /// footprint's turn leaves them off (an object seen from one corner: its footprint is an L,
    /// whose least rectangle may lie along the diagonal; [`crate::geometry::upright_box`]).
    UprightOnFaces,
}

impl Default for ObjectConfig {
    fn default() -> Self {
        Self {
            min_box_side_px: 10,
            box_enlargement: 0.2,
            cloud_voxel_m: 0.01,
            min_extent_m: 0.10,
            bounds_refresh_growth: 0.1,
            bounds_voxel_m: 0.02,
            box_min_voxel_points: 1,
            shape_voxels: ShapeVoxels::Uncontested,
            box_smoothing_m: 0.0,
            voxel_votes: VoxelVotes::default(),
            background_pixel_stride: 4,
            background_voxel_m: 0.05,
            box_fit: BoxFit::UprightOnFaces,
            box_turn: BoxTurn::Rectangle,
            round_objects: RoundObjects::AcrossAxis,
            bleed_radius_px: 0,
            bleed_depth_m: 0.1,
            bleed_depth_per_m: 0.0,
            mask_border_px: 0,
            border_votes: BorderVotes::default(),
            band_in_front: BandInFront::default(),
            in_front_depth_per_m: 0.03,
            association: AssociationConfig::default(),
        }
    }
}

/// Per-object keyframe windows (vMAP's policy).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct KeyframeConfig {
    /// Frames kept per object, including the live one. Must be >= 3.
    pub capacity: usize,
    /// An object's n-th visible frame is a keyframe when n is a multiple of this.
    pub object_stride: u32,
    /// The same for the background.
    pub background_stride: u32,
}

impl Default for KeyframeConfig {
    fn default() -> Self {
        Self {
            capacity: 20,
            object_stride: 25,
            background_stride: 50,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_segmenters_masks_get_the_trim_and_the_border_band_and_exact_ones_neither() {
        let segmenter = ObjectConfig::default().with_mask_borders(MaskBorders::Segmenter);
        assert_eq!(
            (
                segmenter.bleed_radius_px,
                segmenter.bleed_depth_per_m,
                segmenter.mask_border_px
            ),
            (4, 0.1, 2)
        );
        assert_eq!(segmenter.box_min_voxel_points, 3, "boxes skip lone voxels");
        assert_eq!(segmenter.shape_voxels, ShapeVoxels::MostlyOwnMainParts);
        assert_eq!(segmenter.bleed_depth_m, 0.1, "the rest is kept");
        let exact = segmenter.with_mask_borders(MaskBorders::Exact);
        assert_eq!(exact, ObjectConfig::default());
    }
}
