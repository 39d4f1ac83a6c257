use super::*;
use crate::rng::{RngStream, seeded_rng, standard_normal_f32};
use crate::synth::sensor_noise::{DepthNoise, InstanceIds, MaskNoise, SensorSettings};
use crate::synth::{Preset, SyntheticScene};

fn intrinsics(w: u32, h: u32) -> CameraIntrinsics {
    CameraIntrinsics::centred(w, h, 0.8 * w as f32)
}

/// A frame of tilted planes at depths 1 to 5 m (one per band of columns), each pixel's depth
/// off by N(0, `sigma(z)`²).
fn planes(k: &CameraIntrinsics, seed: u64, sigma: impl Fn(f32) -> f32) -> Vec<f32> {
    let mut rng = seeded_rng(seed, RngStream::Mapper);
    let (w, h) = (k.width as usize, k.height as usize);
    (0..w * h)
        .map(|i| {
            let (u, v) = ((i % w) as f32, (i / w) as f32);
            let base = 1.0 + (4 * (i % w) / w) as f32;
            // A plane through (0, 0, base) tilted about both axes: 1/z affine in (u, v).
            let z = base / (1.0 + 0.2 * (u - k.cx) / k.fx - 0.1 * (v - k.cy) / k.fy);
            z + sigma(z) * standard_normal_f32(&mut rng)
        })
        .collect()
}

#[test]
fn the_noise_of_planes_is_found_at_every_depth() {
    let k = intrinsics(320, 240);
    let truth = |z: f32| 0.001 + 0.002 * z * z;
    let mut estimator = DepthNoiseEstimator::default();
    for seed in 0..4 {
        estimator.add_frame(&planes(&k, seed, truth), &k);
    }
    for bin in estimator.bins() {
        let ratio = bin.sigma_m / truth(bin.depth_m);
        assert!((0.85..1.15).contains(&ratio), "{bin:?}: {ratio}");
    }
    let model = estimator.estimate().expect("enough patches");
    for z in [1.0f32, 2.0, 4.0] {
        let ratio = model.sigma_m(z) / truth(z);
        assert!((0.9..1.1).contains(&ratio), "at {z} m: {model:?}, {ratio}");
    }
    assert!(estimator.valid_share() == 1.0);
}

#[test]
fn exact_planes_have_no_noise_and_a_depth_beyond_the_range_none() {
    let k = intrinsics(320, 240);
    let mut estimator = DepthNoiseEstimator::default();
    let mut depth = planes(&k, 0, |_| 0.0);
    // The farthest plane reaches 3.95 m; a range of 3.5 m cuts it.
    let far = depth.iter().map(|&d| if d > 3.5 { 0.0 } else { d }).collect::<Vec<_>>();
    estimator.add_frame(&far, &k);
    let model = estimator.estimate().expect("enough patches");
    assert!(model.sigma_m(4.0) < 1e-4, "{model:?}");
    assert!((3.45..=3.55).contains(&model.range_m), "{model:?}");
    depth.iter_mut().for_each(|d| *d = 0.0);
    let mut none = DepthNoiseEstimator::default();
    none.add_frame(&depth, &k);
    assert_eq!(none.estimate(), None, "no patch, no estimate");
    assert_eq!(none.valid_share(), 0.0);
}

#[test]
fn a_frame_of_another_size_is_ignored() {
    let mut estimator = DepthNoiseEstimator::default();
    estimator.add_frame(&[1.0; 10], &intrinsics(320, 240));
    assert_eq!(estimator, DepthNoiseEstimator::default());
}

/// σ(d) of each camera family, estimated from a dozen frames of the default synthetic scene,
/// within ±30 % of the family's own curve at 1, 2 and 4 m (the acceptance of "Real sensors"; the
/// estimates lie within 10 % of it but the time-of-flight camera's at 2 m, 20 % over: its σ grows
/// with the angle a surface is seen at), and its range within 0.2 m beyond the family's;
/// catmap's own Kinect-like model too, and exact depth as noise-free.
#[test]
fn each_camera_familys_noise_is_estimated_within_thirty_percent_at_one_two_and_four_metres() {
    let scene = SyntheticScene::generate(0, Preset::Default).expect("the default preset fits its room");
    let mut classes: Vec<_> = scene.objects().iter().map(|o| o.class()).collect();
    classes.sort_unstable();
    classes.dedup();
    let positions: Vec<usize> = (0..scene.trajectory().len()).step_by(20).collect();
    let frames: Vec<_> = positions.iter().map(|&p| scene.render(p).expect("renders")).collect();
    for family in [
        DepthNoise::Exact,
        DepthNoise::Kinect,
        DepthNoise::StructuredLight,
        DepthNoise::TimeOfFlight,
        DepthNoise::ActiveStereo,
    ] {
        let sensor = SensorSettings {
            depth: family,
            masks: MaskNoise::Exact,
            ids: InstanceIds::Consistent,
        };
        let mut estimator = DepthNoiseEstimator::default();
        for (frame, &position) in frames.iter().zip(&positions) {
            let mut noisy = frame.clone();
            sensor.apply(&mut noisy, 0, position, &classes);
            estimator.add_frame(&noisy.depth_m, &noisy.intrinsics);
        }
        let model = estimator.estimate().expect("the scene has planes");
        if family != DepthNoise::Exact {
            let over = model.range_m - family.max_range_m();
            assert!((0.0..=0.2).contains(&over), "{family:?}: range {model:?}");
        }
        for z in [1.0f32, 2.0, 4.0] {
            let (estimated, truth) = (model.sigma_m(z), family.sigma_m(z));
            if family == DepthNoise::Exact {
                assert!(estimated < 2e-4, "exact depth at {z} m: {estimated}");
            } else {
                let ratio = estimated / truth;
                assert!(
                    (0.7..1.3).contains(&ratio),
                    "{family:?} at {z} m: estimated {estimated:.5} against {truth:.5} ({ratio:.2}); bins {:?}",
                    estimator.bins()
                );
            }
        }
    }
}
