//! A TUM sequence's camera: `--camera`, else `intrinsics.json` (TUM ships none, so one of the two
//! must be given), and its depth scale.

use std::path::Path;

use super::{TUM_DEPTH_SCALE, TumOptions};
use crate::dataset::camera_spec::read_intrinsics_json;
use crate::error::{CatmapError, Result};
use crate::sensor::frame::CameraIntrinsics;

/// The `--camera` value of TUM's default (ROS) intrinsics, quoted when a sequence has none.
const TUM_DEFAULT_CAMERA: &str = "640,480,525,525,319.5,239.5";

/// The intrinsics (the CLI camera, else `intrinsics.json`) and the depth scale.
pub(super) fn resolve_camera(dir: &Path, options: &TumOptions) -> Result<(CameraIntrinsics, f32)> {
    let json = dir.join("intrinsics.json");
    let (intrinsics, json_scale) = match (options.camera, json.exists()) {
        (Some(camera), false) => (camera, None),
        (None, false) => {
            let reason = format!(
                "no such file, and no --camera: TUM RGB-D ships no intrinsics file; pass the \
                 camera's as --camera W,H,FX,FY,CX,CY (TUM's default: {TUM_DEFAULT_CAMERA}) or \
                 write intrinsics.json (width, height, fx, fy, cx, cy)"
            );
            return Err(CatmapError::layout(json, reason));
        }
        // A folder or an unreadable file in its place is an error naming it, not a silent default.
        (Some(camera), true) => (camera, json_depth_scale(&json)?),
        (None, true) => (read_intrinsics_json(&json)?, json_depth_scale(&json)?),
    };
    let depth_scale = options.depth_scale.or(json_scale).unwrap_or(TUM_DEPTH_SCALE);
    Ok((intrinsics, depth_scale))
}

/// The optional `depth_scale` of an `intrinsics.json`.
fn json_depth_scale(path: &Path) -> Result<Option<f32>> {
    let text = std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| CatmapError::Parse {
        path: path.to_path_buf(),
        line: e.line(),
        reason: e.to_string(),
    })?;
    match json.get("depth_scale") {
        None => Ok(None),
        Some(value) => match value.as_f64() {
            Some(scale) if scale > 0.0 && scale <= f64::from(f32::MAX) => Ok(Some(scale as f32)),
            _ => Err(CatmapError::Parse {
                path: path.to_path_buf(),
                line: 0,
                reason: format!("\"depth_scale\" must be a positive number, found {value}"),
            }),
        },
    }
}
