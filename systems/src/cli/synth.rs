//! `catmap synth`: write a synthetic scene.

use std::path::{Path, PathBuf};

use anyhow::Context as _;
use catmap::synth::sensor_noise::{DepthNoise, MaskNoise};
use catmap::synth::{
    InstanceIds, Preset, SensorModel, SensorSettings, SyntheticScene, write_replica_layout, write_scannet_layout,
    write_tum_layout,
};

use crate::cli::progress::bar;

/// Arguments of `catmap synth`.
#[derive(clap::Args, Debug)]
pub struct SynthArgs {
    /// Seed of the layout.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Layout of the output folder: Replica's (vMAP's), or TUM RGB-D's with masks beside it
    /// (`catmap run --dataset DIR` reads either).
    #[arg(long, value_enum, default_value_t = LayoutArg::Replica)]
    pub layout: LayoutArg,
    /// Scene size.
    #[arg(long, value_enum, default_value_t = PresetArg::Default)]
    pub preset: PresetArg,
    /// Depth camera and segmenter: exact; catmap's own Kinect-like model (or one of its two
    /// parts); or a camera family from the literature with a 2D instance segmenter's masks.
    #[arg(long, value_enum, default_value_t = NoiseArg::None)]
    pub noise: NoiseArg,
    /// The depth camera alone, in place of `--noise`'s.
    #[arg(long, value_enum)]
    pub depth_noise: Option<DepthNoiseArg>,
    /// The segmenter alone, in place of `--noise`'s.
    #[arg(long, value_enum)]
    pub mask_noise: Option<MaskNoiseArg>,
    /// Instance ids: one per object over the sequence, or every frame its own.
    #[arg(long, value_enum, default_value_t = IdsArg::Consistent)]
    pub ids: IdsArg,
    /// Image width in pixels (height three quarters of it, the preset's field of view); the
    /// preset's own when not given (small 160, default and living 640).
    #[arg(long)]
    pub width: Option<u32>,
}

/// `--layout` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutArg {
    /// Replica in vMAP's layout: rgb/, depth/, semantic_class/, semantic_instance/, traj_w_c.txt.
    Replica,
    /// TUM RGB-D's: rgb.txt, depth.txt, groundtruth.txt with timestamps at 30 Hz, depth in units
    /// of 0.2 mm, masks in instance/ and class/.
    Tum,
    /// ScanNet's (SensReader's and the 2D labels'): color/, depth/, pose/, intrinsic/,
    /// instance-filt/, label-filt/ and a label map (`catmap run --format scannet` reads it).
    Scannet,
}

/// `--noise` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoiseArg {
    /// Exact depth and masks.
    None,
    /// Kinect-like depth and a 2D segmenter's masks.
    Kinect,
    /// Kinect-like depth, exact masks.
    KinectDepth,
    /// A 2D segmenter's masks, exact depth.
    SegmenterMasks,
    /// A structured-light camera (Kinect v1, Structure sensor) and a 2D instance segmenter.
    StructuredLight,
    /// A time-of-flight camera (Kinect v2, Azure Kinect) and a 2D instance segmenter.
    TimeOfFlight,
    /// An active stereo camera (RealSense D4xx) and a 2D instance segmenter.
    ActiveStereo,
}

/// `--depth-noise` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum DepthNoiseArg {
    /// The rendered depth.
    Exact,
    /// catmap's own Kinect-like depth.
    Kinect,
    /// A structured-light camera.
    StructuredLight,
    /// A time-of-flight camera.
    TimeOfFlight,
    /// An active stereo camera.
    ActiveStereo,
}

/// `--mask-noise` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum MaskNoiseArg {
    /// The rendered masks.
    Exact,
    /// catmap's own segmenter model.
    Kinect,
    /// A 2D instance segmenter.
    Segmenter,
}

/// `--ids` values.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum IdsArg {
    /// One id per object over the whole sequence.
    Consistent,
    /// Every frame numbers its masks anew.
    PerFrame,
}

impl SynthArgs {
    /// The sensor the arguments ask for.
    pub fn sensor(&self) -> SensorSettings {
        let model = match self.noise {
            NoiseArg::None => SensorModel::None,
            NoiseArg::Kinect => SensorModel::Kinect,
            NoiseArg::KinectDepth => SensorModel::KinectDepth,
            NoiseArg::SegmenterMasks => SensorModel::SegmenterMasks,
            NoiseArg::StructuredLight => SensorModel::StructuredLight,
            NoiseArg::TimeOfFlight => SensorModel::TimeOfFlight,
            NoiseArg::ActiveStereo => SensorModel::ActiveStereo,
        };
        let ids = match self.ids {
            IdsArg::Consistent => InstanceIds::Consistent,
            IdsArg::PerFrame => InstanceIds::PerFrame,
        };
        let mut sensor = SensorSettings::new(model, ids);
        if let Some(depth) = self.depth_noise {
            sensor.depth = match depth {
                DepthNoiseArg::Exact => DepthNoise::Exact,
                DepthNoiseArg::Kinect => DepthNoise::Kinect,
                DepthNoiseArg::StructuredLight => DepthNoise::StructuredLight,
                DepthNoiseArg::TimeOfFlight => DepthNoise::TimeOfFlight,
                DepthNoiseArg::ActiveStereo => DepthNoise::ActiveStereo,
            };
        }
        if let Some(masks) = self.mask_noise {
            sensor.masks = match masks {
                MaskNoiseArg::Exact => MaskNoise::Exact,
                MaskNoiseArg::Kinect => MaskNoise::Kinect,
                MaskNoiseArg::Segmenter => MaskNoise::Segmenter,
            };
        }
        sensor
    }
}

/// Scene presets on the command line.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum PresetArg {
    /// 160×120, 30 frames, 6 objects (three identical chairs, a table, a stool, a lamp): tests
    /// and the quick look.
    Small,
    /// 640×480, 240 frames, 13–15 objects (three or four of each of two chair designs, seven
    /// unique objects, a sofa against a wall among them).
    Default,
    /// 640×480, 240 frames, 11–12 objects of a living-bedroom (a bed, a sofa and a bookcase
    /// against the walls; pairs of nightstands and chairs).
    Living,
}

impl From<PresetArg> for Preset {
    fn from(p: PresetArg) -> Self {
        match p {
            PresetArg::Small => Preset::Small,
            PresetArg::Default => Preset::Default,
            PresetArg::Living => Preset::Living,
        }
    }
}

/// Runs `catmap synth`.
pub fn synth(args: &SynthArgs) -> anyhow::Result<()> {
    write_scene_as(
        args.layout,
        args.seed,
        args.preset.into(),
        args.sensor(),
        args.width,
        &args.out,
    )?;
    Ok(())
}

/// Generates and writes a scene in the Replica layout with a progress bar; returns it.
pub fn write_scene(seed: u64, preset: Preset, sensor: SensorSettings, out: &Path) -> anyhow::Result<SyntheticScene> {
    write_scene_as(LayoutArg::Replica, seed, preset, sensor, None, out)
}

/// Generates and writes a scene in `layout` (its images `width` pixels wide, else the preset's)
/// with a progress bar; returns it.
pub fn write_scene_as(
    layout: LayoutArg,
    seed: u64,
    preset: Preset,
    sensor: SensorSettings,
    width: Option<u32>,
    out: &Path,
) -> anyhow::Result<SyntheticScene> {
    let mut scene = SyntheticScene::generate(seed, preset)
        .context("cannot generate the synthetic scene")?
        .with_sensor(sensor);
    if let Some(width) = width {
        scene = scene.with_image_width(width);
    }
    let progress = bar(0, "synth");
    let report = |done: usize, total: usize| {
        progress.set_length(total as u64);
        progress.set_position(done as u64);
    };
    match layout {
        LayoutArg::Replica => write_replica_layout(&scene, out, report),
        LayoutArg::Tum => write_tum_layout(&scene, out, report),
        LayoutArg::Scannet => write_scannet_layout(&scene, out, report),
    }
    .with_context(|| format!("cannot write the synthetic scene to {}", out.display()))?;
    progress.finish_and_clear();
    tracing::info!(dir = %out.display(), seed, ?layout, "synthetic scene written");
    Ok(scene)
}
