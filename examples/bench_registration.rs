//! Registration benchmark: seeded trials on the synthetic designs (partial view, noise,
//! outliers, random pose) and the time per pair.
//!
//! `cargo run --release --features bench --example bench_registration -- [--trials N] [--config 'TOML']`
//! prints one line per trial, the success rate (rotation < 5° and translation < 3 cm, or
//! aligned-cloud distance < 1 cm for symmetric equivalents) and seconds per pair.

use std::time::Instant;

use anyhow::{Context, Result};
use catmap::geometry::nearest::PointIndex;
use catmap::registration::chamfer::trimmed_normalised_chamfer;
use catmap::registration::{RegistrationConfig, register_to_representative, voxel_centroids};
use catmap::synth::{Design, RegistrationTrial, RegistrationTrialSpec};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

#[expect(clippy::print_stdout, reason = "a benchmark prints its figures")]
fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let flag = |name: &str| args.iter().position(|a| a == name).and_then(|i| args.get(i + 1));
    let trials: u64 = flag("--trials").map(|s| s.parse()).transpose()?.unwrap_or(50);
    let cfg: RegistrationConfig = match flag("--config") {
        Some(text) => toml::from_str(text).context("--config is not a registration config")?,
        None => RegistrationConfig::default(),
    };
    let spec = RegistrationTrialSpec::default();
    let (mut ok, mut seconds) = (0, 0.0);
    let mut icp = catmap::registration::icp::IcpCounts::default();
    for seed in 0..trials {
        let design = Design::ALL[seed as usize % Design::ALL.len()];
        let trial = RegistrationTrial::draw(design, &spec, seed)?;
        let start = Instant::now();
        let fit = register_to_representative(
            &trial.source,
            &trial.template,
            &cfg,
            &mut ChaCha8Rng::seed_from_u64(seed),
        )?;
        let dt = start.elapsed().as_secs_f64();
        seconds += dt;
        let estimate = fit.template_from_source();
        let (rot, trans) = trial.pose_error(&estimate);
        let cloud = trial.aligned_cloud_distance(&estimate)?;
        let truth_score = {
            let fine = voxel_centroids(&trial.source, cfg.icp_voxel_m)?;
            let index = PointIndex::new(&voxel_centroids(&trial.template, cfg.icp_voxel_m)?)?;
            let moved: Vec<_> = fine.iter().map(|p| trial.truth * p).collect();
            trimmed_normalised_chamfer(&moved, &index, cfg.keep_fraction)
        };
        let best_fine = fit.trace.refined[0].1;
        icp = icp + fit.trace.icp;
        let pass = (rot < 5.0 && trans < 0.03) || cloud < 0.01;
        ok += usize::from(pass);
        println!(
            "trial {seed:3} {:18} visible {:.2}  rot {rot:7.2}°  trans {:6.1} cm  cloud {:5.2} cm  score {:.3} fine {best_fine:.3} truth {truth_score:.3} start {:3}  {dt:.3} s  {}",
            design.name(),
            trial.visible_fraction,
            trans * 100.0,
            cloud * 100.0,
            fit.score,
            fit.start_index,
            if pass { "ok" } else { "FAIL" }
        );
    }
    println!(
        "registration trials: {ok}/{trials} within 5° / 3 cm (or aligned-cloud distance < 1 cm); {:.3} s per pair",
        seconds / trials as f64
    );
    println!(
        "ICP: {} runs, {:.1} iterations per run, {} ({:.1} %) reached their iteration cap",
        icp.runs,
        icp.iterations as f64 / icp.runs.max(1) as f64,
        icp.capped,
        100.0 * icp.capped as f64 / icp.runs.max(1) as f64
    );
    Ok(())
}
