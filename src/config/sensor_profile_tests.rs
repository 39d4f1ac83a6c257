use super::*;
use crate::synth::{InstanceIds, Preset, SensorModel, SensorSettings, SyntheticScene};

fn profile(sigma_at_2m_m: f32, off_share: f32) -> SensorProfile {
    SensorProfile {
        frames: 12,
        depth_noise: Some(DepthNoiseModel {
            sigma_floor_m: 0.0,
            sigma_per_m2: sigma_at_2m_m / 4.0,
            range_m: 5.0,
        }),
        depth_noise_bins: Vec::new(),
        valid_depth_share: 0.9,
        mask_borders: Some(MaskBorderModel {
            off_share,
            beyond_share: off_share / 2.0,
            p90_px: 2,
            samples: 1000,
        }),
        instance_ids: None,
    }
}

#[test]
fn flags_win_and_the_probe_decides_the_rest() {
    let noisy = profile(0.006, 0.6);
    let choice = SensorChoice::resolve(None, Some(MaskBorders::Exact), None, Some(noisy.clone()));
    assert_eq!(
        (choice.depth, choice.depth_chosen_by),
        (DepthImages::Camera, ChosenBy::Probe)
    );
    assert_eq!(
        (choice.masks, choice.masks_chosen_by),
        (MaskBorders::Exact, ChosenBy::Flag)
    );
    let exact = SensorChoice::resolve(None, None, None, Some(profile(0.0003, 0.03)));
    assert_eq!((exact.depth, exact.masks), (DepthImages::Exact, MaskBorders::Exact));
    let unprobed = SensorChoice::resolve(None, None, None, None);
    assert_eq!(
        (unprobed.depth, unprobed.masks),
        (DepthImages::Exact, MaskBorders::Exact)
    );
}

#[test]
fn a_choice_lays_the_sensors_settings_over_a_profile() {
    let base = MapperConfig::default();
    let exact = SensorChoice::resolve(None, None, None, Some(profile(0.0003, 0.03)));
    assert_eq!(
        exact.apply(base.clone()),
        base,
        "exact depth and masks are the profile's"
    );
    let noisy = SensorChoice::resolve(None, None, None, Some(profile(0.006, 0.6)));
    let mut expected = base.clone();
    expected.objects = expected.objects.clone().with_mask_borders(MaskBorders::Segmenter);
    expected.objects.association.instances = InstanceSource::PerFrame;
    let expected = expected.with_depth_images(DepthImages::Camera);
    assert_eq!(
        noisy.apply(base.clone()),
        expected,
        "as --depth camera --masks segmenter --instances per-frame"
    );
    let camera_exact_masks = SensorChoice::resolve(
        Some(DepthImages::Camera),
        Some(MaskBorders::Exact),
        Some(InstanceSource::Consistent),
        None,
    )
    .apply(base);
    assert_eq!(
        camera_exact_masks.objects.box_min_voxel_points, 3,
        "a camera's strays are left out of the boxes whatever the masks"
    );
    assert_eq!(camera_exact_masks.objects.mask_border_px, 0);
}

#[test]
fn the_small_scene_probes_exact_and_through_a_kinect_like_camera_and_segmenter_noisy() {
    let exact = SyntheticScene::generate(1, Preset::Small).expect("small scene");
    let profile = SensorProfile::probe(&exact);
    assert_eq!(profile.frames, PROBE_FRAMES);
    assert_eq!(
        (profile.depth_images(), profile.mask_borders(), profile.instances()),
        (DepthImages::Exact, MaskBorders::Exact, InstanceSource::Consistent)
    );
    assert_eq!(profile.instance_ids.map(|m| m.pairs), Some(PROBE_FRAMES / PAIR_EVERY));
    let noisy = SyntheticScene::generate(1, Preset::Small)
        .expect("small scene")
        .with_sensor(SensorSettings::new(SensorModel::Kinect, InstanceIds::PerFrame));
    let profile = SensorProfile::probe(&noisy);
    assert_eq!(
        (profile.depth_images(), profile.mask_borders(), profile.instances()),
        (DepthImages::Camera, MaskBorders::Segmenter, InstanceSource::PerFrame),
        "{profile:?}"
    );
    let per_frame_exact = SyntheticScene::generate(1, Preset::Small)
        .expect("small scene")
        .with_sensor(SensorSettings::new(SensorModel::None, InstanceIds::PerFrame));
    let profile = SensorProfile::probe(&per_frame_exact);
    assert_eq!(
        (profile.mask_borders(), profile.instances()),
        (MaskBorders::Exact, InstanceSource::PerFrame),
        "exact masks, ids numbered anew in every frame: {profile:?}"
    );
}

#[test]
fn the_markdown_page_states_the_choice_and_the_fit() {
    let mut noisy = profile(0.006, 0.6);
    noisy.depth_noise_bins = vec![DepthNoiseBin {
        depth_m: 2.125,
        sigma_m: 0.0061,
        patches: 700,
    }];
    let page = SensorChoice::resolve(None, Some(MaskBorders::Exact), None, Some(noisy)).markdown();
    assert!(
        page.contains("depth: **Camera** (probe), masks: **Exact** (flag), ids: **PerFrame** (probe)"),
        "{page}"
    );
    assert!(
        page.contains("σ at 2 m 6.0 mm") && page.contains("range 5.00 m"),
        "{page}"
    );
    assert!(page.contains("| 2.12 | 6.10 | 700 |"), "{page}");
    let flags = SensorChoice::resolve(
        Some(DepthImages::Exact),
        Some(MaskBorders::Exact),
        Some(InstanceSource::Consistent),
        None,
    )
    .markdown();
    assert!(!flags.contains("Probe"), "{flags}");
}

#[test]
fn probe_positions_spread_over_the_stream() {
    assert_eq!(probe_positions(5, 12), vec![0, 1, 2, 3, 4]);
    assert_eq!(probe_positions(100, 5), vec![0, 24, 49, 74, 99]);
    assert_eq!(probe_positions(100, 1), vec![0]);
    assert_eq!(probe_positions(0, 12), Vec::<usize>::new());
}
