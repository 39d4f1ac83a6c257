//! The settings a run maps with, resolved once from its layers, each laid over the one before:
//! the profile (`paper` or `fast`, [`super::profile`]), the sensor's settings (a flag's or the
//! probe's, [`SensorChoice`]), the config file, the command line's flags. What the resolution
//! gives is the whole tree, every key set: the mapper holds it, `summary.json` stores it and
//! `catmap config --resolved` prints it.

use serde::Deserialize as _;

use crate::error::{CatmapError, Result};
use crate::training::SchedulePolicy;

use super::MapperConfig;
use super::sensor_profile::SensorChoice;

/// A run's layers of settings, above its profile.
#[derive(Debug, Clone, Default)]
pub struct SettingsLayers {
    /// The sensor's settings, once chosen (`None`: exact depth and masks, consistent ids).
    pub sensor: Option<SensorChoice>,
    /// What the config file sets (a TOML table of overrides; empty without a file).
    pub file: toml::Table,
    /// What the command line's flags set, as a table of the same keys.
    pub flags: toml::Table,
}

impl SettingsLayers {
    /// The profile these layers start from: the flags' `schedule.policy`, else the file's;
    /// `paper` where either asks for the offline protocol (`fields.offline`, always the
    /// paper's); else `fast`.
    pub fn profile(&self) -> Result<SchedulePolicy> {
        let layers = [&self.flags, &self.file];
        let offline = layers
            .iter()
            .any(|t| lookup(t, "fields.offline").and_then(toml::Value::as_bool) == Some(true));
        let named = layers.iter().find_map(|t| lookup(t, "schedule.policy"));
        match named {
            Some(value) => {
                let policy = SchedulePolicy::deserialize(value.clone())
                    .map_err(|e| CatmapError::ConfigValue(format!("schedule.policy: {e}")))?;
                Ok(if offline { SchedulePolicy::Paper } else { policy })
            }
            None if offline => Ok(SchedulePolicy::Paper),
            None => Ok(SchedulePolicy::Fast),
        }
    }

    /// The settings: the profile, the sensor's settings over it, the file's over those, the
    /// flags' over all; validated.
    pub fn resolve(&self) -> Result<MapperConfig> {
        let mut config = MapperConfig::profile(self.profile()?);
        if let Some(sensor) = &self.sensor {
            config = sensor.apply(config);
        }
        let mut tree = config.to_table();
        merge(&mut tree, &self.file);
        merge(&mut tree, &self.flags);
        let config: MapperConfig = tree
            .try_into()
            .map_err(|e: toml::de::Error| CatmapError::ConfigSyntax(e.message().trim().to_owned()))?;
        config.validate()?;
        Ok(config)
    }
}

/// Sets `key` (dotted) of `table` to `value`, making the tables on its way.
pub fn set(table: &mut toml::Table, key: &str, value: impl Into<toml::Value>) {
    let mut parts: Vec<&str> = key.split('.').collect();
    let leaf = parts.pop().unwrap_or(key);
    let mut at = table;
    for part in parts {
        let entry = at
            .entry(part.to_owned())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()));
        if !entry.is_table() {
            *entry = toml::Value::Table(toml::Table::new());
        }
        at = entry.as_table_mut().expect("made a table above");
    }
    at.insert(leaf.to_owned(), value.into());
}

/// The value at `key` (dotted) of `table`.
pub fn lookup<'t>(table: &'t toml::Table, key: &str) -> Option<&'t toml::Value> {
    let mut parts = key.split('.').peekable();
    let mut at = table;
    while let Some(part) = parts.next() {
        let value = at.get(part)?;
        if parts.peek().is_none() {
            return Some(value);
        }
        at = value.as_table()?;
    }
    None
}

/// Every leaf of `table` (values that are not tables) as (dotted key, value), in key order.
pub fn leaves(table: &toml::Table) -> Vec<(String, toml::Value)> {
    fn walk(table: &toml::Table, prefix: &str, out: &mut Vec<(String, toml::Value)>) {
        for (key, value) in table {
            let path = if prefix.is_empty() {
                key.clone()
            } else {
                format!("{prefix}.{key}")
            };
            match value {
                toml::Value::Table(inner) => walk(inner, &path, out),
                _ => out.push((path, value.clone())),
            }
        }
    }
    let mut out = Vec::new();
    walk(table, "", &mut out);
    out
}

/// `over` laid over `base`: tables merge key by key, every other value replaces the base's.
fn merge(base: &mut toml::Table, over: &toml::Table) {
    for (key, value) in over {
        match (base.get_mut(key), value) {
            (Some(toml::Value::Table(inner)), toml::Value::Table(over_inner)) => merge(inner, over_inner),
            _ => {
                base.insert(key.clone(), value.clone());
            }
        }
    }
}

#[cfg(test)]
#[path = "layers_tests.rs"]
mod tests;
