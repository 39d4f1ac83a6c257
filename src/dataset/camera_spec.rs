//! Camera parameters written as text: the CLI `--camera W,H,FX,FY,CX,CY` spec, a Replica folder's
//! `intrinsics.json`, ScanNet's 4×4 `intrinsic_depth.txt`, and 4×4 camera-to-world pose matrices.
//!
//! Pose matrices are checked (finite, last row ≈ `[0, 0, 0, 1]`, rotation part close to a proper
//! rotation) and their rotation orthonormalised through the SVD (`R = U·Vᵀ`), because text files
//! round the entries.

use std::path::Path;

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion};

use crate::error::{CatmapError, Result};
use crate::sensor::frame::CameraIntrinsics;

/// Largest camera translation accepted, metres: farther is a corrupt file (and would not survive the
/// conversion to 32-bit floats).
const MAX_TRANSLATION_M: f64 = 1.0e6;

/// Largest deviation of the last pose row from `[0, 0, 0, 1]` that is accepted.
const LAST_ROW_TOLERANCE: f64 = 1e-3;
/// Largest entry of `RᵀR − I` accepted before orthonormalising.
const ORTHONORMAL_TOLERANCE: f64 = 1e-2;

/// Why `intrinsics` cannot describe a pinhole camera, if it cannot.
pub fn intrinsics_problem(intrinsics: &CameraIntrinsics) -> Option<String> {
    let CameraIntrinsics {
        width,
        height,
        fx,
        fy,
        cx,
        cy,
    } = *intrinsics;
    if width == 0 || height == 0 {
        return Some(format!("image size {width}×{height} must be positive"));
    }
    if !(fx > 0.0 && fy > 0.0 && fx.is_finite() && fy.is_finite()) {
        return Some(format!(
            "focal lengths fx = {fx}, fy = {fy} must be positive and finite"
        ));
    }
    if !(cx.is_finite() && cy.is_finite()) {
        return Some(format!("principal point ({cx}, {cy}) must be finite"));
    }
    // Lenient (crops and shifted lenses move it off-centre, even off the image); farther than an
    // image size beyond the border is a corrupt file.
    let (w, h) = (f64::from(width), f64::from(height));
    if (f64::from(cx) - w / 2.0).abs() > 1.5 * w || (f64::from(cy) - h / 2.0).abs() > 1.5 * h {
        return Some(format!(
            "principal point ({cx}, {cy}) lies far outside the {width}×{height} image"
        ));
    }
    None
}

/// Parses a CLI camera spec `W,H,FX,FY,CX,CY` (e.g. `1200,680,600,600,599.5,339.5`).
pub fn parse_camera_spec(spec: &str) -> Result<CameraIntrinsics> {
    let bad = |reason: String| CatmapError::ConfigValue(format!("--camera {spec:?}: {reason}"));
    let parts: Vec<&str> = spec.split(',').map(str::trim).collect();
    let [w, h, fx, fy, cx, cy] = parts[..] else {
        return Err(bad(format!(
            "expected 6 comma-separated values W,H,FX,FY,CX,CY, found {}",
            parts.len()
        )));
    };
    let size = |name: &str, text: &str| {
        text.parse::<u32>()
            .map_err(|_| bad(format!("{name} must be a positive integer, found {text:?}")))
    };
    let number = |name: &str, text: &str| match text.parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(bad(format!("{name} must be a finite number, found {text:?}"))),
    };
    let intrinsics = CameraIntrinsics {
        width: size("W", w)?,
        height: size("H", h)?,
        fx: number("FX", fx)?,
        fy: number("FY", fy)?,
        cx: number("CX", cx)?,
        cy: number("CY", cy)?,
    };
    match intrinsics_problem(&intrinsics) {
        Some(reason) => Err(bad(reason)),
        None => Ok(intrinsics),
    }
}

fn read_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path).map_err(|e| CatmapError::io(path, e))
}

fn parse_error(path: &Path, line: usize, reason: impl Into<String>) -> CatmapError {
    CatmapError::Parse {
        path: path.to_path_buf(),
        line,
        reason: reason.into(),
    }
}

/// Reads `intrinsics.json`: an object with numeric `width`, `height`, `fx`, `fy`, `cx`, `cy`
/// (other keys, e.g. `depth_scale`, are ignored).
pub fn read_intrinsics_json(path: &Path) -> Result<CameraIntrinsics> {
    let text = read_text(path)?;
    let json: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| parse_error(path, e.line(), e.to_string()))?;
    let number = |key: &str| {
        json.get(key)
            .and_then(serde_json::Value::as_f64)
            .ok_or_else(|| parse_error(path, 0, format!("missing or non-numeric key {key:?}")))
    };
    let size = |key: &str| {
        let v = number(key)?;
        if v.fract() == 0.0 && v >= 1.0 && v <= f64::from(u32::MAX) {
            Ok(v as u32)
        } else {
            Err(parse_error(
                path,
                0,
                format!("{key:?} must be a positive integer, found {v}"),
            ))
        }
    };
    let intrinsics = CameraIntrinsics {
        width: size("width")?,
        height: size("height")?,
        fx: number("fx")? as f32,
        fy: number("fy")? as f32,
        cx: number("cx")? as f32,
        cy: number("cy")? as f32,
    };
    match intrinsics_problem(&intrinsics) {
        Some(reason) => Err(parse_error(path, 0, reason)),
        None => Ok(intrinsics),
    }
}

/// Reads a 4×4 (or 3×3) intrinsic matrix as ScanNet writes it (`fx = m00`, `fy = m11`,
/// `cx = m02`, `cy = m12`), for images of `width × height`.
pub fn read_intrinsic_matrix(path: &Path, width: u32, height: u32) -> Result<CameraIntrinsics> {
    let text = read_text(path)?;
    let mut rows = Vec::new();
    for (i, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        rows.push(parse_numbers(line).map_err(|reason| parse_error(path, i + 1, reason))?);
    }
    let columns = rows.len();
    if !(columns == 3 || columns == 4) || rows.iter().any(|r| r.len() != columns) {
        let reason = format!("expected a 4×4 (or 3×3) matrix, found {columns} rows");
        return Err(parse_error(path, 0, reason));
    }
    let intrinsics = CameraIntrinsics {
        width,
        height,
        fx: rows[0][0] as f32,
        fy: rows[1][1] as f32,
        cx: rows[0][2] as f32,
        cy: rows[1][2] as f32,
    };
    match intrinsics_problem(&intrinsics) {
        Some(reason) => Err(parse_error(path, 0, reason)),
        None => Ok(intrinsics),
    }
}

/// Whitespace-separated numbers of one text line (`inf`, `-inf` and `nan` parse, as ScanNet
/// writes lost poses as `-inf`); the error names the first token that is not a number.
pub fn parse_numbers(line: &str) -> std::result::Result<Vec<f64>, String> {
    line.split_whitespace()
        .map(|token| token.parse::<f64>().map_err(|_| format!("{token:?} is not a number")))
        .collect()
}

/// A camera-to-world pose from a row-major 4×4 matrix; the error says why it is not a rigid motion.
pub fn world_from_camera_from_rows(m: &[f64; 16]) -> std::result::Result<Isometry3<f32>, String> {
    if m.iter().any(|v| !v.is_finite()) {
        return Err("pose has a NaN or infinite entry".to_owned());
    }
    let last_row_off = [m[12], m[13], m[14], m[15] - 1.0]
        .iter()
        .any(|v| v.abs() > LAST_ROW_TOLERANCE);
    if last_row_off {
        return Err(format!(
            "last row is [{}, {}, {}, {}], expected [0, 0, 0, 1]",
            m[12], m[13], m[14], m[15]
        ));
    }
    let rotation = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
    let det = rotation.determinant();
    if det <= 0.0 {
        return Err(format!(
            "rotation part has determinant {det:.4}, expected a rotation (determinant 1)"
        ));
    }
    let deviation = (rotation.transpose() * rotation - Matrix3::identity()).amax();
    if deviation > ORTHONORMAL_TOLERANCE {
        return Err(format!(
            "rotation part is not orthonormal (RᵀR differs from I by {deviation:.4})"
        ));
    }
    if [m[3], m[7], m[11]].iter().any(|v| v.abs() > MAX_TRANSLATION_M) {
        return Err(format!(
            "translation [{:.3e}, {:.3e}, {:.3e}] is more than {MAX_TRANSLATION_M} m from the origin",
            m[3], m[7], m[11]
        ));
    }
    let svd = rotation.svd(true, true);
    let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
        return Err("rotation part has no singular value decomposition".to_owned());
    };
    let orthonormal = Rotation3::from_matrix_unchecked((u * v_t).cast::<f32>());
    let translation = Translation3::new(m[3] as f32, m[7] as f32, m[11] as f32);
    Ok(Isometry3::from_parts(
        translation,
        UnitQuaternion::from_rotation_matrix(&orthonormal),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_spec_parses_six_values() {
        let k = parse_camera_spec("640, 480,500,510,319.5,239.5").expect("valid spec");
        assert_eq!(
            k,
            CameraIntrinsics {
                width: 640,
                height: 480,
                fx: 500.0,
                fy: 510.0,
                cx: 319.5,
                cy: 239.5
            }
        );
    }

    #[test]
    fn camera_spec_errors_say_what_is_wrong() {
        let count = parse_camera_spec("640,480,500").expect_err("three values");
        assert!(
            count.to_string().contains("expected 6 comma-separated values"),
            "{count}"
        );
        let width = parse_camera_spec("6x0,480,500,500,1,1").expect_err("bad width");
        assert!(
            width
                .to_string()
                .contains("W must be a positive integer, found \"6x0\""),
            "{width}"
        );
        let focal = parse_camera_spec("640,480,-5,500,1,1").expect_err("negative focal length");
        assert!(focal.to_string().contains("focal lengths"), "{focal}");
        let nan = parse_camera_spec("640,480,500,500,NaN,1").expect_err("NaN centre");
        assert!(nan.to_string().contains("CX must be a finite number"), "{nan}");
    }

    #[test]
    fn pose_rotation_is_orthonormalised() {
        let s = 1.0005; // a slightly scaled identity, as rounding in text files produces
        let m = [s, 0.0, 0.0, 1.0, 0.0, s, 0.0, 2.0, 0.0, 0.0, s, 3.0, 0.0, 0.0, 0.0, 1.0];
        let pose = world_from_camera_from_rows(&m).expect("near-rigid pose");
        assert!((pose.rotation.angle()).abs() < 1e-6);
        assert_eq!(pose.translation.vector, nalgebra::Vector3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn reflections_and_projective_rows_are_rejected() {
        let mirror = [
            -1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        assert!(
            world_from_camera_from_rows(&mirror)
                .expect_err("det −1")
                .contains("determinant")
        );
        let projective = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 1.0,
        ];
        assert!(
            world_from_camera_from_rows(&projective)
                .expect_err("last row")
                .contains("last row")
        );
    }

    #[test]
    fn translations_beyond_f32_and_far_principal_points_are_rejected() {
        // Found by the pose fuzzers: 1e39 is finite as f64 but became inf as f32.
        let far = [
            1.0, 0.0, 0.0, 1e39, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let err = world_from_camera_from_rows(&far).expect_err("too far");
        assert!(err.contains("1.000e39") && err.contains("from the origin"), "{err}");
        let camera = |cx, cy| CameraIntrinsics {
            width: 16,
            height: 12,
            fx: 12.0,
            fy: 12.0,
            cx,
            cy,
        };
        assert_eq!(intrinsics_problem(&camera(7.5, 5.5)), None);
        assert_eq!(
            intrinsics_problem(&camera(20.0, -3.0)),
            None,
            "off the image but plausible"
        );
        let problem = intrinsics_problem(&camera(70.5, 5.5)).expect("far outside");
        assert!(problem.contains("far outside the 16×12 image"), "{problem}");
    }
}
