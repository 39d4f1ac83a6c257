//! Association benchmark: per-frame masks of a synthetic scene seen through the Kinect-like
//! sensor, associated into objects (no fields, no training) and checked against the exact render.
//!
//! `cargo run --release --features bench --example bench_association -- [--preset default|living|small] [--seeds 0,1,2,3] [--noise none|kinect|kinect-depth|segmenter-masks|structured-light|time-of-flight|active-stereo] [--masks exact|segmenter] [--depth-noise FAMILY] [--mask-noise exact|kinect|segmenter] [--config 'TOML of objects.association'] [--dataset DIR --truth DIR]`
//! prints, per scene, the objects made against the ground truth's, each object's purity (the
//! share of its pixels that show its main ground-truth object; `catmap::metrics::association_purity`),
//! ground-truth objects no object covers, and the association's milliseconds per frame.
//!
//! With `--boxes [--depth exact|camera]` each object's cloud is also grown as the cloud stage
//! grows it (its views voting on its voxels; a merged object's cloud absorbed) and its box
//! fitted at the end; each object's line then gives its box's edges against its truth's (the
//! same fit on the exact render's cloud) and its cloud's voxels more than 5 cm outside the
//! truth's box, by the share of views that saw them as the object's.

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use catmap::ObjectId;
use catmap::config::MapperConfig;
use catmap::dataset::FrameSource;
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::smoothed_depth::with_depth_smoothing;
use catmap::geometry::oriented_box::OrientedBox;
use catmap::metrics::association_purity::AssociationTally;
use catmap::objects::border_votes::LabelHistory;
use catmap::objects::config::{MaskBorders, ObjectConfig};
use catmap::objects::instance_association::{AssociationConfig, InstanceSource, InstanceTracker};
use catmap::objects::object_bounds::fit_object_box;
use catmap::objects::observed_cloud::ObservedCloud;
use catmap::objects::segment::segment_frame;
use catmap::sensor::depth_smoothing::DepthImages;
use catmap::sensor::frame::InstanceLabel;
use catmap::synth::{InstanceIds, Preset, SensorModel, SensorSettings, SyntheticScene};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let flag = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1));
    let preset = match flag("--preset").map_or("default", String::as_str) {
        "default" => Preset::Default,
        "living" => Preset::Living,
        "small" => Preset::Small,
        other => bail!("--preset {other}: default, living or small"),
    };
    let model = match flag("--noise").map_or("kinect", String::as_str) {
        "kinect" => SensorModel::Kinect,
        "none" => SensorModel::None,
        "structured-light" => SensorModel::StructuredLight,
        "time-of-flight" => SensorModel::TimeOfFlight,
        "active-stereo" => SensorModel::ActiveStereo,
        "segmenter-masks" => SensorModel::SegmenterMasks,
        "kinect-depth" => SensorModel::KinectDepth,
        other => bail!(
            "--noise {other}: kinect, none, kinect-depth, segmenter-masks, structured-light, time-of-flight or active-stereo"
        ),
    };
    let mut sensor = SensorSettings::new(model, InstanceIds::PerFrame);
    if let Some(name) = flag("--depth-noise") {
        sensor.depth =
            kebab(name).context("--depth-noise: exact, kinect, structured-light, time-of-flight or active-stereo")?;
    }
    if let Some(name) = flag("--mask-noise") {
        sensor.masks = kebab(name).context("--mask-noise: exact, kinect or segmenter")?;
    }
    let seeds: Vec<u64> = flag("--seeds")
        .map_or("0,1,2,3", String::as_str)
        .split(',')
        .map(|s| s.trim().parse().context("--seeds is a comma-separated list"))
        .collect::<Result<_>>()?;
    let borders = match flag("--masks").map_or("exact", String::as_str) {
        "exact" => MaskBorders::Exact,
        "segmenter" => MaskBorders::Segmenter,
        other => bail!("--masks {other}: exact or segmenter"),
    };
    let depth = match flag("--depth").map_or("exact", String::as_str) {
        "exact" => DepthImages::Exact,
        "camera" => DepthImages::Camera,
        other => bail!("--depth {other}: exact or camera"),
    };
    let mut config = MapperConfig::default().with_depth_images(depth);
    config.objects = ObjectConfig {
        association: match flag("--config") {
            Some(text) => toml::from_str(text).context("--config is not an association config")?,
            None => AssociationConfig {
                instances: InstanceSource::PerFrame,
                ..Default::default()
            },
        },
        ..config.objects
    }
    .with_mask_borders(borders);
    let setup = Setup {
        cfg: config.objects.clone(),
        boxes: args.iter().any(|a| a == "--boxes"),
        depth_noise_per_m2: config.dataset.depth_noise_per_m2,
    };
    let smoothed = |source: Arc<dyn FrameSource>| {
        with_depth_smoothing(source, config.dataset.depth_smoothing, &config.dataset.bilateral)
    };
    if let Some(dir) = flag("--dataset") {
        let truth = flag("--truth").context("--dataset needs --truth DIR: the same scene with exact masks")?;
        let options = ReplicaOptions::default();
        let noisy = smoothed(Arc::new(ReplicaSequence::open(dir, &options)?));
        let exact = ReplicaSequence::open(truth, &options)?;
        let run = associate(noisy.as_ref(), &exact, &setup)?;
        report(dir, &run, None, &|_| "?".to_owned(), &setup.cfg);
        return Ok(());
    }
    for seed in seeds {
        let exact = SyntheticScene::generate(seed, preset)?;
        let noisy = smoothed(Arc::new(SyntheticScene::generate(seed, preset)?.with_sensor(sensor)));
        let run = associate(noisy.as_ref(), &exact, &setup)?;
        let truths: Vec<(ObjectId, String)> = exact
            .objects()
            .iter()
            .map(|o| (o.id, o.design.name().to_owned()))
            .collect();
        report(
            &format!("{} seed {seed}", preset.name()),
            &run,
            Some(&truths),
            &|id| exact.object(id).map_or("?", |t| t.design.name()).to_owned(),
            &setup.cfg,
        );
    }
    Ok(())
}

/// What the benchmark runs with.
struct Setup {
    cfg: ObjectConfig,
    /// Grow clouds and fit boxes too.
    boxes: bool,
    depth_noise_per_m2: f32,
}

/// One scene's association against its exact twin.
struct Associated {
    tally: AssociationTally,
    seconds_per_frame: f64,
    /// Per associated object, the first frame that shows it.
    first_frame: BTreeMap<ObjectId, usize>,
    /// Objects found to be part of another.
    merges: usize,
    /// With `--boxes`: each object's cloud and each truth's (exact render).
    clouds: BTreeMap<ObjectId, ObservedCloud>,
    truth_clouds: BTreeMap<ObjectId, ObservedCloud>,
}

/// Every frame of `noisy` through the segment stage's own path, tallied against `exact`.
fn associate(noisy: &dyn FrameSource, exact: &dyn FrameSource, setup: &Setup) -> Result<Associated> {
    let cfg = &setup.cfg;
    let mut tracker = InstanceTracker::default();
    let mut history = LabelHistory::default();
    let mut tally = AssociationTally::default();
    let mut seconds = 0.0;
    let mut first_frame: BTreeMap<ObjectId, usize> = BTreeMap::new();
    let mut merges = 0;
    let mut clouds: BTreeMap<ObjectId, ObservedCloud> = BTreeMap::new();
    let mut truth_clouds: BTreeMap<ObjectId, ObservedCloud> = BTreeMap::new();
    for i in 0..noisy.len() {
        let frame = noisy.read_frame(i)?;
        let start = Instant::now();
        let (changed, observation) = segment_frame(&frame, cfg, &mut tracker, &mut history);
        seconds += start.elapsed().as_secs_f64();
        for merge in &observation.merges {
            tally.merge(merge.kept, merge.absorbed);
            let first = first_frame.remove(&merge.absorbed);
            if let (Some(first), Some(kept)) = (first, first_frame.get_mut(&merge.kept)) {
                *kept = (*kept).min(first);
            }
            merges += 1;
            if let Some(absorbed) = clouds.remove(&merge.absorbed) {
                clouds
                    .entry(merge.kept)
                    .or_insert_with(|| ObservedCloud::new(cfg.cloud_voxel_m))
                    .absorb(&absorbed);
            }
        }
        let relabelled = changed.unwrap_or(frame);
        let exact_frame = exact.read_frame(i)?;
        tally.add(&relabelled.instances, &exact_frame.instances);
        if setup.boxes {
            for (&id, seen) in &observation.objects {
                let cloud = clouds
                    .entry(id)
                    .or_insert_with(|| ObservedCloud::new(cfg.cloud_voxel_m));
                cloud.add_view(&relabelled, &seen.pixels, id, cfg.voxel_votes, setup.depth_noise_per_m2);
            }
            let mut by_truth: BTreeMap<ObjectId, Vec<u32>> = BTreeMap::new();
            for p in 0..exact_frame.instances.len() {
                if let InstanceLabel::Object(id) = exact_frame.instances.label(p) {
                    by_truth.entry(id).or_default().push(p as u32);
                }
            }
            for (id, pixels) in by_truth {
                let cloud = truth_clouds
                    .entry(id)
                    .or_insert_with(|| ObservedCloud::new(cfg.cloud_voxel_m));
                cloud.add_pixels(&exact_frame, &pixels);
            }
        }
        for p in 0..relabelled.instances.len() {
            if let Some(id) = relabelled.instances.object_at(p) {
                first_frame.entry(id).or_insert(i);
            }
        }
    }
    Ok(Associated {
        tally,
        seconds_per_frame: seconds / noisy.len().max(1) as f64,
        first_frame,
        merges,
        clouds,
        truth_clouds,
    })
}

/// Prints the scene's line (objects against `truths` when known) and one line per object.
#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn report(
    name: &str,
    run: &Associated,
    truths: Option<&[(ObjectId, String)]>,
    design: &dyn Fn(ObjectId) -> String,
    cfg: &ObjectConfig,
) {
    let objects = run.tally.objects();
    let covered: BTreeSet<_> = objects.iter().map(|o| o.truth).collect();
    let min_purity = objects.iter().map(|o| o.purity).fold(1.0f32, f32::min);
    let against = truths.map_or_else(String::new, |truths| {
        let uncovered: Vec<String> = (truths.iter())
            .filter(|(id, _)| !covered.contains(id))
            .map(|(id, design)| format!("{id} ({design})"))
            .collect();
        format!(
            " for {} ({:+}), uncovered: {}",
            truths.len(),
            objects.len() as i64 - truths.len() as i64,
            if uncovered.is_empty() {
                "none".to_owned()
            } else {
                uncovered.join(", ")
            }
        )
    });
    println!(
        "{name}: {} objects{against}, {} merged, min purity {:.1} %, {:.2} ms per frame",
        objects.len(),
        run.merges,
        100.0 * min_purity,
        1000.0 * run.seconds_per_frame
    );
    for o in &objects {
        let first = run.first_frame.get(&o.id).copied().unwrap_or_default();
        println!(
            "  object {:2} → truth {:2} {:18} purity {:5.1} %  {} px (+{:.1} % on the background), from frame {first}",
            o.id,
            o.truth,
            design(o.truth),
            100.0 * o.purity,
            o.pixels,
            100.0 * o.background_pixels as f64 / o.pixels.max(1) as f64
        );
        if let (Some(cloud), Some(truth)) = (run.clouds.get(&o.id), run.truth_clouds.get(&o.truth)) {
            println!("{}", box_line(cloud, truth, cfg));
        }
    }
}

/// An object's box against its truth's, and its cloud's voxels beyond the truth's box.
fn box_line(cloud: &ObservedCloud, truth: &ObservedCloud, cfg: &ObjectConfig) -> String {
    let (Ok(fitted), Ok(true_box)) = (fit_object_box(cloud, cfg), fit_object_box(truth, cfg)) else {
        return "      no box".to_owned();
    };
    let edges = |b: &OrientedBox| {
        let mut e: Vec<f32> = b.extents().iter().copied().collect();
        e.sort_by(|a, b| b.total_cmp(a));
        format!("{:.2}×{:.2}×{:.2}", e[0], e[1], e[2])
    };
    // Voxels 5 cm or more beyond the truth's box: contested, seen as the object's by fewer than
    // half the views that saw them, by at least half.
    let mut beyond = [0usize; 3];
    for (p, _, votes) in cloud.voxels() {
        if !true_box.contains(&p, 0.05) {
            beyond[usize::from(!votes.contested()) + usize::from(votes.mostly_own())] += 1;
        }
    }
    format!(
        "      box {} (truth {}); voxels beyond the truth's box: {} contested, {} mostly another's, {} mostly its own",
        edges(&fitted),
        edges(&true_box),
        beyond[0],
        beyond[1],
        beyond[2]
    )
}

/// A kebab-case name of a serde enum (`time-of-flight`) as its value.
fn kebab<T: serde::de::DeserializeOwned>(name: &str) -> Result<T> {
    Ok(toml::Value::String(name.to_owned()).try_into()?)
}
