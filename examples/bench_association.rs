//! Association benchmark: per-frame masks of a synthetic scene seen through the Kinect-like
//! sensor, associated into objects (no fields, no training) and checked against the exact render.
//!
//! `cargo run --release --features bench --example bench_association -- [--preset default|living|small] [--seeds 0,1,2,3] [--noise none|kinect|kinect-depth|segmenter-masks|structured-light|time-of-flight|active-stereo] [--masks exact|segmenter] [--depth-noise FAMILY] [--mask-noise exact|kinect|segmenter] [--config 'TOML of objects.association'] [--dataset DIR --truth DIR]`
//! prints, per scene, the objects made against the ground truth's, each object's purity (the
//! share of its pixels that show its main ground-truth object; `catmap::metrics::association_purity`),
//! ground-truth objects no object covers, and the association's milliseconds per frame.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use catmap::ObjectId;
use catmap::dataset::FrameSource;
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::metrics::association_purity::AssociationTally;
use catmap::objects::border_votes::LabelHistory;
use catmap::objects::config::{MaskBorders, ObjectConfig};
use catmap::objects::instance_association::{AssociationConfig, InstanceSource, InstanceTracker};
use catmap::objects::segment::segment_frame;
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
    let cfg = ObjectConfig {
        association: match flag("--config") {
            Some(text) => toml::from_str(text).context("--config is not an association config")?,
            None => AssociationConfig {
                instances: InstanceSource::PerFrame,
                ..Default::default()
            },
        },
        ..ObjectConfig::default()
    }
    .with_mask_borders(borders);
    if let Some(dir) = flag("--dataset") {
        let truth = flag("--truth").context("--dataset needs --truth DIR: the same scene with exact masks")?;
        let options = ReplicaOptions::default();
        let noisy = ReplicaSequence::open(dir, &options)?;
        let exact = ReplicaSequence::open(truth, &options)?;
        let run = associate(&noisy, &exact, &cfg)?;
        report(dir, &run, None, &|_| "?".to_owned());
        return Ok(());
    }
    for seed in seeds {
        let exact = SyntheticScene::generate(seed, preset)?;
        let noisy = SyntheticScene::generate(seed, preset)?.with_sensor(sensor);
        let run = associate(&noisy, &exact, &cfg)?;
        let truths: Vec<(ObjectId, String)> = exact
            .objects()
            .iter()
            .map(|o| (o.id, o.design.name().to_owned()))
            .collect();
        report(&format!("{} seed {seed}", preset.name()), &run, Some(&truths), &|id| {
            exact.object(id).map_or("?", |t| t.design.name()).to_owned()
        });
    }
    Ok(())
}

/// One scene's association against its exact twin.
struct Associated {
    tally: AssociationTally,
    seconds_per_frame: f64,
    /// Per associated object, the first frame that shows it.
    first_frame: BTreeMap<ObjectId, usize>,
    /// Objects found to be part of another.
    merges: usize,
}

/// Every frame of `noisy` through the segment stage's own path, tallied against `exact`.
fn associate(noisy: &dyn FrameSource, exact: &dyn FrameSource, cfg: &ObjectConfig) -> Result<Associated> {
    let mut tracker = InstanceTracker::default();
    let mut history = LabelHistory::default();
    let mut tally = AssociationTally::default();
    let mut seconds = 0.0;
    let mut first_frame: BTreeMap<ObjectId, usize> = BTreeMap::new();
    let mut merges = 0;
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
        }
        let relabelled = changed.unwrap_or(frame);
        tally.add(&relabelled.instances, &exact.read_frame(i)?.instances);
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
    })
}

/// Prints the scene's line (objects against `truths` when known) and one line per object.
#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn report(name: &str, run: &Associated, truths: Option<&[(ObjectId, String)]>, design: &dyn Fn(ObjectId) -> String) {
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
    }
}

/// A kebab-case name of a serde enum (`time-of-flight`) as its value.
fn kebab<T: serde::de::DeserializeOwned>(name: &str) -> Result<T> {
    Ok(toml::Value::String(name.to_owned()).try_into()?)
}
