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
            let given =
                run.instances.is_some() || instances == catmap::objects::instance_association::InstanceSource::PerFrame;
            Some(sensor_choice(
                run.depth,
                run.masks,
                given.then_some(instances),
                raw.as_ref(),
            ))
        }
        None if flagged => Some(crate::cli::sensor_choice::flagged_choice(
            run.depth,
            run.masks,
            run.instances,
        )),
        None => None,
    };
    layers.sensor = sensor;
    Ok(resolved(&layers, run.format)?.to_toml())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: ConfigArgs,
    }

    fn printed(argv: &[&str]) -> anyhow::Result<catmap::MapperConfig> {
        let cli = Cli::try_parse_from(std::iter::once("config").chain(argv.iter().copied()))?;
        Ok(catmap::MapperConfig::from_toml(&config(&cli.args)?)?)
    }

    #[test]
    fn the_resolved_paper_schedule_is_the_paper_profile_and_no_option_is_the_default() {
        use catmap::MapperConfig;
        assert_eq!(printed(&[]).expect("defaults"), MapperConfig::default());
        assert_eq!(printed(&["--resolved"]).expect("resolved"), MapperConfig::fast());
        assert_eq!(
            printed(&["--resolved", "--schedule", "paper"]).expect("resolved"),
            MapperConfig::paper(),
            "METHOD.md §7's `paper` column (catmap::config's profile tests)"
        );
        let offline = printed(&["--resolved", "--offline", "--iterations", "300"]).expect("resolved");
        assert_eq!(
            offline,
            MapperConfig {
                fields: catmap::config::FieldConfig {
                    offline: true,
                    offline_iterations: 300,
                    ..MapperConfig::paper().fields
                },
                ..MapperConfig::paper()
            }
        );
    }

    #[test]
    fn a_sensor_flag_lays_its_settings_under_the_config_file() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("mine.toml");
        std::fs::write(&path, "[dataset]\ndepth_noise_per_m2 = 0.001\n").expect("write");
        let path = path.to_str().expect("a UTF-8 path");
        let camera = printed(&["--resolved", "--depth", "camera"]).expect("resolved");
        assert_eq!(camera.dataset.depth_noise_per_m2, 0.0025, "the camera's allowance");
        let mine = printed(&["--resolved", "--depth", "camera", "--config", path]).expect("resolved");
        assert_eq!(mine.dataset.depth_noise_per_m2, 0.001, "the file's, over the camera's");
        assert_eq!(mine.dataset.depth_smoothing, camera.dataset.depth_smoothing);
    }

    #[test]
    fn run_options_without_resolved_are_refused() {
        let err = printed(&["--schedule", "paper"]).expect_err("needs --resolved");
        assert!(err.to_string().contains("--resolved"), "{err}");
    }
}
