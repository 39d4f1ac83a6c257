//! `catmap run`'s depth and mask settings: the flags where given, else the probe of the dataset's
//! frames (`catmap::config::sensor_profile`), logged.

use catmap::config::sensor_profile::{SensorChoice, SensorProfile};
use catmap::objects::config::MaskBorders;
use catmap::sensor::depth_smoothing::DepthImages;

use catmap::objects::instance_association::InstanceSource;

use crate::cli::run::{DepthArg, InstancesArg, MasksArg};

/// The depth, mask and id settings: `--depth` and `--masks` where given, `instances` where
/// `--instances` was given (or a config file said per-frame), else what a probe of the dataset's
/// frames finds (logged).
pub fn sensor_choice(
    depth: Option<DepthArg>,
    masks: Option<MasksArg>,
    instances: Option<InstanceSource>,
    source: &dyn catmap::dataset::FrameSource,
) -> SensorChoice {
    let (depth, masks) = (depth.map(depth_images), masks.map(mask_borders));
    let profile = (depth.is_none() || masks.is_none() || instances.is_none()).then(|| SensorProfile::probe(source));
    if let Some(profile) = &profile {
        let noise = profile.depth_noise;
        tracing::info!(
            frames = profile.frames,
            sigma_at_2m_mm = noise.map(|n| n.sigma_m(2.0) * 1000.0),
            range_m = noise.map(|n| n.range_m),
            valid_depth = profile.valid_depth_share,
            mask_borders_off = profile.mask_borders.map(|m| m.off_share),
            ids_agreeing = profile.instance_ids.and_then(|m| m.agreeing_share()),
            "sensor probed"
        );
    }
    let choice = SensorChoice::resolve(depth, masks, instances, profile);
    tracing::info!(depth = ?choice.depth, by = ?choice.depth_chosen_by, masks = ?choice.masks, masks_by = ?choice.masks_chosen_by, instances = ?choice.instances, instances_by = ?choice.instances_chosen_by, "sensor settings");
    choice
}

/// The flags' depth, mask and id settings alone, exact and consistent where a flag is missing
/// (`catmap config --resolved` without a dataset to probe).
pub fn flagged_choice(
    depth: Option<DepthArg>,
    masks: Option<MasksArg>,
    instances: Option<InstancesArg>,
) -> SensorChoice {
    SensorChoice::resolve(
        depth.map(depth_images),
        masks.map(mask_borders),
        instances.map(InstanceSource::from),
        None,
    )
}

fn depth_images(depth: DepthArg) -> DepthImages {
    match depth {
        DepthArg::Exact => DepthImages::Exact,
        DepthArg::Camera => DepthImages::Camera,
    }
}

fn mask_borders(masks: MasksArg) -> MaskBorders {
    match masks {
        MasksArg::Exact => MaskBorders::Exact,
        MasksArg::Segmenter => MaskBorders::Segmenter,
    }
}
