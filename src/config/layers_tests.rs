use super::*;
use crate::config::sensor_profile::ChosenBy;
use crate::objects::config::MaskBorders;
use crate::objects::instance_association::InstanceSource;
use crate::sensor::depth_smoothing::DepthImages;

fn table(text: &str) -> toml::Table {
    toml::from_str(text).expect("a TOML table")
}

fn camera_and_segmenter() -> SensorChoice {
    SensorChoice {
        depth: DepthImages::Camera,
        depth_chosen_by: ChosenBy::Probe,
        masks: MaskBorders::Segmenter,
        masks_chosen_by: ChosenBy::Probe,
        instances: InstanceSource::PerFrame,
        instances_chosen_by: ChosenBy::Probe,
        profile: None,
    }
}

#[test]
fn no_layers_resolve_to_the_fast_profile_and_a_named_schedule_to_its_profile() {
    assert_eq!(
        SettingsLayers::default().resolve().expect("valid"),
        MapperConfig::fast()
    );
    let paper_flag = SettingsLayers {
        flags: table("schedule.policy = \"paper\""),
        ..SettingsLayers::default()
    };
    assert_eq!(paper_flag.resolve().expect("valid"), MapperConfig::paper());
    let paper_file = SettingsLayers {
        file: table("[schedule]\npolicy = \"paper\""),
        ..SettingsLayers::default()
    };
    assert_eq!(paper_file.resolve().expect("valid"), MapperConfig::paper());
    let flag_wins = SettingsLayers {
        file: table("[schedule]\npolicy = \"paper\""),
        flags: table("schedule.policy = \"fast\""),
        ..SettingsLayers::default()
    };
    assert_eq!(flag_wins.resolve().expect("valid"), MapperConfig::fast());
}

#[test]
fn the_offline_protocol_starts_from_the_paper_profile() {
    let offline = SettingsLayers {
        flags: table("fields.offline = true"),
        ..SettingsLayers::default()
    };
    assert_eq!(offline.profile().expect("valid"), SchedulePolicy::Paper);
    let resolved = offline.resolve().expect("valid");
    assert!(resolved.fields.offline);
    assert_eq!(resolved.fields.object_rays, MapperConfig::paper().fields.object_rays);
    assert_eq!(resolved.meshes.object.occupancy_level, 0.5);
}

#[test]
fn the_file_keeps_what_it_sets_over_the_sensors_settings_and_the_flags_win_over_both() {
    let sensor = camera_and_segmenter();
    let probed = SettingsLayers {
        sensor: Some(sensor.clone()),
        ..SettingsLayers::default()
    }
    .resolve()
    .expect("valid");
    assert_eq!(
        probed,
        sensor.apply(MapperConfig::fast()),
        "the sensor over the profile"
    );
    assert_eq!(probed.dataset.depth_noise_per_m2, 0.0025);
    assert_eq!(probed.objects.association.instances, InstanceSource::PerFrame);
    let layers = SettingsLayers {
        sensor: Some(sensor),
        file: table("seed = 4\n[dataset]\ndepth_noise_per_m2 = 0.001\n[objects]\nmask_border_px = 0\n"),
        flags: table("seed = 9"),
    };
    let resolved = layers.resolve().expect("valid");
    assert_eq!(
        resolved.dataset.depth_noise_per_m2, 0.001,
        "the file's, not the camera's"
    );
    assert_eq!(resolved.objects.mask_border_px, 0, "the file's, not the segmenter's");
    assert_eq!(
        resolved.dataset.depth_smoothing, probed.dataset.depth_smoothing,
        "the camera's"
    );
    assert_eq!(resolved.seed, 9, "the flag's, not the file's");
}

#[test]
fn a_bad_value_in_any_layer_is_an_error_naming_the_key() {
    let bad_policy = SettingsLayers {
        flags: table("schedule.policy = \"slow\""),
        ..SettingsLayers::default()
    };
    let err = bad_policy.resolve().expect_err("no such schedule");
    assert!(
        matches!(&err, CatmapError::ConfigValue(m) if m.contains("schedule.policy")),
        "{err}"
    );
    let bad_stride = SettingsLayers {
        flags: table("stream.stride = 0"),
        ..SettingsLayers::default()
    };
    let err = bad_stride.resolve().expect_err("stride 0");
    assert!(
        matches!(&err, CatmapError::ConfigValue(m) if m.contains("stream.stride")),
        "{err}"
    );
    let unknown = SettingsLayers {
        file: table("[stream]\nstrides = 2"),
        ..SettingsLayers::default()
    };
    let err = unknown.resolve().expect_err("no such key");
    assert!(
        matches!(&err, CatmapError::ConfigSyntax(m) if m.contains("strides")),
        "an unknown key is a syntax error naming it: {err}"
    );
}

#[test]
fn set_and_lookup_walk_dotted_keys() {
    let mut t = toml::Table::new();
    set(&mut t, "a.b.c", 3);
    set(&mut t, "a.d", "x");
    set(&mut t, "e", true);
    assert_eq!(t, table("e = true\n[a]\nd = \"x\"\n[a.b]\nc = 3\n"));
    assert_eq!(lookup(&t, "a.b.c"), Some(&toml::Value::Integer(3)));
    assert_eq!(lookup(&t, "a.b.x"), None);
    assert_eq!(lookup(&t, "e.f"), None, "a leaf has no keys");
}
