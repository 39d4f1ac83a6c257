//! Step-by-step mapping: build a `Mapper`, push the frames of the small synthetic scene one at a
//! time, and print what each step changed (new objects, classes, keyframes, cloud growth).
//!
//! ```text
//! cargo run --example step_by_step -- --seed 3
//! ```

use std::collections::BTreeMap;

use catmap::dataset::FrameSource;
use catmap::dataset::class_names::replica_class_name;
use catmap::synth::{Preset, SyntheticScene};
use catmap::{MapperConfig, ObjectId};
use catmap_systems::Mapper;
use clap::Parser;

/// Arguments.
#[derive(Parser, Debug)]
struct Args {
    /// Seed of the synthetic scene and of the mapper.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Stop after this many frames.
    #[arg(long)]
    max_frames: Option<usize>,
}

fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt().with_env_filter("warn").init();
    run(&Args::parse())
}

fn run(args: &Args) -> anyhow::Result<()> {
    let scene = SyntheticScene::generate(args.seed, Preset::Small)?;
    let config = MapperConfig {
        seed: args.seed,
        ..MapperConfig::default()
    };
    let mut mapper = Mapper::new(config)?;
    let mut previous: BTreeMap<ObjectId, (usize, usize)> = BTreeMap::new();
    let frames = args.max_frames.unwrap_or(scene.len()).min(scene.len());
    for position in 0..frames {
        let frame = scene.read_frame(position)?;
        let index = frame.index;
        mapper.push(frame)?;
        mapper.step()?;
        let map = mapper.snapshot();
        let mut changes = Vec::new();
        for object in &map.objects {
            let name = replica_class_name(object.class).unwrap_or("?");
            match previous.get(&object.id) {
                None => changes.push(format!("new {name} {} ({} pts)", object.id, object.cloud_points)),
                Some(&(points, keyframes)) => {
                    if object.cloud_points > points {
                        changes.push(format!("{name} {} +{} pts", object.id, object.cloud_points - points));
                    }
                    if object.keyframes.len() > keyframes {
                        changes.push(format!("{name} {} keyframe #{}", object.id, object.keyframes.len()));
                    }
                }
            }
            previous.insert(object.id, (object.cloud_points, object.keyframes.len()));
        }
        say(&format!(
            "frame {index:>3}: {} objects | {}",
            map.objects.len(),
            changes.join(", ")
        ));
    }
    mapper.end_stream()?;
    mapper.step()?;
    let map = mapper.finish();
    say("\nobject  class        frames  points  box (m)");
    for o in &map.objects {
        let extents = o
            .bounds
            .map(|b| b.extents())
            .map_or("-".to_owned(), |e| format!("{:.2} × {:.2} × {:.2}", e.x, e.y, e.z));
        let name = replica_class_name(o.class).unwrap_or("?");
        say(&format!(
            "{:>6}  {name:<11} {:>6}  {:>6}  {extents}",
            o.id, o.visible_frames, o.cloud_points
        ));
    }
    Ok(())
}

#[expect(clippy::print_stdout, reason = "an example prints what it shows")]
fn say(line: &str) {
    println!("{line}");
}
