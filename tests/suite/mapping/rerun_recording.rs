//! The recording a run writes decodes with Rerun's own decoder and holds the camera, its images,
//! every object's cloud, box, field loss and mesh, and the viewer layout.

use std::collections::BTreeSet;
use std::ops::ControlFlow;

use catmap::MapperConfig;
use catmap::dataset::FrameSource;
use catmap::synth::{Preset, SyntheticScene};
use catmap_systems::blueprint::titles;
use catmap_systems::rrd_file::{RrdFooter, save_rrd};
use catmap_systems::{Mapper, RunOutcome};
use re_log_encoding::DecoderApp;
use re_log_types::LogMsg;

/// What an .rrd file holds: the recording's entity paths (without the leading slash), and the
/// blueprint's chunks printed as tables.
struct Decoded {
    paths: BTreeSet<String>,
    blueprint: Vec<String>,
}

fn decode(path: &std::path::Path) -> Decoded {
    let file = std::fs::File::open(path).expect("the recording exists");
    let mut decoded = Decoded {
        paths: BTreeSet::new(),
        blueprint: Vec::new(),
    };
    for message in DecoderApp::decode_lazy(std::io::BufReader::new(file)) {
        if let LogMsg::ArrowMsg(store, arrow) = message.expect("every message decodes") {
            let chunk = re_chunk::Chunk::from_arrow_msg(&arrow).expect("every message is a chunk");
            if store.is_blueprint() {
                decoded.blueprint.push(chunk.to_string());
            } else {
                decoded
                    .paths
                    .insert(chunk.entity_path().to_string().trim_start_matches('/').to_owned());
            }
        }
    }
    decoded
}

/// Entity paths of the recording in an .rrd file, without the leading slash.
fn entity_paths(path: &std::path::Path) -> BTreeSet<String> {
    decode(path).paths
}

#[test]
fn a_saved_recording_holds_camera_images_and_object_entities() {
    let dir = tempfile::tempdir().expect("temp dir");
    let rrd = dir.path().join("recording.rrd");
    let scene = SyntheticScene::generate(5, Preset::Small).expect("scene");
    {
        let rec = rerun::RecordingStreamBuilder::new("catmap_test")
            .save(&rrd)
            .expect("open the recording file");
        let mut config = MapperConfig {
            seed: 5,
            ..MapperConfig::default()
        };
        // Cheap training: enough to log losses and a preview mesh or two.
        config.fields.steps_per_frame = 1;
        // The background field is off by default; its loss is logged when it is on.
        config.fields.background_every = 10;
        config.meshes.preview_every_frames = 10;
        config.meshes.preview_voxel_m = 0.05;
        // A short category phase: chairs share one field (with these weak fields one chair may
        // be split off into its own subcategory).
        config.categories.min_field_steps = 1;
        config.category_fields.enabled = true;
        // The default (fast) schedule: one short phase after the stream trains every field.
        config.schedule.max_steps_after_stream = 20;
        let mut mapper = Mapper::new(config).expect("config");
        mapper.set_recording(rec);
        for position in 0..scene.len() {
            mapper.push(scene.read_frame(position).expect("frame")).expect("push");
            mapper.step().expect("a tick");
        }
        mapper.end_stream().expect("a tick");
        mapper.step().expect("a tick");
        assert_eq!(
            mapper.run(|_| ControlFlow::Continue(())).expect("the run"),
            RunOutcome::Complete
        );
        assert_eq!(mapper.category_field_count(), 1, "one category field");
        let meshes = mapper.extract_final_meshes().expect("final meshes");
        assert!(meshes.background.is_some(), "the background field is meshed at the end");
        let map = mapper.finish();
        assert!(map.objects.len() >= 3, "the small scene maps several objects");
    }
    let Decoded { paths, blueprint } = decode(&rrd);
    for expected in [
        "world",
        "world/camera",
        "world/camera/image",
        "world/camera/image/rgb",
        "world/camera/image/depth",
        "training/loss/categories/0",
        "world/camera/image/instances",
    ] {
        assert!(paths.contains(expected), "{expected} missing from {paths:?}");
    }
    let objects_with_points = paths
        .iter()
        .filter(|p| p.starts_with("world/objects/") && p.ends_with("/points"))
        .count();
    let objects_with_boxes = paths
        .iter()
        .filter(|p| p.starts_with("world/objects/") && p.ends_with("/box"))
        .count();
    assert!(objects_with_points >= 3, "object clouds are logged: {paths:?}");
    assert!(objects_with_boxes >= 3, "object boxes are logged: {paths:?}");
    let with_suffix = |suffix: &str| {
        paths
            .iter()
            .filter(|p| p.starts_with("world/objects/") && p.ends_with(suffix))
            .count()
    };
    let series = |quantity: &str| {
        paths
            .iter()
            .filter(|p| p.starts_with(&format!("training/{quantity}/objects/")))
            .count()
    };
    assert!(series("loss") >= 3, "field losses are logged: {paths:?}");
    assert!(series("steps") >= 3, "field steps are logged: {paths:?}");
    assert!(with_suffix("/mesh") >= 3, "preview meshes are logged: {paths:?}");
    assert!(
        series("shape_code_norm") >= 2,
        "the members' code norms are logged: {paths:?}"
    );
    assert!(
        series("texture_code_norm") >= 2,
        "the members' code norms are logged: {paths:?}"
    );
    assert!(
        paths.contains("training/loss/background"),
        "the background's loss is logged"
    );
    // The viewer layout: its views, by title, kind and origin (a chunk prints as a table with
    // a `[value]` cell per component).
    let layout = blueprint.join("\n");
    for (title, kind, origin) in [
        (titles::MAP, "3D", "/world"),
        (titles::CATEGORIES, "3D", "/world/objects"),
        (titles::CAMERA, "2D", "/world/camera/image"),
        (titles::LOSS, "TimeSeries", "/training/loss"),
        (titles::STEPS, "TimeSeries", "/training/steps"),
        (titles::CARVING, "TimeSeries", "/training/carving_share"),
        (titles::STREAM, "TimeSeries", "/stream"),
        (titles::SENSOR, "TextDocument", "/sensor"),
    ] {
        let view = blueprint
            .iter()
            .find(|chunk| chunk.contains("ViewBlueprint:display_name") && chunk.contains(&format!("[{title}]")))
            .unwrap_or_else(|| panic!("no view titled {title} in the blueprint:\n{layout}"));
        assert!(view.contains(&format!("[{kind}]")), "{title} is a {kind} view:\n{view}");
        assert!(view.contains(&format!("[{origin}]")), "{title} shows {origin}:\n{view}");
    }
    assert!(
        paths.contains("world/background/mesh"),
        "the final meshes are logged (the background is only meshed at the end): {paths:?}"
    );
}

/// Maps the first ten frames of a small scene (no fields) into a recording saved with `footer`;
/// returns the file's bytes and entity paths.
fn record_ten_frames(footer: RrdFooter) -> (Vec<u8>, BTreeSet<String>) {
    let dir = tempfile::tempdir().expect("temp dir");
    let rrd = dir.path().join("recording.rrd");
    let scene = SyntheticScene::generate(5, Preset::Small).expect("scene");
    {
        let builder = rerun::RecordingStreamBuilder::new("catmap_test");
        let config = MapperConfig {
            fields: catmap::config::FieldConfig::disabled(),
            ..MapperConfig::default()
        };
        let mut mapper = Mapper::new(config).expect("config");
        mapper.set_recording(save_rrd(builder, &rrd, footer).expect("open the recording file"));
        for position in 0..10 {
            mapper.push(scene.read_frame(position).expect("frame")).expect("push");
            mapper.step().expect("a tick");
        }
        mapper.finish();
    }
    let bytes = std::fs::read(&rrd).expect("the recording exists");
    (bytes, entity_paths(&rrd))
}

/// Whether an .rrd file ends with Rerun's stream footer (fourcc `RRF2`, identifier `FOOT`).
fn has_stream_footer(bytes: &[u8]) -> bool {
    let tail = &bytes[bytes.len().saturating_sub(256)..];
    tail.windows(8).any(|w| w == b"RRF2FOOT")
}

#[test]
fn a_long_stream_recording_without_its_chunk_index_still_holds_every_entity() {
    // Issue 6 (long stream): Rerun's chunk index grew in memory by ≈ 15 MiB per 1 000 frames.
    let (indexed, indexed_paths) = record_ten_frames(RrdFooter::Indexed);
    let (omitted, omitted_paths) = record_ten_frames(RrdFooter::Omitted);
    assert!(has_stream_footer(&indexed), "a bounded stream keeps the chunk index");
    assert!(
        !has_stream_footer(&omitted),
        "a long stream is saved without the chunk index"
    );
    assert_eq!(omitted_paths, indexed_paths, "both files hold the same entities");
    assert!(
        omitted_paths.contains("world/camera/image/rgb"),
        "the footer-less file decodes: {omitted_paths:?}"
    );
}
