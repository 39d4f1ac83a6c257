//! `catmap config`: the default settings as TOML (what a config file changes), or with
//! `--resolved` the settings `catmap run` with the same options maps with.

use clap::Parser as _;

use crate::cli::run::{RunArgs, layers_from_args, resolved};
use crate::cli::run_plan::{MapMode, Recording, RunPlan};
use crate::cli::sensor_choice::sensor_choice;

/// Arguments of `catmap config`.
#[derive(clap::Args, Debug)]
pub struct ConfigArgs {
    /// Print the settings `catmap run` with these options maps with, every key set: the
    /// profile (`--schedule`, `--offline`), the sensor's settings (`--depth`, `--masks`,
    /// `--instances`, or a probe of `--dataset`), the config file, then the flags.
    #[arg(long)]
    pub resolved: bool,
    /// The options of `catmap run` (with `--resolved`).
    #[command(flatten)]
    pub run: RunArgs,
}

/// `catmap run`'s options alone, to tell whether any was given.
#[derive(clap::Parser)]
struct Bare {
    #[command(flatten)]
    run: RunArgs,
}

/// The TOML `catmap config` prints.
pub fn config(args: &ConfigArgs) -> anyhow::Result<String> {
    if !args.resolved {
        let none = Bare::try_parse_from(["catmap"]).map_err(anyhow::Error::from)?.run;
        anyhow::ensure!(
            format!("{:?}", args.run) == format!("{none:?}"),
            "the options of `catmap run` need --resolved (`catmap config` alone prints the defaults)"
        );
        return Ok(catmap::MapperConfig::default().to_toml());
    }
    let run = &args.run;
    let mut layers = layers_from_args(run)?;
    let config = resolved(&layers, run.format)?;
    let flagged = run.depth.is_some() || run.masks.is_some() || run.instances.is_some();
    let sensor = match &run.dataset {
        Some(dataset) => {
            let plan = RunPlan {
                dataset: dataset.clone(),
                format: run.format,
                camera: run.camera.clone(),
                out: run.out.clone(),
                mode: MapMode::Category,
                recording: Recording::Off,
                seconds_before: 0.0,
                sensor: None,
            };
            let raw = plan.open_raw_source(&config)?;
            let instances = config.objects.association.instances;
            let given = run.instances.is_some()
                || instances == catmap::objects::instance_association::InstanceSource::PerFrame;
            Some(sensor_choice(run.depth, run.masks, given.then_some(instances), raw.as_ref()))
        }
        None if flagged => Some(crate::cli::sensor_choice::flagged_choice(run.depth, run.masks, run.instances)),
        None => None,
    };
    layers.sensor = sensor;
    Ok(resolved(&layers, run.format)?.to_toml())
}
