//! Representative check: does the uncertainty ranking (METHOD.md §3) pick a well-observed member?
//!
//! Maps synthetic scenes (every `--stride`-th frame, `--iterations` offline per-object steps, then
//! the class registration), and prints for every class with several members, and for each of its
//! subcategories, every member's observed surface fraction (ground truth: the share of the
//! object's surface that some frame sees), its reliable uncertainty rays and whether the
//! representative's fraction is above the group's median; then the seconds the whole scene's
//! uncertainty spheres and its registration + subcategorisation took.
//!
//! ```text
//! cargo run --release --features bench --example bench_representative -- --seeds 0,1,2,3
//! ```

use std::collections::BTreeMap;
use std::ops::ControlFlow;

use catmap::categories::uncertainty::{RepresentativeChoice, choose_representative};
use catmap::config::FieldConfig;
use catmap::dataset::FrameSource;
use catmap::dataset::class_names::replica_class_name;
use catmap::synth::{Preset, SyntheticScene};
use catmap::{MapperConfig, ObjectId};
use catmap_systems::Mapper;
use clap::Parser;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Arguments.
#[derive(Parser, Debug)]
struct Args {
    /// Scene seeds (comma-separated); the mapper uses seed 0 for all.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    seeds: Vec<u64>,
    /// Use every K-th frame.
    #[arg(long, default_value_t = 2)]
    stride: usize,
    /// Offline per-object training steps before the registration.
    #[arg(long, default_value_t = 1500)]
    iterations: usize,
}

#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn main() -> anyhow::Result<()> {
    tracing_subscriber::fmt().with_env_filter("warn").init();
    let args = Args::parse();
    let (mut above, mut groups) = (0, 0);
    for &seed in &args.seeds {
        let (a, g) = check_scene(seed, &args)?;
        above += a;
        groups += g;
    }
    println!("representatives above their group's median observed fraction: {above} of {groups}");
    Ok(())
}

/// Prints one scene's groups; returns (representatives above the median, groups).
#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn check_scene(seed: u64, args: &Args) -> anyhow::Result<(usize, usize)> {
    let scene = SyntheticScene::generate(seed, Preset::Default)?;
    let mut config = MapperConfig {
        seed: 0,
        fields: FieldConfig {
            offline: true,
            offline_iterations: args.iterations,
            ..FieldConfig::default()
        },
        ..MapperConfig::default()
    };
    config.categories.enabled = true;
    config.category_fields.enabled = false; // the representatives only
    let mut mapper = Mapper::new(config)?;
    for position in (0..scene.len()).step_by(args.stride.max(1)) {
        mapper.push(scene.read_frame(position)?)?;
        mapper.step()?;
    }
    mapper.end_stream()?;
    mapper.step()?;
    mapper.run(|_| ControlFlow::Continue(()))?;
    let observed = scene.observed_surface_fraction();
    let (mut above, mut groups) = (0, 0);
    for class in mapper.category_records() {
        let members: Vec<_> = class.subcategories.iter().flat_map(|s| &s.members).collect();
        if members.len() < 2 {
            continue;
        }
        let name = class.name.as_deref().or(replica_class_name(class.class)).unwrap_or("?");
        let rays: BTreeMap<ObjectId, usize> = members.iter().map(|m| (m.id, m.reliable_rays.unwrap_or(0))).collect();
        // The class's representative by the uncertainty ranking (it draws nothing from the RNG).
        let ranked: Vec<(ObjectId, usize)> = rays.iter().map(|(id, n)| (*id, *n)).collect();
        let class_rep = choose_representative(
            &ranked,
            RepresentativeChoice::Uncertainty,
            &mut ChaCha8Rng::seed_from_u64(0),
        );
        let mut report = |label: String, ids: Vec<ObjectId>, rep: Option<ObjectId>| {
            if ids.len() < 2 {
                return;
            }
            let mut fractions: Vec<f32> = ids.iter().map(|id| observed.get(id).copied().unwrap_or(0.0)).collect();
            fractions.sort_by(f32::total_cmp);
            let n = fractions.len();
            let median = if n.is_multiple_of(2) {
                0.5 * (fractions[n / 2 - 1] + fractions[n / 2])
            } else {
                fractions[n / 2]
            };
            let rep_fraction = rep.and_then(|r| observed.get(&r).copied()).unwrap_or(0.0);
            let ok = rep_fraction > median;
            groups += 1;
            above += usize::from(ok);
            let rows: Vec<String> = ids
                .iter()
                .map(|id| {
                    let mark = if Some(*id) == rep { "*" } else { "" };
                    let fraction = observed.get(id).copied().unwrap_or(0.0);
                    format!("{mark}{id} {fraction:.3}/{}", rays.get(id).copied().unwrap_or(0))
                })
                .collect();
            println!(
                "seed {seed} {label:24} median {median:.3}  rep {rep_fraction:.3} {}  [{}]",
                if ok { "above" } else { "NOT above" },
                rows.join(", ")
            );
        };
        report(format!("{name} (class)"), rays.keys().copied().collect(), class_rep);
        if class.subcategories.len() > 1 {
            for (k, sub) in class.subcategories.iter().enumerate() {
                let ids = sub.members.iter().map(|m| m.id).collect();
                report(format!("{name} subcategory {k}"), ids, Some(sub.representative));
            }
        }
    }
    let seconds = mapper.stage_seconds();
    let stage = |name: &str| seconds.get(name).copied().unwrap_or(0.0);
    println!(
        "seed {seed} whole scene: uncertainty {:.2} s, registration and subcategories {:.2} s",
        stage("uncertainty"),
        stage("register")
    );
    Ok((above, groups))
}
