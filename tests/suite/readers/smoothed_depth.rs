//! `dataset.depth_smoothing`: any frame source wrapped so that its frames' depth is smoothed
//! before the mapper reads it — a Kinect-like synthetic scene comes closer to its exact depth,
//! and everything else passes through.

use std::sync::Arc;

use catmap::dataset::FrameSource;
use catmap::dataset::smoothed_depth::with_depth_smoothing;
use catmap::sensor::depth_smoothing::{BilateralDepth, DepthSmoothing};
use catmap::synth::{InstanceIds, Preset, SensorModel, SensorSettings, SyntheticScene};

/// Root-mean-square difference of two depth images over the pixels valid in both.
fn rms(a: &[f32], b: &[f32]) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (x, y) in a.iter().zip(b) {
        if *x > 0.0 && *y > 0.0 {
            sum += f64::from(x - y).powi(2);
            n += 1;
        }
    }
    (sum / n.max(1) as f64).sqrt() as f32
}

#[test]
fn a_depth_cameras_frames_come_closer_to_the_exact_depth_and_the_rest_passes_through() {
    let exact = SyntheticScene::generate(2, Preset::Small).expect("the small preset fits its room");
    let scene = SyntheticScene::generate(2, Preset::Small).expect("the small preset fits its room");
    let noisy: Arc<dyn FrameSource> =
        Arc::new(scene.with_sensor(SensorSettings::new(SensorModel::Kinect, InstanceIds::Consistent)));
    let smoothed = with_depth_smoothing(noisy.clone(), DepthSmoothing::Bilateral, &BilateralDepth::default());
    assert_eq!(
        (smoothed.len(), smoothed.intrinsics()),
        (noisy.len(), noisy.intrinsics())
    );
    assert_eq!(smoothed.name(), noisy.name());
    for position in [0, noisy.len() / 2] {
        let truth = exact.read_frame(position).expect("frame").depth_m;
        let raw = noisy.read_frame(position).expect("frame");
        let filtered = smoothed.read_frame(position).expect("frame");
        let (before, after) = (rms(&raw.depth_m, &truth), rms(&filtered.depth_m, &truth));
        assert!(after < 0.8 * before, "frame {position}: rms {before} m → {after} m");
        let holes = |d: &[f32]| d.iter().filter(|z| **z <= 0.0).count();
        assert_eq!(holes(&filtered.depth_m), holes(&raw.depth_m), "holes stay holes");
        assert_eq!(
            (filtered.index, filtered.instances.clone()),
            (raw.index, raw.instances.clone())
        );
        assert_eq!(filtered.world_from_camera, raw.world_from_camera);
    }
    let untouched = with_depth_smoothing(noisy.clone(), DepthSmoothing::None, &BilateralDepth::default());
    assert!(Arc::ptr_eq(&untouched, &noisy), "no smoothing, the source itself");
}
