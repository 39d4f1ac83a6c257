//! What a real depth camera and a 2D segmenter do to a frame, applied to a synthetic one
//! (`catmap synth --noise FAMILY --ids per-frame`).
//!
//! A scene's [`SensorSettings`] name a depth camera ([`DepthNoise`]), a segmenter
//! ([`MaskNoise`]) and how instance ids relate across frames ([`InstanceIds`]). The depth cameras
//! are independent families with parameters from the literature, each in its own file:
//! - [`DepthNoise::Kinect`] and [`MaskNoise::Kinect`]: catmap's own Kinect-like model
//!   ([`kinect`]), the one the mapper's settings were first tuned on;
//! - [`DepthNoise::StructuredLight`] ([`structured_light`]): Kinect v1 / Structure sensor —
//!   disparity quantised to 1/8 px, Nguyen et al.'s axial σ(z), the projector's shadows, holes at
//!   depth edges, in speckles and at grazing angles, 4.5 m range;
//! - [`DepthNoise::TimeOfFlight`] ([`time_of_flight`]): Kinect v2 / Azure Kinect — Fankhauser et
//!   al.'s σ(z, θ), flying pixels at depth edges, multipath in concave corners;
//! - [`DepthNoise::ActiveStereo`] ([`active_stereo`]): RealSense D4xx — σ ∝ z² from the
//!   disparity's sub-pixel error, edges fattened by the matching window, the second imager's
//!   occlusions, holes on dark surfaces and where the projected pattern fades;
//! - [`MaskNoise::Segmenter`] ([`segmenter`]): a 2D instance segmenter — borders off by up to
//!   2 px along their length, small objects missed more often, a large object split into two
//!   masks, two touching objects merged into one, spurious one-frame masks, similar classes
//!   confused.
//!
//! [`InstanceIds::PerFrame`] then gives every frame its own instance ids: the objects of a frame
//! get distinct ids drawn from 1–99 anew, as a per-frame segmenter numbers its masks.
//!
//! Unlabelled pixels have instance 0 and class 0. Every draw of frame `i` comes from one generator
//! of the scene's seed and stream [`RngStream::SensorFrame`]`(i)`, the depth's draws first, so a
//! frame reads the same whichever order frames are read in.

use std::collections::BTreeMap;

use rand::RngExt;
use serde::{Deserialize, Serialize};

use super::render::RenderedFrame;
use crate::dataset::classes::is_replica_background;
use crate::ids::ClassId;
use crate::rng::{RngStream, seeded_rng};

pub mod active_stereo;
pub mod depth_image;
pub mod kinect;
pub mod segmenter;
pub mod structured_light;
pub mod time_of_flight;

pub use kinect::KinectNoise;

/// A depth camera family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DepthNoise {
    /// The rendered depth.
    #[default]
    Exact,
    /// catmap's own Kinect-like depth ([`KinectNoise`]).
    Kinect,
    /// A structured-light camera ([`structured_light::StructuredLight`]).
    StructuredLight,
    /// A time-of-flight camera ([`time_of_flight::TimeOfFlight`]).
    TimeOfFlight,
    /// An active stereo camera ([`active_stereo::ActiveStereo`]).
    ActiveStereo,
}

impl DepthNoise {
    /// The family's axial noise at depth `z_m` on a surface facing the camera (its true σ(z)),
    /// metres; 0 for exact depth.
    pub fn sigma_m(self, z_m: f32) -> f32 {
        match self {
            Self::Exact => 0.0,
            Self::Kinect => KinectNoise::default().sigma_m(z_m),
            Self::StructuredLight => structured_light::StructuredLight::default().sigma_m(z_m),
            Self::TimeOfFlight => time_of_flight::TimeOfFlight::default().sigma_m(z_m, 0.0),
            Self::ActiveStereo => active_stereo::ActiveStereo::default().sigma_m(z_m),
        }
    }

    /// Farthest depth the family returns, metres (`f32::INFINITY` for exact depth).
    pub fn max_range_m(self) -> f32 {
        match self {
            Self::Exact => f32::INFINITY,
            Self::Kinect => KinectNoise::default().max_range_m,
            Self::StructuredLight => structured_light::StructuredLight::default().max_range_m,
            Self::TimeOfFlight => time_of_flight::TimeOfFlight::default().max_range_m,
            Self::ActiveStereo => active_stereo::ActiveStereo::default().max_range_m,
        }
    }
}

/// A segmenter family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MaskNoise {
    /// The rendered masks.
    #[default]
    Exact,
    /// catmap's own segmenter model: masks grown or shrunk whole, missed, mislabelled
    /// ([`KinectNoise`]).
    Kinect,
    /// A 2D instance segmenter ([`segmenter::SegmenterNoise`]).
    Segmenter,
}

/// `catmap synth --noise`: a depth camera and a segmenter together.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SensorModel {
    /// Exact depth and exact masks (the default).
    #[default]
    None,
    /// catmap's own Kinect-like depth and segmenter.
    Kinect,
    /// The depth of [`SensorModel::Kinect`] with exact masks.
    KinectDepth,
    /// The masks of [`SensorModel::Kinect`] with exact depth.
    SegmenterMasks,
    /// A structured-light camera and a 2D instance segmenter.
    StructuredLight,
    /// A time-of-flight camera and a 2D instance segmenter.
    TimeOfFlight,
    /// An active stereo camera and a 2D instance segmenter.
    ActiveStereo,
}

impl SensorModel {
    /// Its depth camera and segmenter.
    pub fn parts(self) -> (DepthNoise, MaskNoise) {
        match self {
            Self::None => (DepthNoise::Exact, MaskNoise::Exact),
            Self::Kinect => (DepthNoise::Kinect, MaskNoise::Kinect),
            Self::KinectDepth => (DepthNoise::Kinect, MaskNoise::Exact),
            Self::SegmenterMasks => (DepthNoise::Exact, MaskNoise::Kinect),
            Self::StructuredLight => (DepthNoise::StructuredLight, MaskNoise::Segmenter),
            Self::TimeOfFlight => (DepthNoise::TimeOfFlight, MaskNoise::Segmenter),
            Self::ActiveStereo => (DepthNoise::ActiveStereo, MaskNoise::Segmenter),
        }
    }
}

/// How instance ids relate across frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InstanceIds {
    /// One id per object over the whole sequence (Replica, ScanNet).
    #[default]
    Consistent,
    /// Every frame numbers its masks anew.
    PerFrame,
}

/// The imperfections of a synthetic scene's frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(from = "SensorRecord")]
pub struct SensorSettings {
    /// The depth camera.
    pub depth: DepthNoise,
    /// The segmenter.
    pub masks: MaskNoise,
    /// Instance ids across frames.
    pub ids: InstanceIds,
}

/// `scene.json`'s `sensor` as written now (`depth`, `masks`, `ids`) or before the families
/// (`model`, `ids`).
#[derive(Deserialize)]
struct SensorRecord {
    #[serde(default)]
    model: Option<SensorModel>,
    #[serde(default)]
    depth: DepthNoise,
    #[serde(default)]
    masks: MaskNoise,
    #[serde(default)]
    ids: InstanceIds,
}

impl From<SensorRecord> for SensorSettings {
    fn from(r: SensorRecord) -> Self {
        match r.model {
            Some(model) => Self::new(model, r.ids),
            None => Self {
                depth: r.depth,
                masks: r.masks,
                ids: r.ids,
            },
        }
    }
}

impl SensorSettings {
    /// The depth camera and segmenter of `model`, with `ids`.
    pub fn new(model: SensorModel, ids: InstanceIds) -> Self {
        let (depth, masks) = model.parts();
        Self { depth, masks, ids }
    }

    /// True when frames stay as rendered.
    pub fn is_exact(&self) -> bool {
        self.depth == DepthNoise::Exact && self.masks == MaskNoise::Exact && self.ids == InstanceIds::Consistent
    }

    /// Frame `position` of a scene seeded with `seed` as the sensor and segmenter would give it;
    /// `classes` are the scene's object classes (what a confused segmenter may say instead).
    pub fn apply(&self, frame: &mut RenderedFrame, seed: u64, position: usize, classes: &[ClassId]) {
        if self.is_exact() {
            return;
        }
        let mut rng = seeded_rng(seed, RngStream::SensorFrame(position as u64));
        let kinect = KinectNoise::default();
        match self.depth {
            DepthNoise::Exact => {}
            DepthNoise::Kinect => kinect::degrade_depth(frame, &kinect, &mut rng),
            DepthNoise::StructuredLight => structured_light::StructuredLight::default().degrade(frame, &mut rng),
            DepthNoise::TimeOfFlight => time_of_flight::TimeOfFlight::default().degrade(frame, &mut rng),
            DepthNoise::ActiveStereo => active_stereo::ActiveStereo::default().degrade(frame, &mut rng),
        }
        match self.masks {
            MaskNoise::Exact => {}
            MaskNoise::Kinect => kinect::degrade_masks(frame, &kinect, classes, &mut rng),
            MaskNoise::Segmenter => segmenter::SegmenterNoise::default().degrade(frame, position, classes, &mut rng),
        }
        if self.ids == InstanceIds::PerFrame {
            renumber_instances(frame, &mut rng);
        }
    }
}

/// True when pixel `i` belongs to an object (not nothing, floor or wall).
pub(crate) fn is_object(frame: &RenderedFrame, i: usize) -> bool {
    frame.instance_ids[i] != 0 && !is_replica_background(frame.classes[i])
}

/// Gives the frame's objects distinct ids drawn from 1–99 (a partial shuffle).
fn renumber_instances(frame: &mut RenderedFrame, rng: &mut impl rand::Rng) {
    let mut present: Vec<u16> = (0..frame.instance_ids.len())
        .filter(|&i| is_object(frame, i))
        .map(|i| frame.instance_ids[i])
        .collect();
    present.sort_unstable();
    present.dedup();
    let mut pool: Vec<u16> = (1..=99.max(present.len() as u16)).collect();
    let mapping: BTreeMap<u16, u16> = present
        .iter()
        .map(|&id| (id, pool.swap_remove(rng.random_range(0..pool.len()))))
        .collect();
    for i in 0..frame.instance_ids.len() {
        if is_object(frame, i) {
            frame.instance_ids[i] = mapping[&frame.instance_ids[i]];
        }
    }
}

#[cfg(test)]
#[path = "sensor_noise_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "sensor_noise_family_tests.rs"]
mod family_tests;

#[cfg(test)]
#[path = "sensor_noise_segmenter_tests.rs"]
mod segmenter_tests;
