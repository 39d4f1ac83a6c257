//! What a dataset's camera and masks are like, read off a few of its frames before the run: the
//! depth's noise σ(d) and range ([`crate::sensor::depth_noise`]) and how far the masks' borders
//! sit from their silhouettes ([`crate::sensor::mask_borders`]), and whether the instance ids
//! name one object over the sequence ([`crate::sensor::instance_ids`]). From them the run takes a
//! depth camera's settings ([`DepthImages::Camera`]), a segmenter's ([`MaskBorders::Segmenter`])
//! and the association of per-frame masks ([`InstanceSource::PerFrame`]) when no flag says which,
//! so a real sensor needs none.

use serde::{Deserialize, Serialize};

use crate::config::MapperConfig;
use crate::dataset::FrameSource;
use crate::objects::config::MaskBorders;
use crate::objects::instance_association::InstanceSource;
use crate::sensor::depth_noise::{DepthNoiseBin, DepthNoiseEstimator, DepthNoiseModel};
use crate::sensor::depth_smoothing::DepthImages;
use crate::sensor::frame::RgbdFrame;
use crate::sensor::instance_ids::InstanceIdModel;
use crate::sensor::mask_borders::{MaskBorderEstimator, MaskBorderModel};

/// Frames read to probe a dataset: spread evenly over it.
pub const PROBE_FRAMES: usize = 12;

/// Every this many probed frames, the frame after it is read too, to compare the ids of a pair.
pub const PAIR_EVERY: usize = 3;

/// Depth whose σ at 2 m is larger than this is a camera's, metres: a tenth of the objects' cloud
/// voxel (1 cm), below which the noise changes no voxel a point lands in. Exact depth stored in
/// millimetres has σ ≈ 0.3 mm.
pub const CAMERA_SIGMA_AT_2M_M: f32 = 0.001;

/// Masks whose border lies a pixel or more from its silhouette in more than this share of the
/// border samples are a segmenter's, or lie on depth whose silhouettes moved (flying pixels,
/// fattened edges): either way their borders are not to be trusted. Measured on 12 frames of
/// the default and living scenes: exact masks 3 % (with catmap's Kinect-like depth 13 %, a
/// structured-light camera's 8 %), a segmenter's 54–90 %, exact masks on a time-of-flight
/// camera's depth 52 %, on an active stereo camera's 98 %.
pub const SEGMENTER_OFF_SHARE: f32 = 0.3;

/// What the probe found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorProfile {
    /// Frames read.
    pub frames: usize,
    /// The depth's noise and range (`None`: no patch of any frame was a plane).
    pub depth_noise: Option<DepthNoiseModel>,
    /// σ per 0.25 m depth bin, as measured.
    pub depth_noise_bins: Vec<DepthNoiseBin>,
    /// Share of the pixels with a depth.
    pub valid_depth_share: f32,
    /// The masks' borders (`None`: no border met a silhouette).
    pub mask_borders: Option<MaskBorderModel>,
    /// The instance ids across pairs of consecutive frames (`None`: no pair was read).
    #[serde(default)]
    pub instance_ids: Option<InstanceIdModel>,
}

impl SensorProfile {
    /// The profile of `frames`.
    pub fn of_frames<F: std::borrow::Borrow<RgbdFrame>>(frames: impl IntoIterator<Item = F>) -> Self {
        let mut depth = DepthNoiseEstimator::default();
        let mut borders = MaskBorderEstimator::default();
        let mut count = 0;
        for frame in frames {
            let frame = frame.borrow();
            depth.add_frame(&frame.depth_m, &frame.intrinsics);
            borders.add_frame(&frame.instances, &frame.depth_m, frame.intrinsics.width as usize);
            count += 1;
        }
        Self {
            frames: count,
            depth_noise: depth.estimate(),
            depth_noise_bins: depth.bins(),
            valid_depth_share: depth.valid_share(),
            mask_borders: borders.estimate(),
            instance_ids: None,
        }
    }

    /// The profile of [`PROBE_FRAMES`] frames of `source` spread over it, with the frame after
    /// every [`PAIR_EVERY`]th for the ids; a frame that cannot be read is left out (the run
    /// reports it when it reaches it).
    pub fn probe(source: &dyn FrameSource) -> Self {
        let positions = probe_positions(source.len(), PROBE_FRAMES);
        let mut ids = InstanceIdModel::default();
        let frames = positions.iter().enumerate().filter_map(|(k, &position)| {
            let frame = source.read_frame(position).ok()?;
            if k % PAIR_EVERY == 1
                && position + 1 < source.len()
                && let Ok(next) = source.read_frame(position + 1)
            {
                ids.add_pair(&frame, &next);
            }
            Some(frame)
        });
        let profile = Self::of_frames(frames);
        Self {
            instance_ids: (ids.pairs > 0).then_some(ids),
            ..profile
        }
    }

    /// A depth camera's images when σ(2 m) is above [`CAMERA_SIGMA_AT_2M_M`], else exact ones.
    pub fn depth_images(&self) -> DepthImages {
        match self.depth_noise {
            Some(model) if model.sigma_m(2.0) > CAMERA_SIGMA_AT_2M_M => DepthImages::Camera,
            _ => DepthImages::Exact,
        }
    }

    /// A segmenter's masks when more than [`SEGMENTER_OFF_SHARE`] of the borders are off their
    /// silhouette, else exact ones.
    pub fn mask_borders(&self) -> MaskBorders {
        match self.mask_borders {
            Some(m) if m.off_share > SEGMENTER_OFF_SHARE => MaskBorders::Segmenter,
            _ => MaskBorders::Exact,
        }
    }

    /// Per-frame association when the ids do not name one object across a pair of frames, or
    /// when the masks are a segmenter's (whose split halves and spurious masks carry ids of their
    /// own, so its ids are trusted no further than its borders); else the ids as given.
    pub fn instances(&self) -> InstanceSource {
        let ids_consistent = self.instance_ids.is_none_or(|m| m.consistent());
        match (ids_consistent, self.mask_borders()) {
            (true, MaskBorders::Exact) => InstanceSource::Consistent,
            _ => InstanceSource::PerFrame,
        }
    }
}

/// Who chose a setting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChosenBy {
    /// The command line (`--depth`, `--masks`).
    Flag,
    /// The probe of the dataset's frames.
    Probe,
}

/// The depth and mask settings a run took, who chose them, and what the probe found (`None`
/// when both came from flags and no frame was probed).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorChoice {
    /// The depth images' settings.
    pub depth: DepthImages,
    /// Who chose them.
    pub depth_chosen_by: ChosenBy,
    /// The masks' settings.
    pub masks: MaskBorders,
    /// Who chose them.
    pub masks_chosen_by: ChosenBy,
    /// Where object ids come from.
    pub instances: InstanceSource,
    /// Who chose it (a flag: `--instances`, or the config file's).
    pub instances_chosen_by: ChosenBy,
    /// What the probe found.
    pub profile: Option<SensorProfile>,
}

impl SensorChoice {
    /// The flags' settings where given, the profile's elsewhere; `profile` is needed only when a
    /// flag is missing (`None` then reads as exact depth and masks).
    pub fn resolve(
        depth: Option<DepthImages>,
        masks: Option<MaskBorders>,
        instances: Option<InstanceSource>,
        profile: Option<SensorProfile>,
    ) -> Self {
        let by = |flag: bool| if flag { ChosenBy::Flag } else { ChosenBy::Probe };
        Self {
            depth: depth.unwrap_or_else(|| profile.as_ref().map_or(DepthImages::Exact, SensorProfile::depth_images)),
            depth_chosen_by: by(depth.is_some()),
            masks: masks.unwrap_or_else(|| profile.as_ref().map_or(MaskBorders::Exact, SensorProfile::mask_borders)),
            masks_chosen_by: by(masks.is_some()),
            instances: instances.unwrap_or_else(|| {
                profile
                    .as_ref()
                    .map_or(InstanceSource::Consistent, SensorProfile::instances)
            }),
            instances_chosen_by: by(instances.is_some()),
            profile,
        }
    }

    /// `config` (a profile's settings) with these: the depth's, the masks' and the ids'. A config
    /// file laid over them afterwards ([`super::layers`]) keeps what it sets.
    /// The masks' settings come first: a depth camera's keeps at least 3 points per box voxel
    /// whatever the masks.
    pub fn apply(&self, mut config: MapperConfig) -> MapperConfig {
        config.objects = config.objects.clone().with_mask_borders(self.masks);
        config.objects.association.instances = self.instances;
        config.with_depth_images(self.depth)
    }
}

impl SensorChoice {
    /// The choice and the profile as a short Markdown page (the recording's `sensor` entity).
    pub fn markdown(&self) -> String {
        use std::fmt::Write as _;
        let by = |c: ChosenBy| match c {
            ChosenBy::Flag => "flag",
            ChosenBy::Probe => "probe",
        };
        let mut out = format!(
            "# Sensor\n\ndepth: **{:?}** ({}), masks: **{:?}** ({}), ids: **{:?}** ({})\n",
            self.depth,
            by(self.depth_chosen_by),
            self.masks,
            by(self.masks_chosen_by),
            self.instances,
            by(self.instances_chosen_by)
        );
        let Some(p) = &self.profile else {
            return out;
        };
        let _ = write!(
            out,
            "\nProbe of {} frames: {:.0} % of the pixels have a depth",
            p.frames,
            100.0 * p.valid_depth_share
        );
        if let Some(m) = p.depth_noise {
            let _ = write!(
                out,
                "; σ(d) = {:.2} mm + {:.2} mm · d² (σ at 2 m {:.1} mm), range {:.2} m",
                1000.0 * m.sigma_floor_m,
                1000.0 * m.sigma_per_m2,
                1000.0 * m.sigma_m(2.0),
                m.range_m
            );
        }
        if let Some(b) = p.mask_borders {
            let _ = write!(
                out,
                "; mask borders off their silhouette: {:.0} % of {} samples (90 % within {} px)",
                100.0 * b.off_share,
                b.samples,
                b.p90_px
            );
        }
        if let Some(ids) = p.instance_ids {
            let _ = write!(
                out,
                "; ids in the same place in the next frame: {} of {} in {} pairs",
                ids.agreeing, ids.ids, ids.pairs
            );
        }
        out.push_str(".\n\n| depth, m | σ, mm | patches |\n|---:|---:|---:|\n");
        for bin in &p.depth_noise_bins {
            let _ = writeln!(
                out,
                "| {:.2} | {:.2} | {} |",
                bin.depth_m,
                1000.0 * bin.sigma_m,
                bin.patches
            );
        }
        out
    }
}

/// The positions of `count` frames spread evenly over a stream of `len` (all of them when it is
/// shorter), first and last included.
pub fn probe_positions(len: usize, count: usize) -> Vec<usize> {
    if len <= count {
        return (0..len).collect();
    }
    if count <= 1 {
        return vec![0; count.min(len)];
    }
    (0..count).map(|k| k * (len - 1) / (count - 1)).collect()
}

#[cfg(test)]
#[path = "sensor_profile_tests.rs"]
mod tests;
