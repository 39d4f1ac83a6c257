//! The end-of-run summary: objects per class, frames and seconds per stage, as a terminal table
//! and as `summary.json`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use catmap::classes::replica_name;
use serde::Serialize;

use crate::snapshot::MapSnapshot;

/// One row per object.
#[derive(Debug, Clone, Serialize)]
pub struct ObjectRow {
    /// Dataset instance id.
    pub id: u32,
    /// Class id.
    pub class: u32,
    /// Class name when known.
    pub class_name: String,
    /// Frames the object was visible in.
    pub visible_frames: u64,
    /// Observed cloud points (1 cm voxels).
    pub cloud_points: usize,
    /// Oriented box edge lengths, metres (sorted as the box axes: x, y, z).
    pub box_extents_m: Option<[f32; 3]>,
}

/// What a run did and how long each stage took.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Where the frames came from.
    pub dataset: String,
    /// Field model and protocol, e.g. "instance (offline)".
    pub mode: String,
    /// Training steps run (object batch).
    pub training_steps: u64,
    /// Frames mapped.
    pub frames: u64,
    /// Frames the reader skipped.
    pub frames_skipped: u64,
    /// Objects per class name.
    pub objects_per_class: BTreeMap<String, usize>,
    /// Every object.
    pub objects: Vec<ObjectRow>,
    /// Seconds per stage (`read` is the reader thread's decode time, overlapping the others).
    pub stage_seconds: BTreeMap<String, f64>,
    /// Wall-clock seconds of the whole run.
    pub total_seconds: f64,
    /// Frames per wall-clock second.
    pub frames_per_second: f64,
    /// Largest resident memory of the process so far, MiB (Linux; absent elsewhere).
    pub peak_resident_mib: Option<f64>,
}

fn class_name(class: catmap::ClassId) -> String {
    replica_name(class).map_or_else(|| format!("class {class}"), str::to_owned)
}

impl RunSummary {
    /// Builds the summary of a finished map.
    pub fn new(dataset: String, map: &MapSnapshot, stage_seconds: BTreeMap<String, f64>, total_seconds: f64) -> Self {
        let objects: Vec<ObjectRow> = map
            .objects
            .iter()
            .map(|o| ObjectRow {
                id: o.id.0,
                class: o.class.0,
                class_name: class_name(o.class),
                visible_frames: o.visible_frames,
                cloud_points: o.cloud_points,
                box_extents_m: o.bounds.map(|b| b.extents().into()),
            })
            .collect();
        let mut objects_per_class = BTreeMap::new();
        for row in &objects {
            *objects_per_class.entry(row.class_name.clone()).or_insert(0) += 1;
        }
        Self {
            dataset,
            mode: String::new(),
            training_steps: 0,
            frames: map.frames_ingested,
            frames_skipped: map.frames_skipped,
            objects_per_class,
            objects,
            stage_seconds,
            total_seconds,
            frames_per_second: map.frames_ingested as f64 / total_seconds.max(1e-9),
            peak_resident_mib: catmap::process_memory::peak_resident_mib(),
        }
    }

    /// Writes the summary as pretty JSON, atomically.
    pub fn write_json(&self, path: &Path) -> catmap::Result<()> {
        let text = serde_json::to_string_pretty(self).expect("the summary has only JSON-representable fields");
        catmap::atomic_file::write_atomic(path, text.as_bytes())
    }

    /// The end-of-run table for the terminal.
    pub fn table(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "{} frames ({} skipped) from {}",
            self.frames, self.frames_skipped, self.dataset
        );
        if !self.mode.is_empty() {
            let _ = writeln!(out, "mode: {}, {} training steps", self.mode, self.training_steps);
        }
        let _ = writeln!(out, "\n| class | objects |\n|---|---:|");
        for (class, n) in &self.objects_per_class {
            let _ = writeln!(out, "| {class} | {n} |");
        }
        let _ = writeln!(out, "| **all** | {} |", self.objects.len());
        let _ = writeln!(out, "\n| stage | seconds |\n|---|---:|");
        for (stage, secs) in &self.stage_seconds {
            let _ = writeln!(out, "| {stage} | {secs:.2} |");
        }
        let _ = writeln!(
            out,
            "| **wall clock** | {:.2} ({:.1} frames/s) |",
            self.total_seconds, self.frames_per_second
        );
        if let Some(peak) = self.peak_resident_mib {
            let _ = writeln!(out, "\npeak memory: {peak:.0} MiB resident");
        }
        out
    }
}
