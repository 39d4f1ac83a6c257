//! TUM RGB-D's text lists, parsed: `rgb.txt` and `depth.txt` (`timestamp path` per line) and
//! `groundtruth.txt` (`timestamp tx ty tz qx qy qz qw`, the camera's pose in the world).
//!
//! Lines that are blank or start with `#` are comments (TUM's files open with three). Timestamps
//! are seconds, finite and strictly increasing down a file. Paths are relative to the sequence
//! folder and stay inside it. A pose is a translation and a unit quaternion `(qx, qy, qz, qw)`
//! (norm within [`QUATERNION_NORM_TOLERANCE`] of 1, then normalised): `world_from_camera`, TUM's
//! convention. Errors name the file and the line.

use std::path::{Component, Path};

use nalgebra::{Isometry3, Quaternion, UnitQuaternion};

use crate::dataset::camera_spec::{parse_numbers, world_from_camera_from_rows};
use crate::error::{CatmapError, Result};

/// Largest deviation of a pose quaternion's norm from 1 that is accepted (TUM writes 4 decimals).
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-2;

/// One data line of `rgb.txt` or `depth.txt`.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedFile {
    /// When the image was taken, seconds.
    pub timestamp_s: f64,
    /// The image, relative to the sequence folder.
    pub path: String,
    /// 1-based line number in its list.
    pub line: usize,
}

/// One data line of `groundtruth.txt`.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedPose {
    /// When the pose was measured, seconds.
    pub timestamp_s: f64,
    /// The camera's pose.
    pub world_from_camera: Isometry3<f32>,
    /// 1-based line number.
    pub line: usize,
}

/// The data lines of `text` (1-based line number, trimmed content): no blank or `#` lines.
fn data_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, line)| (i + 1, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'))
}

/// Checks that timestamps increase down a file: `previous` is the last data line's
/// `(line, timestamp)`.
fn check_increasing(timestamp_s: f64, previous: Option<(usize, f64)>) -> std::result::Result<(), String> {
    if !timestamp_s.is_finite() {
        return Err(format!("timestamp {timestamp_s} is not a finite number of seconds"));
    }
    match previous {
        Some((line, before)) if timestamp_s <= before => Err(format!(
            "timestamp {timestamp_s} is not after {before} on line {line}: timestamps must increase"
        )),
        _ => Ok(()),
    }
}

/// Why `path` cannot name an image of the sequence, if it cannot: it must be relative and stay
/// inside the folder.
fn path_problem(path: &str) -> Option<String> {
    let inside = Path::new(path)
        .components()
        .all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    (!inside).then(|| format!("{path:?} must be a path inside the sequence folder (relative, without `..`)"))
}

fn parse_error(list: &Path, line: usize, reason: String) -> CatmapError {
    CatmapError::Parse {
        path: list.to_path_buf(),
        line,
        reason,
    }
}

/// Parses the text of `rgb.txt` or `depth.txt` (`list` names it in errors).
pub fn parse_file_list(text: &str, list: &Path) -> Result<Vec<TimedFile>> {
    let mut files: Vec<TimedFile> = Vec::new();
    for (line, content) in data_lines(text) {
        let error = |reason: String| parse_error(list, line, reason);
        let fields: Vec<&str> = content.split_whitespace().collect();
        let [timestamp, path] = fields[..] else {
            return Err(error(format!(
                "expected `timestamp path`, found {} fields",
                fields.len()
            )));
        };
        let timestamp_s: f64 = timestamp
            .parse()
            .map_err(|_| error(format!("timestamp {timestamp:?} is not a number")))?;
        check_increasing(timestamp_s, files.last().map(|f| (f.line, f.timestamp_s))).map_err(error)?;
        if let Some(problem) = path_problem(path) {
            return Err(error(problem));
        }
        files.push(TimedFile {
            timestamp_s,
            path: path.to_owned(),
            line,
        });
    }
    Ok(files)
}

/// Parses the text of `groundtruth.txt` (`list` names it in errors).
pub fn parse_groundtruth(text: &str, list: &Path) -> Result<Vec<TimedPose>> {
    let mut poses: Vec<TimedPose> = Vec::new();
    for (line, content) in data_lines(text) {
        let error = |reason: String| parse_error(list, line, reason);
        let numbers = parse_numbers(content).map_err(error)?;
        let [timestamp_s, tx, ty, tz, qx, qy, qz, qw] = numbers[..] else {
            return Err(error(format!(
                "expected `timestamp tx ty tz qx qy qz qw`, found {} numbers",
                numbers.len()
            )));
        };
        check_increasing(timestamp_s, poses.last().map(|p| (p.line, p.timestamp_s))).map_err(error)?;
        let world_from_camera = pose_from_tum([tx, ty, tz], [qx, qy, qz, qw]).map_err(error)?;
        poses.push(TimedPose {
            timestamp_s,
            world_from_camera,
            line,
        });
    }
    Ok(poses)
}

/// A pose from TUM's translation and `(qx, qy, qz, qw)` quaternion; the error says why it is not
/// a rigid motion.
pub fn pose_from_tum(t: [f64; 3], [qx, qy, qz, qw]: [f64; 4]) -> std::result::Result<Isometry3<f32>, String> {
    let q = Quaternion::new(qw, qx, qy, qz);
    let norm = q.norm();
    if !norm.is_finite() {
        return Err("quaternion has a NaN or infinite entry".to_owned());
    }
    if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
        return Err(format!(
            "quaternion (qx, qy, qz, qw) = ({qx}, {qy}, {qz}, {qw}) has norm {norm:.4}, expected 1"
        ));
    }
    let r = UnitQuaternion::from_quaternion(q).to_rotation_matrix();
    let m = r.matrix();
    let rows = [
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        t[0],
        m[(1, 0)],
        m[(1, 1)],
        m[(1, 2)],
        t[1],
        m[(2, 0)],
        m[(2, 1)],
        m[(2, 2)],
        t[2],
        0.0,
        0.0,
        0.0,
        1.0,
    ];
    // The translation's checks (finite, not absurdly far) are the matrix readers'.
    world_from_camera_from_rows(&rows)
}

/// Reads and parses `rgb.txt` or `depth.txt`.
pub fn read_file_list(list: &Path) -> Result<Vec<TimedFile>> {
    parse_file_list(&read_list(list)?, list)
}

/// Reads and parses `groundtruth.txt`.
pub fn read_groundtruth(list: &Path) -> Result<Vec<TimedPose>> {
    parse_groundtruth(&read_list(list)?, list)
}

fn read_list(list: &Path) -> Result<String> {
    let bytes = std::fs::read(list).map_err(|e| CatmapError::io(list, e))?;
    String::from_utf8(bytes).map_err(|e| {
        let line = 1 + e.as_bytes()[..e.utf8_error().valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        parse_error(list, line, "not UTF-8 text".to_owned())
    })
}

#[cfg(test)]
#[path = "lists_tests.rs"]
mod tests;
