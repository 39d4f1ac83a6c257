//! Properties every accepted reader output must have.

use catmap::RgbdFrame;
use catmap::dataset::camera_spec::intrinsics_problem;
use nalgebra::Isometry3;

/// A decoded frame must be consistent (sizes, finite pose) and hold no NaN or negative depth.
pub fn check_frame(frame: &RgbdFrame) -> Result<(), String> {
    frame.validate()?;
    if let Some(problem) = intrinsics_problem(&frame.intrinsics) {
        return Err(format!("decoded frame has bad intrinsics: {problem}"));
    }
    match frame.depth_m.iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
        Some(d) => Err(format!("decoded frame has depth {d}")),
        None => Ok(()),
    }
}

/// A pose must be finite with a unit rotation.
pub fn check_pose(pose: &Isometry3<f32>) -> Result<(), String> {
    let finite = pose.to_homogeneous().iter().all(|x| x.is_finite());
    if finite && (pose.rotation.norm() - 1.0).abs() < 1e-4 {
        Ok(())
    } else {
        Err(format!("accepted pose is not a rigid motion: {pose:?}"))
    }
}
