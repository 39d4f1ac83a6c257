//! One posed RGB-D frame with its instance and semantic masks, as every reader produces it.
//!
//! Images are row-major, `width × height`, pixel `(u, v)` at `v * width + u`. The camera follows
//! OpenCV: x right, y down, z forward; depth is the z coordinate in metres (0 = invalid).

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};

use crate::ids::{ClassId, FrameIndex, ObjectId};

/// Pinhole intrinsics of a depth camera, in pixels.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraIntrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Focal length along x, pixels.
    pub fx: f32,
    /// Focal length along y, pixels.
    pub fy: f32,
    /// Principal point x, pixels.
    pub cx: f32,
    /// Principal point y, pixels.
    pub cy: f32,
}

impl CameraIntrinsics {
    /// A `width` × `height` camera of focal length `focal_px` on both axes, its principal point at
    /// the image's centre.
    pub fn centred(width: u32, height: u32, focal_px: f32) -> Self {
        Self {
            width,
            height,
            fx: focal_px,
            fy: focal_px,
            cx: (width as f32 - 1.0) / 2.0,
            cy: (height as f32 - 1.0) / 2.0,
        }
    }

    /// Replica's camera as the vMAP layout assumes it: 1200×680, f = 600, c = (599.5, 339.5).
    pub const REPLICA: Self = Self {
        width: 1200,
        height: 680,
        fx: 600.0,
        fy: 600.0,
        cx: 599.5,
        cy: 339.5,
    };

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Ray direction through pixel centre `(u, v)` in the camera frame, with z = 1 (not normalised,
    /// so that `origin + depth · dir` is the back-projected point).
    pub fn ray_in_camera(&self, u: f32, v: f32) -> Vector3<f32> {
        Vector3::new((u - self.cx) / self.fx, (v - self.cy) / self.fy, 1.0)
    }

    /// Back-projects pixel `(u, v)` at camera depth `depth_m` into the camera frame.
    pub fn point_in_camera(&self, u: f32, v: f32, depth_m: f32) -> Point3<f32> {
        Point3::from(self.ray_in_camera(u, v) * depth_m)
    }

    /// Projects a camera-frame point to pixel coordinates; `None` behind the camera.
    pub fn project(&self, point_in_camera: &Point3<f32>) -> Option<(f32, f32)> {
        (point_in_camera.z > 1e-6).then(|| {
            (
                self.fx * point_in_camera.x / point_in_camera.z + self.cx,
                self.fy * point_in_camera.y / point_in_camera.z + self.cy,
            )
        })
    }

    /// The same camera on an image scaled by `factor` (e.g. 0.5 halves each side).
    pub fn scaled(&self, factor: f32) -> Self {
        Self {
            width: ((self.width as f32 * factor).round() as u32).max(1),
            height: ((self.height as f32 * factor).round() as u32).max(1),
            fx: self.fx * factor,
            fy: self.fy * factor,
            cx: (self.cx + 0.5) * factor - 0.5,
            cy: (self.cy + 0.5) * factor - 0.5,
        }
    }
}

/// What the instance mask says about one pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InstanceLabel {
    /// Background (walls, floor, …) or no instance.
    Background,
    /// A foreground object instance.
    Object(ObjectId),
    /// The segmentation does not know (ScanNet's unlabelled pixels).
    Unknown,
    /// The segmentation's label is not trusted here (a mask's uncertain border, a mask the
    /// association held back): no field learns from the pixel.
    Unsure,
}

/// Per-pixel instance labels of one frame.
///
/// Stored compactly as `u32` codes; read them through [`InstanceMask::label`].
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct InstanceMask {
    codes: Vec<u32>,
}

impl InstanceMask {
    const BACKGROUND: u32 = 0;
    const UNKNOWN: u32 = u32::MAX;
    const UNSURE: u32 = u32::MAX - 1;

    /// An all-background mask of `pixel_count` pixels.
    pub fn background(pixel_count: usize) -> Self {
        Self {
            codes: vec![Self::BACKGROUND; pixel_count],
        }
    }

    /// Builds a mask from per-pixel labels.
    pub fn from_labels(labels: impl IntoIterator<Item = InstanceLabel>) -> Self {
        Self {
            codes: labels.into_iter().map(Self::encode).collect(),
        }
    }

    fn encode(label: InstanceLabel) -> u32 {
        match label {
            InstanceLabel::Background => Self::BACKGROUND,
            InstanceLabel::Unknown => Self::UNKNOWN,
            InstanceLabel::Unsure => Self::UNSURE,
            InstanceLabel::Object(ObjectId(id)) => {
                debug_assert!(
                    id != Self::BACKGROUND && id != Self::UNKNOWN && id != Self::UNSURE,
                    "object id {id} is reserved"
                );
                id
            }
        }
    }

    /// Label of pixel `i` (row-major index).
    #[inline]
    pub fn label(&self, i: usize) -> InstanceLabel {
        match self.codes[i] {
            Self::BACKGROUND => InstanceLabel::Background,
            Self::UNKNOWN => InstanceLabel::Unknown,
            Self::UNSURE => InstanceLabel::Unsure,
            id => InstanceLabel::Object(ObjectId(id)),
        }
    }

    /// Sets pixel `i`.
    #[inline]
    pub fn set(&mut self, i: usize, label: InstanceLabel) {
        self.codes[i] = Self::encode(label);
    }

    /// The object at pixel `i`, if any.
    #[inline]
    pub fn object_at(&self, i: usize) -> Option<ObjectId> {
        match self.label(i) {
            InstanceLabel::Object(id) => Some(id),
            _ => None,
        }
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.codes.len()
    }

    /// True when the mask has no pixels.
    pub fn is_empty(&self) -> bool {
        self.codes.is_empty()
    }
}

/// One posed RGB-D frame with instance and semantic masks. Shared by `Arc` between the stream,
/// the mapper and the keyframe windows that keep it.
#[derive(Debug, Clone)]
pub struct RgbdFrame {
    /// Position in the stream.
    pub index: FrameIndex,
    /// Camera pose: maps camera coordinates to world coordinates.
    pub world_from_camera: Isometry3<f32>,
    /// Intrinsics of all images of this frame.
    pub intrinsics: CameraIntrinsics,
    /// RGB, 3 bytes per pixel.
    pub rgb: Vec<[u8; 3]>,
    /// Camera-z depth in metres; 0 marks an invalid pixel.
    pub depth_m: Vec<f32>,
    /// Instance labels (background classes already merged into the background).
    pub instances: InstanceMask,
    /// Semantic class per pixel.
    pub classes: Vec<ClassId>,
}

/// A frame shared between the stream, the mapper and keyframe windows.
pub type SharedFrame = Arc<RgbdFrame>;

impl RgbdFrame {
    /// Checks that every image has `width × height` pixels and the pose is finite.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.intrinsics.pixel_count();
        let sizes = [
            ("rgb", self.rgb.len()),
            ("depth", self.depth_m.len()),
            ("instance mask", self.instances.len()),
            ("semantic mask", self.classes.len()),
        ];
        for (what, len) in sizes {
            if len != n {
                return Err(format!("{what} has {len} pixels, expected {n}"));
            }
        }
        let m = self.world_from_camera.to_homogeneous();
        if m.iter().any(|x| !x.is_finite()) {
            return Err("pose has a NaN or infinite entry".to_owned());
        }
        Ok(())
    }

    /// Pixel `(u, v)` of a row-major index.
    #[inline]
    pub fn pixel_of(&self, i: usize) -> (u32, u32) {
        let w = self.intrinsics.width as usize;
        ((i % w) as u32, (i / w) as u32)
    }

    /// World point of pixel `i`, or `None` for invalid depth.
    #[inline]
    pub fn point_in_world(&self, i: usize) -> Option<Point3<f32>> {
        let d = self.depth_m[i];
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        let (u, v) = self.pixel_of(i);
        Some(self.world_from_camera * self.intrinsics.point_in_camera(u as f32, v as f32, d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn project_inverts_back_projection() {
        let k = CameraIntrinsics {
            width: 160,
            height: 120,
            fx: 100.0,
            fy: 110.0,
            cx: 79.5,
            cy: 59.5,
        };
        let p = k.point_in_camera(12.0, 97.0, 2.5);
        let (u, v) = k.project(&p).expect("point is in front of the camera");
        assert!((u - 12.0).abs() < 1e-4 && (v - 97.0).abs() < 1e-4, "got ({u}, {v})");
        assert!((p.z - 2.5).abs() < 1e-6, "depth is the camera z coordinate");
    }

    #[test]
    fn instance_mask_round_trips_every_label() {
        let labels = [
            InstanceLabel::Background,
            InstanceLabel::Object(ObjectId(7)),
            InstanceLabel::Unknown,
        ];
        let mask = InstanceMask::from_labels(labels);
        for (i, label) in labels.iter().enumerate() {
            assert_eq!(mask.label(i), *label, "pixel {i}");
        }
        assert_eq!(mask.object_at(1), Some(ObjectId(7)));
    }

    #[test]
    fn scaled_intrinsics_keep_pixel_centres_aligned() {
        let k = CameraIntrinsics {
            width: 640,
            height: 480,
            fx: 500.0,
            fy: 500.0,
            cx: 319.5,
            cy: 239.5,
        };
        let half = k.scaled(0.5);
        assert_eq!((half.width, half.height), (320, 240));
        assert!((half.cx - 159.5).abs() < 1e-6 && (half.cy - 119.5).abs() < 1e-6);
    }
}
