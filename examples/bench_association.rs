//! Association benchmark: per-frame masks of a synthetic scene seen through the Kinect-like
//! sensor, associated into objects (no fields, no training) and checked against the exact render.
//!
//! `cargo run --release --features bench --example bench_association -- [--preset default|living|small] [--seeds 0,1,2,3] [--noise none|kinect|structured-light|time-of-flight|active-stereo] [--config 'TOML of objects.association']`
//! prints, per scene, the objects made against the ground truth's, each object's purity (the
//! share of its pixels that show its main ground-truth object; `catmap::metrics::association_purity`),
//! ground-truth objects no object covers, and the association's milliseconds per frame.

use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use catmap::dataset::FrameSource;
use catmap::metrics::association_purity::AssociationTally;
use catmap::objects::config::ObjectConfig;
use catmap::objects::frame_observation::observe_objects;
use catmap::objects::instance_association::InstanceTracker;
use catmap::objects::segment::associate_frame;
use catmap::synth::{InstanceIds, Preset, SensorModel, SensorSettings, SyntheticScene};

#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
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
        other => bail!("--noise {other}: kinect, none, structured-light, time-of-flight or active-stereo"),
    };
    let seeds: Vec<u64> = flag("--seeds")
        .map_or("0,1,2,3", String::as_str)
        .split(',')
        .map(|s| s.trim().parse().context("--seeds is a comma-separated list"))
        .collect::<Result<_>>()?;
    let cfg = ObjectConfig {
        association: match flag("--config") {
            Some(text) => toml::from_str(text).context("--config is not an association config")?,
            None => Default::default(),
        },
        ..ObjectConfig::default()
    };
    for seed in seeds {
        let exact = SyntheticScene::generate(seed, preset)?;
        let truth_count = exact.objects().len();
        let noisy =
            SyntheticScene::generate(seed, preset)?.with_sensor(SensorSettings::new(model, InstanceIds::PerFrame));
        let mut tracker = InstanceTracker::default();
        let mut tally = AssociationTally::default();
        let mut seconds = 0.0;
        let mut first_frame: BTreeMap<u32, (usize, usize)> = BTreeMap::new();
        for i in 0..noisy.len() {
            let frame = noisy.read_frame(i)?;
            let start = Instant::now();
            let (relabelled, _) = associate_frame(&mut tracker, &frame, &observe_objects(&frame, &cfg), &cfg);
            seconds += start.elapsed().as_secs_f64();
            tally.add(&relabelled.instances, &exact.read_frame(i)?.instances);
            for p in 0..relabelled.instances.len() {
                if let Some(id) = relabelled.instances.object_at(p) {
                    first_frame.entry(id.0).or_insert((i, 0)).1 += 1;
                }
            }
        }
        let objects = tally.objects();
        let covered: BTreeSet<_> = objects.iter().map(|o| o.truth).collect();
        let uncovered: Vec<String> = exact
            .objects()
            .iter()
            .filter(|o| !covered.contains(&o.id))
            .map(|o| format!("{} ({})", o.id, o.design.name()))
            .collect();
        let min_purity = objects.iter().map(|o| o.purity).fold(1.0f32, f32::min);
        println!(
            "{} seed {seed}: {} objects for {truth_count} ({:+}), min purity {:.1} %, uncovered: {}, {:.2} ms per frame",
            preset.name(),
            objects.len(),
            objects.len() as i64 - truth_count as i64,
            100.0 * min_purity,
            if uncovered.is_empty() {
                "none".to_owned()
            } else {
                uncovered.join(", ")
            },
            1000.0 * seconds / noisy.len() as f64
        );
        for o in &objects {
            let design = exact.object(o.truth).map_or("?", |t| t.design.name());
            let (first, _) = first_frame.get(&o.id.0).copied().unwrap_or_default();
            println!(
                "  object {:2} → truth {:2} {design:18} purity {:5.1} %  {} px, from frame {first}",
                o.id,
                o.truth,
                100.0 * o.purity,
                o.pixels
            );
        }
    }
    Ok(())
}
