//! What an object keeps of one keyframe: the crop of the frame inside its 2D sampling box, with
//! each pixel's state relative to the object. Keeping crops instead of whole frames bounds memory
//! on long streams (a 640×480 frame is ~4.6 MB; a chair's crop is a few hundred kB).

use nalgebra::Isometry3;

use crate::ids::{FrameIndex, ObjectId};
use crate::sensor::frame::{CameraIntrinsics, InstanceLabel, RgbdFrame};
use crate::sensor::pixel_box::PixelBox;

/// A pixel's relation to the object being trained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[repr(u8)]
pub enum PixelState {
    /// The pixel shows another object (or, for an object, the background): free space up to it.
    OtherObject,
    /// The pixel shows this object (for the background entity: shows background).
    ThisObject,
    /// The segmentation does not know (ScanNet's unlabelled pixels).
    Unknown,
    /// The segmentation's label is not trusted ([`InstanceLabel::Unsure`]): the pixel teaches
    /// only the free space before its return, whoever's surface that is
    /// ([`crate::field::ray_sampler::UnsurePixels`]).
    Unsure,
    /// Not a pixel: a prior ray whose samples lie in cells of the object's box that no view saw
    /// into ([`super::hidden_space`]); each sample is asked to be solid.
    HiddenSolid,
    /// Not a pixel: a prior ray whose samples lie under the object's box, below the lowest point
    /// it was seen at (what it stands on); each sample is asked to be empty.
    BelowSupport,
    /// Not a pixel: a prior ray whose samples lie around the centres of cells of the object's
    /// box that a view saw free ([`super::hidden_space`]); each sample is asked to be empty.
    SeenFree,
}

impl PixelState {
    /// Whether the loss reads the ray's measured colour (and, with valid depth, its depth): the
    /// object's own and unknown pixels.
    pub fn reads_colour(self) -> bool {
        matches!(self, Self::ThisObject | Self::Unknown)
    }

    /// The rendered opacity the loss asks of the ray, if it asks one: 1 on the object's pixels,
    /// 0 on other objects' (free space up to them) and on unsure ones (whose samples all lie
    /// before their return).
    pub fn opacity_target(self) -> Option<f32> {
        match self {
            Self::ThisObject => Some(1.0),
            Self::OtherObject | Self::Unsure => Some(0.0),
            Self::Unknown | Self::HiddenSolid | Self::BelowSupport | Self::SeenFree => None,
        }
    }

    /// The occupancy each sample of a prior ray is asked to have (1 solid, 0 empty); `None` for
    /// rays of pixels.
    pub fn sample_target(self) -> Option<f32> {
        match self {
            Self::HiddenSolid => Some(1.0),
            Self::BelowSupport | Self::SeenFree => Some(0.0),
            Self::ThisObject | Self::OtherObject | Self::Unknown | Self::Unsure => None,
        }
    }
}

/// Whose view a crop is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ViewOwner {
    /// A foreground object.
    Object(ObjectId),
    /// The background.
    Background,
}

impl ViewOwner {
    /// The state of a pixel with `label`, seen from this owner.
    pub fn state_of(self, label: InstanceLabel) -> PixelState {
        match (self, label) {
            (_, InstanceLabel::Unknown) => PixelState::Unknown,
            (_, InstanceLabel::Unsure) => PixelState::Unsure,
            (Self::Object(me), InstanceLabel::Object(id)) if me == id => PixelState::ThisObject,
            (Self::Background, InstanceLabel::Background) => PixelState::ThisObject,
            _ => PixelState::OtherObject,
        }
    }
}

/// The crop of one frame kept by one object's keyframe window.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ObjectView {
    /// The frame the crop comes from.
    pub frame: FrameIndex,
    /// Camera pose of that frame.
    pub world_from_camera: Isometry3<f32>,
    /// Intrinsics of the full frame (pixel coordinates below are full-frame coordinates).
    pub intrinsics: CameraIntrinsics,
    /// The cropped region, in full-frame pixels.
    pub region: PixelBox,
    /// RGB of the region, row-major.
    pub rgb: Vec<[u8; 3]>,
    /// Depth of the region in metres (0 = invalid), row-major.
    pub depth_m: Vec<f32>,
    /// State of each pixel of the region, row-major.
    pub states: Vec<PixelState>,
    /// How far a measured depth d may stray: this × d² metres (`dataset.depth_noise_per_m2`).
    #[serde(default)]
    pub depth_noise_per_m2: f32,
    /// The deepest depth the crop measured, metres (0 when none): the sensor reaches at least
    /// this far, so a patch without a return says nothing lies nearer
    /// ([`super::cell_evidence`]); of what lies deeper it says nothing.
    pub deepest_return_m: f32,
}

/// The largest valid depth of `depth_m`, 0 when none is valid.
pub fn deepest_return(depth_m: &[f32]) -> f32 {
    depth_m.iter().filter(|d| d.is_finite()).fold(0.0, |a, &d| a.max(d))
}

impl ObjectView {
    /// Crops `frame` to `region` (clamped to the image) for `owner`.
    pub fn crop(frame: &RgbdFrame, region: PixelBox, owner: ViewOwner) -> Self {
        let k = frame.intrinsics;
        let region = PixelBox {
            u_min: region.u_min.min(k.width - 1),
            v_min: region.v_min.min(k.height - 1),
            u_max: region.u_max.min(k.width - 1),
            v_max: region.v_max.min(k.height - 1),
        };
        let n = (region.width() * region.height()) as usize;
        let (mut rgb, mut depth_m, mut states) = (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
        for v in region.v_min..=region.v_max {
            let row = (v * k.width) as usize;
            let (start, end) = (row + region.u_min as usize, row + region.u_max as usize + 1);
            rgb.extend_from_slice(&frame.rgb[start..end]);
            depth_m.extend_from_slice(&frame.depth_m[start..end]);
            states.extend((start..end).map(|i| owner.state_of(frame.instances.label(i))));
        }
        let deepest_return_m = deepest_return(&depth_m);
        Self {
            frame: frame.index,
            world_from_camera: frame.world_from_camera,
            intrinsics: k,
            region,
            rgb,
            depth_m,
            states,
            depth_noise_per_m2: 0.0,
            deepest_return_m,
        }
    }

    /// The crop with its depth's noise allowance set (`dataset.depth_noise_per_m2`).
    pub fn with_depth_noise(self, depth_noise_per_m2: f32) -> Self {
        Self {
            depth_noise_per_m2,
            ..self
        }
    }

    /// How far the depth `d` measured by this view may stray from the surface, metres.
    pub fn depth_noise_m(&self, d: f32) -> f32 {
        self.depth_noise_per_m2 * d * d
    }

    /// Index into the crop's arrays of full-frame pixel `(u, v)`, if inside the region.
    pub fn index_of(&self, u: u32, v: u32) -> Option<usize> {
        self.region
            .contains(u, v)
            .then(|| ((v - self.region.v_min) * self.region.width() + (u - self.region.u_min)) as usize)
    }

    /// The nearest depth measured within `radius_px` of full-frame pixel `(u, v)` in the crop
    /// (the least valid depth of the square window), if any: a depth camera's holes at depth
    /// edges are a pixel or two wide, and the nearer side of the edge is the surface that hid
    /// what lies behind.
    pub fn nearest_return_around(&self, u: u32, v: u32, radius_px: u32) -> Option<f32> {
        let window = (v.saturating_sub(radius_px)..=v + radius_px)
            .flat_map(|y| (u.saturating_sub(radius_px)..=u + radius_px).map(move |x| (x, y)));
        window
            .filter_map(|(x, y)| self.index_of(x, y))
            .map(|j| self.depth_m[j])
            .filter(|d| d.is_finite() && *d > 0.0)
            .min_by(f32::total_cmp)
    }

    /// Makes the pixels of other objects unsure: what one of two objects found to be one saw as
    /// the other's is its own surface (a frame that showed both apart), and an unsure pixel teaches
    /// only the free space before its return, true whoever's surface it is.
    pub fn others_unsure(&mut self) {
        for state in &mut self.states {
            if *state == PixelState::OtherObject {
                *state = PixelState::Unsure;
            }
        }
    }

    /// Takes in the view of the same frame kept by an object found to be part of this one: its
    /// pixels that showed that object, inside this crop, show this one.
    pub fn absorb(&mut self, other: &ObjectView) {
        let width = other.region.width();
        for (j, state) in other.states.iter().enumerate() {
            let (u, v) = (
                other.region.u_min + j as u32 % width,
                other.region.v_min + j as u32 / width,
            );
            if *state == PixelState::ThisObject
                && let Some(i) = self.index_of(u, v)
            {
                self.states[i] = PixelState::ThisObject;
            }
        }
    }

    /// Bytes held by the crop's pixel arrays.
    pub fn byte_size(&self) -> usize {
        self.rgb.len() * 3 + self.depth_m.len() * 4 + self.states.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::ClassId;
    use crate::sensor::frame::InstanceMask;

    #[test]
    fn a_crop_keeps_the_region_with_states_relative_to_its_owner() {
        use InstanceLabel::{Background as B, Object as O, Unknown as U};
        let me = ObjectId(4);
        let labels = [B, O(me), O(ObjectId(5)), U, O(me), B];
        let frame = RgbdFrame {
            index: FrameIndex(9),
            world_from_camera: Isometry3::identity(),
            intrinsics: CameraIntrinsics {
                width: 3,
                height: 2,
                fx: 1.0,
                fy: 1.0,
                cx: 1.0,
                cy: 1.0,
            },
            rgb: (0..6).map(|i| [i as u8; 3]).collect(),
            depth_m: (0..6).map(|i| i as f32).collect(),
            instances: InstanceMask::from_labels(labels),
            classes: vec![ClassId(0); 6],
        };
        let view = ObjectView::crop(
            &frame,
            PixelBox {
                u_min: 1,
                v_min: 0,
                u_max: 2,
                v_max: 1,
            },
            ViewOwner::Object(me),
        );
        assert_eq!(view.depth_m, [1.0, 2.0, 4.0, 5.0]);
        use PixelState::{OtherObject as X, ThisObject as T};
        assert_eq!(view.states, [T, X, T, X]);
        assert_eq!(view.index_of(2, 1), Some(3));
        assert_eq!(view.index_of(0, 0), None);
        let background = ObjectView::crop(
            &frame,
            PixelBox {
                u_min: 0,
                v_min: 0,
                u_max: 2,
                v_max: 1,
            },
            ViewOwner::Background,
        );
        assert_eq!(background.states[0], T, "background pixels belong to the background");
        assert_eq!(background.states[3], PixelState::Unknown);
    }
}
