//! The end-of-run summary: objects per class, frames and seconds per stage, as a terminal table
//! and as `summary.json`.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::Context as _;
use catmap::metrics::{ClassLabel, ObjectClasses};
use catmap::{ClassId, ObjectId};
use serde::{Deserialize, Serialize};

use crate::snapshot::MapSnapshot;
pub use crate::training_report::{CategoryHistory, FieldTraining, TrainingReport};

/// One row per object.
#[derive(Debug, Clone, Serialize, Deserialize)]
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
    /// The oriented box: its pose `world_from_box` (`rotation` as a quaternion `[x, y, z, w]`,
    /// `translation` in metres: the box centre) and `half_extents` in metres. `None` while the
    /// cloud was too small to fit one.
    #[serde(default)]
    pub bounds: Option<catmap::geometry::oriented_box::OrientedBox>,
    /// The observed cloud's vertical mirror plane `normal · p = offset` (world, metres), if one
    /// was found: an object alone in its class with a plane trains on mirrored rays too
    /// (`fields.object_rays.mirror_rays`).
    #[serde(default)]
    pub mirror_plane: Option<catmap::geometry::mirror_symmetry::MirrorPlane>,
    /// A second plane at right angles to the first, if the cloud is symmetric about it too: its
    /// rays are mirrored across it as well (`fields.object_rays.mirror_planes`).
    #[serde(default)]
    pub second_mirror_plane: Option<catmap::geometry::mirror_symmetry::MirrorPlane>,
    /// Share of its mask pixels over its views that had a depth: below one half, most of what
    /// the camera saw of it had no return (beyond the range, dark or shiny) and its map rests on
    /// little.
    #[serde(default)]
    pub depth_share: Option<f32>,
}

/// What a run did and how long each stage took.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// catmap's version (and the commit it was built from, when known).
    pub version: String,
    /// The command line of the process that finished the run.
    pub command_line: Vec<String>,
    /// Seed of every random choice.
    pub seed: u64,
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
    /// Objects found to be part of another with per-frame ids (one object made twice: its ends
    /// seen apart as the camera panned, or a fragment of a split mask), in the order they were
    /// merged: the frame, the object that kept its id and the one taken into it.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub merged_objects: Vec<catmap::objects::instance_association::ObjectMerge>,
    /// Seconds per stage (`read` is the reader thread's decode time, overlapping the others).
    pub stage_seconds: BTreeMap<String, f64>,
    /// Wall-clock seconds of the whole run.
    pub total_seconds: f64,
    /// Frames per wall-clock second.
    pub frames_per_second: f64,
    /// Largest resident memory of the process so far, MiB (Linux; absent elsewhere).
    pub peak_resident_mib: Option<f64>,
    /// How the fields trained: the schedule, each field's steps and state, and why the phases
    /// after the stream ended.
    pub training: Option<TrainingReport>,
    /// What became of each step after the map was made (`recording`: the recording's
    /// completion, `eval`: the evaluation). A failure here never fails the run.
    pub finishing_steps: BTreeMap<String, StepOutcome>,
    /// A live run's stream (`catmap run --live`): its rate, frames taken and dropped, and the
    /// seconds from the stream's end to the final meshes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub live: Option<LiveSummary>,
    /// The depth and mask settings the run took (`--depth`, `--masks`, else the probe of the
    /// dataset's frames) and what the probe found: σ(d) and range of the depth, how far the masks'
    /// borders sit from their silhouettes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sensor: Option<catmap::config::sensor_profile::SensorChoice>,
    /// The whole configuration the run used (defaults, config file and command line resolved),
    /// the same tree as `catmap config` prints.
    pub config: Option<catmap::MapperConfig>,
}

/// What became of one step after the map was made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum StepOutcome {
    /// Done: what it wrote (a file, or the viewer the recording went to).
    Done {
        /// The output.
        output: String,
    },
    /// Not run.
    Skipped {
        /// Why not.
        reason: String,
    },
    /// Failed; the run went on.
    Failed {
        /// The error, naming the file at fault.
        reason: String,
    },
}

/// The part of `summary.json` that names the objects' classes.
#[derive(Deserialize)]
struct SummaryObjects {
    objects: Vec<ObjectRow>,
}

/// The objects' classes recorded in a run's `summary.json`, or in `summary.json` inside the run
/// folder `path`.
pub fn read_object_classes(path: &Path) -> anyhow::Result<ObjectClasses> {
    let file = if path.is_dir() {
        path.join("summary.json")
    } else {
        path.to_owned()
    };
    let text = std::fs::read_to_string(&file).with_context(|| format!("cannot read {}", file.display()))?;
    let summary: SummaryObjects = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a catmap run summary (no objects with classes)", file.display()))?;
    Ok(object_classes(&summary.objects))
}

/// Object id → class label of `rows`.
fn object_classes(rows: &[ObjectRow]) -> ObjectClasses {
    rows.iter()
        .map(|row| {
            let label = ClassLabel {
                class: ClassId(row.class),
                name: row.class_name.clone(),
            };
            (ObjectId(row.id), label)
        })
        .collect()
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
                class_name: o.class_name.clone(),
                visible_frames: o.visible_frames,
                cloud_points: o.cloud_points,
                box_extents_m: o.bounds.map(|b| b.extents().into()),
                bounds: o.bounds,
                mirror_plane: o.mirror_plane,
                second_mirror_plane: o.second_mirror_plane,
                depth_share: o.depth_share,
            })
            .collect();
        let mut objects_per_class = BTreeMap::new();
        for row in &objects {
            *objects_per_class.entry(row.class_name.clone()).or_insert(0) += 1;
        }
        Self {
            version: String::new(),
            command_line: Vec::new(),
            seed: 0,
            dataset,
            mode: String::new(),
            training_steps: 0,
            frames: map.frames_ingested,
            frames_skipped: map.frames_skipped,
            objects_per_class,
            objects,
            merged_objects: map.merges.clone(),
            stage_seconds,
            total_seconds,
            frames_per_second: map.frames_ingested as f64 / total_seconds.max(1e-9),
            peak_resident_mib: catmap::process_memory::peak_resident_mib(),
            training: None,
            finishing_steps: BTreeMap::new(),
            live: None,
            sensor: None,
            config: None,
        }
    }

    /// Each object's class as the map voted it from the semantic masks.
    pub fn object_classes(&self) -> ObjectClasses {
        object_classes(&self.objects)
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
        if !self.merged_objects.is_empty() {
            let merges: Vec<String> = (self.merged_objects.iter())
                .map(|m| format!("{} into {} (frame {})", m.absorbed, m.kept, m.frame))
                .collect();
            let _ = writeln!(out, "\nobjects merged: {}", merges.join(", "));
        }
        if let Some(training) = &self.training {
            training.write_table(&mut out);
        }
        let _ = writeln!(out, "\n| stage | seconds |\n|---|---:|");
        for (stage, secs) in &self.stage_seconds {
            let _ = writeln!(out, "| {stage} | {secs:.2} |");
        }
        let _ = writeln!(
            out,
            "| **wall clock** | {:.2} ({:.1} frames/s) |",
            self.total_seconds, self.frames_per_second
        );
        let little: Vec<String> = self
            .objects
            .iter()
            .filter_map(|o| {
                let share = o
                    .depth_share
                    .filter(|&s| s < catmap::objects::frame_observation::LOW_DEPTH_SHARE)?;
                Some(format!("{} {} ({:.0} %)", o.class_name, o.id, 100.0 * share))
            })
            .collect();
        if !little.is_empty() {
            let _ = writeln!(
                out,
                "\nmost pixels with no depth (beyond the camera's range, dark or shiny; mapped from little): {}",
                little.join(", ")
            );
        }
        if let Some(peak) = self.peak_resident_mib {
            let _ = writeln!(out, "\npeak memory: {peak:.0} MiB resident");
        }
        for (step, outcome) in &self.finishing_steps {
            if let StepOutcome::Failed { reason } = outcome {
                let _ = writeln!(out, "{step} failed (the map is complete): {reason}");
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn summary_with(rows: Vec<ObjectRow>) -> RunSummary {
        let map = crate::snapshot::MapSnapshot {
            frames_ingested: 3,
            frames_skipped: 0,
            objects: Vec::new(),
            background: None,
            categories: Vec::new(),
            merges: Vec::new(),
        };
        let mut summary = RunSummary::new("scene".to_owned(), &map, BTreeMap::new(), 1.0);
        summary.objects = rows;
        summary
    }

    fn row(id: u32, class: u32) -> ObjectRow {
        ObjectRow {
            id,
            class,
            class_name: catmap::dataset::class_names::ClassNames::replica().name(ClassId(class)),
            visible_frames: 1,
            cloud_points: 10,
            box_extents_m: None,
            bounds: None,
            mirror_plane: None,
            second_mirror_plane: None,
            depth_share: None,
        }
    }

    #[test]
    fn objects_whose_pixels_mostly_had_no_depth_are_named_in_the_table() {
        let lamp = ObjectRow {
            depth_share: Some(0.3),
            ..row(4, 47)
        };
        let chair = ObjectRow {
            depth_share: Some(0.9),
            ..row(3, 20)
        };
        let table = summary_with(vec![chair, lamp]).table();
        let line = table
            .lines()
            .find(|l| l.contains("no depth"))
            .expect("a line names them");
        assert!(line.contains("lamp 4 (30 %)") && !line.contains("chair"), "{line}");
        assert!(!summary_with(vec![row(3, 20)]).table().contains("no depth"));
    }

    #[test]
    fn a_written_summary_names_each_objects_class_from_its_file_or_its_folder() {
        let dir = tempfile::tempdir().expect("temp dir");
        let mut summary = summary_with(vec![row(3, 20), row(5, 200)]);
        summary.finishing_steps.insert(
            "eval".to_owned(),
            StepOutcome::Failed {
                reason: "gt/obj_3.ply: bad".to_owned(),
            },
        );
        let path = dir.path().join("summary.json");
        summary.write_json(&path).expect("written");
        for source in [path.as_path(), dir.path()] {
            let classes = read_object_classes(source).expect("a catmap summary");
            assert_eq!(classes, summary.object_classes(), "read back from {}", source.display());
        }
        let classes = summary.object_classes();
        assert_eq!(classes[&ObjectId(3)].name, "chair");
        assert_eq!(classes[&ObjectId(5)].name, "class 200", "a class without a known name");
        let text = std::fs::read_to_string(&path).expect("readable");
        assert!(
            text.contains(r#""outcome": "failed""#) && text.contains("obj_3.ply"),
            "the failure is recorded: {text}"
        );
        assert!(
            summary
                .table()
                .contains("eval failed (the map is complete): gt/obj_3.ply: bad")
        );
    }

    #[test]
    fn a_file_that_is_not_a_summary_is_named_in_the_error() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("metrics.json");
        std::fs::write(&path, r#"{"mean": {}}"#).expect("write");
        let err = read_object_classes(&path).expect_err("no objects");
        assert!(format!("{err:#}").contains("metrics.json"), "{err:#}");
        let err = read_object_classes(&dir.path().join("nope")).expect_err("no file");
        assert!(format!("{err:#}").contains("nope"), "{err:#}");
    }
}

/// What a live run's stream did.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LiveSummary {
    /// Frames per second of the replay.
    pub fps: f64,
    /// Frames the mapper took.
    pub frames_taken: u64,
    /// Frames dropped because a newer one arrived before the mapper could take them.
    pub frames_dropped: u64,
    /// Seconds from the stream's end (its last tick) to the final meshes.
    pub seconds_after_stream: f64,
}
