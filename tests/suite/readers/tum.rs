//! The TUM RGB-D reader on a tiny fixture written to a temporary folder: association by nearest
//! timestamp, skipped colour images, poses, depth in TUM's units, 8- and 16-bit masks, the
//! camera's sources, errors that name the file and line; and a synthetic scene written in TUM's
//! layout read back as the scene's own frames.

use std::path::Path;

use catmap::dataset::FrameSource;
use catmap::dataset::tum::{SkippedImages, TumOptions, TumSequence};
use catmap::synth::{Preset, SyntheticScene, write_tum_layout};
use catmap::{CameraIntrinsics, ClassId, FrameIndex, InstanceLabel, ObjectId};
use nalgebra::Vector3;
use tempfile::TempDir;

use crate::common::{assert_mentions, pixel, write_grey8, write_grey16, write_rgb};

const SIZE: (u32, u32) = (16, 12);

/// `(class, instance)` at `(u, v)`: a chair (class 20, instance 7) on a floor (class 40, instance
/// 2) and a chair-class pixel of no instance.
fn labels(u: u32, v: u32) -> (u8, u16) {
    match (u, v) {
        (_, 9..) => (40, 2),
        (3..11, 2..=7) => (20, 7),
        (0, 0) => (20, 0),
        _ => (0, 0),
    }
}

/// Six colour images at ~30 Hz: 10.000 and 10.033 make frames; 10.066 has no depth image within
/// 0.02 s; 10.100 no pose; 10.133 no masks; 10.166 (a JPEG with 8-bit masks) makes a frame.
fn tum_fixture() -> TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path();
    let stamps = [
        "10.000000",
        "10.033000",
        "10.066000",
        "10.100000",
        "10.133000",
        "10.166000",
    ];
    let mut rgb_txt = "# color images\n# file: 'fixture.bag'\n# timestamp filename\n".to_owned();
    for (k, stamp) in stamps.iter().enumerate() {
        let name = if k == 5 {
            format!("rgb/{stamp}.jpg")
        } else {
            format!("rgb/{stamp}.png")
        };
        rgb_txt += &format!("{stamp} {name}\n");
        write_rgb(&root.join(&name), SIZE, |u, v| [u as u8 * 9, v as u8 * 11, k as u8]);
        if k == 4 {
            continue;
        }
        if k == 5 {
            write_grey8(&root.join(format!("instance/{stamp}.png")), SIZE, |u, v| {
                labels(u, v).1 as u8
            });
        } else {
            write_grey16(&root.join(format!("instance/{stamp}.png")), SIZE, |u, v| labels(u, v).1);
        }
        write_grey8(&root.join(format!("class/{stamp}.png")), SIZE, |u, v| labels(u, v).0);
    }
    let mut depth_txt = "# depth maps\n".to_owned();
    for stamp in ["10.004000", "10.037000", "10.104000", "10.137000", "10.170000"] {
        depth_txt += &format!("{stamp} depth/{stamp}.png\n");
        write_grey16(&root.join(format!("depth/{stamp}.png")), SIZE, |u, v| match (u, v) {
            (15, 11) => 60_000, // 12 m: beyond the 8 m range
            _ => 5000 + 50 * u as u16,
        });
    }
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let groundtruth = format!(
        "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n\
         9.998 1 2 3 0 0 0 1\n10.031 0 0 0.5 0 0 {h} {h}\n10.131 0 0 0 0 0 0 1\n10.164 5 0 0 0 0 0 1\n"
    );
    std::fs::write(root.join("rgb.txt"), rgb_txt).expect("rgb.txt");
    std::fs::write(root.join("depth.txt"), depth_txt).expect("depth.txt");
    std::fs::write(root.join("groundtruth.txt"), groundtruth).expect("groundtruth.txt");
    let json = r#"{"width": 16, "height": 12, "fx": 12.0, "fy": 12.5, "cx": 7.5, "cy": 5.5}"#;
    std::fs::write(root.join("intrinsics.json"), json).expect("intrinsics.json");
    dir
}

#[test]
fn tum_frames_are_colour_images_with_the_nearest_depth_and_pose_and_unmatched_ones_are_skipped() {
    let dir = tum_fixture();
    let sequence = TumSequence::open(dir.path(), &TumOptions::default()).expect("valid sequence");
    assert_eq!(
        sequence.skipped(),
        SkippedImages {
            no_depth: 1,
            no_pose: 1,
            no_mask: 1
        },
        "10.066 has no depth image, 10.100 no pose, 10.133 no masks"
    );
    assert_eq!(sequence.len(), 3, "three of six colour images make frames");
    assert_eq!(
        sequence.depth_scale(),
        5000.0,
        "TUM's units without a depth_scale in intrinsics.json"
    );
    assert_eq!(sequence.timestamp_s(1), Some(10.033));

    let frame = sequence.read_frame(1).expect("frame of 10.033 decodes");
    frame.validate().expect("all images have the camera's size");
    assert_eq!(frame.index, FrameIndex(1), "the second colour image");
    let pose = frame.world_from_camera;
    assert_eq!(
        pose.translation.vector,
        Vector3::new(0.0, 0.0, 0.5),
        "the pose of 10.031"
    );
    assert!(
        (pose.rotation * Vector3::x() - Vector3::y()).norm() < 1e-6,
        "a quarter turn about z"
    );
    assert!(
        (frame.depth_m[pixel(&frame, 0, 0)] - 1.0).abs() < 1e-6,
        "5000 units are 1 m"
    );
    assert!(
        (frame.depth_m[pixel(&frame, 4, 0)] - 1.04).abs() < 1e-6,
        "50 units a column"
    );
    assert_eq!(
        frame.depth_m[pixel(&frame, 15, 11)],
        0.0,
        "12 m is beyond the 8 m range"
    );
    assert_eq!(
        frame.rgb[pixel(&frame, 2, 3)],
        [18, 33, 1],
        "the colour image of 10.033"
    );
    let label = |u, v| frame.instances.label(pixel(&frame, u, v));
    assert_eq!(label(5, 4), InstanceLabel::Object(ObjectId(7)), "the chair");
    assert_eq!(label(5, 10), InstanceLabel::Background, "the floor class is background");
    assert_eq!(label(0, 0), InstanceLabel::Background, "instance 0 is none");
    assert_eq!(frame.classes[pixel(&frame, 5, 4)], ClassId(20));

    let jpeg = sequence.read_frame(2).expect("frame of 10.166 decodes");
    assert_eq!(
        jpeg.index,
        FrameIndex(5),
        "skipped colour images leave gaps in the indices"
    );
    assert_eq!(jpeg.world_from_camera.translation.x, 5.0, "the pose of 10.164");
    let chair = jpeg.instances.label(pixel(&jpeg, 5, 4));
    assert_eq!(chair, InstanceLabel::Object(ObjectId(7)), "an 8-bit instance mask");
    assert_eq!(sequence.class_names().name(ClassId(20)), "chair", "Replica's names");
}

#[test]
fn without_intrinsics_json_the_camera_must_be_given_and_a_depth_scale_there_is_used() {
    let dir = tum_fixture();
    std::fs::remove_file(dir.path().join("intrinsics.json")).expect("no intrinsics.json");
    let err = TumSequence::open(dir.path(), &TumOptions::default()).expect_err("no camera at all");
    assert_mentions(
        &err,
        &[
            "intrinsics.json",
            "no --camera",
            "TUM RGB-D ships no intrinsics",
            "--camera W,H",
        ],
    );
    let camera = CameraIntrinsics {
        width: 16,
        height: 12,
        fx: 12.0,
        fy: 12.0,
        cx: 7.5,
        cy: 5.5,
    };
    let options = TumOptions {
        camera: Some(camera),
        ..TumOptions::default()
    };
    let sequence = TumSequence::open(dir.path(), &options).expect("the camera from the command line");
    assert_eq!(sequence.intrinsics(), camera);
    let json = r#"{"width": 16, "height": 12, "fx": 12.0, "fy": 12.5, "cx": 7.5, "cy": 5.5, "depth_scale": 1000}"#;
    std::fs::write(dir.path().join("intrinsics.json"), json).expect("intrinsics.json");
    let sequence = TumSequence::open(dir.path(), &TumOptions::default()).expect("millimetres");
    let frame = sequence.read_frame(0).expect("frame");
    assert!((frame.depth_m[0] - 5.0).abs() < 1e-6, "5000 units of 1 mm are 5 m");
}

#[test]
fn bad_tum_lists_and_images_are_errors_naming_the_file_and_line() {
    let dir = tum_fixture();
    let open = || TumSequence::open(dir.path(), &TumOptions::default());
    let depth_txt = std::fs::read_to_string(dir.path().join("depth.txt")).expect("depth.txt");
    std::fs::write(
        dir.path().join("depth.txt"),
        depth_txt.replace("10.104000 depth", "10.1o4 depth"),
    )
    .expect("a typo");
    assert_mentions(
        &open().expect_err("a typo"),
        &["depth.txt:4:", "\"10.1o4\" is not a number"],
    );
    std::fs::write(dir.path().join("depth.txt"), depth_txt).expect("depth.txt restored");

    std::fs::remove_file(dir.path().join("rgb/10.033000.png")).expect("a listed image gone");
    assert_mentions(
        &open().expect_err("a listed image is missing"),
        &["rgb.txt:5:", "rgb/10.033000.png is not a file"],
    );
    write_rgb(&dir.path().join("rgb/10.033000.png"), SIZE, |_, _| [0; 3]);

    write_grey16(&dir.path().join("instance/10.033000.png"), (8, 6), |_, _| 1);
    let sequence = open().expect("sizes are checked per frame");
    assert_mentions(
        &sequence.read_frame(1).expect_err("a mask of the wrong size"),
        &["instance/10.033000.png", "is 8×6 pixels", "rgb.txt line 5"],
    );

    std::fs::write(dir.path().join("groundtruth.txt"), "# nothing near\n0 0 0 0 0 0 0 1\n").expect("poses");
    assert_mentions(
        &open().expect_err("no frame"),
        &[
            "rgb.txt",
            "no colour image makes a frame",
            "5 no pose within 0.02 s in groundtruth.txt",
        ],
    );
    let missing = Path::new("no-such-sequence");
    assert_mentions(
        &TumSequence::open(missing, &TumOptions::default()).expect_err("no folder"),
        &[
            "no-such-sequence",
            "does not exist",
            "rgb.txt, depth.txt and groundtruth.txt",
        ],
    );
}

#[test]
fn a_synthetic_scene_written_in_tums_layout_reads_back_as_its_own_frames() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = SyntheticScene::generate(1, Preset::Small).expect("small scene");
    write_tum_layout(&scene, dir.path(), |_, _| {}).expect("written");
    let sequence = TumSequence::open(dir.path(), &TumOptions::default()).expect("TUM layout");
    assert_eq!(sequence.len(), scene.len(), "every frame associated");
    assert_eq!(sequence.skipped(), SkippedImages::default());
    assert_eq!(sequence.intrinsics(), scene.intrinsics());
    for position in [0, scene.len() - 1] {
        let (read, truth) = (
            sequence.read_frame(position).expect("frame"),
            scene.read_frame(position).expect("rendered"),
        );
        assert_eq!(read.index, truth.index);
        let pose_error = read.world_from_camera.inverse() * truth.world_from_camera;
        assert!(
            pose_error.translation.vector.norm() < 1e-5 && pose_error.rotation.angle() < 1e-5,
            "the pose of frame {position}: {pose_error:?}"
        );
        assert_eq!(read.rgb, truth.rgb);
        assert_eq!(read.classes, truth.classes);
        assert_eq!(read.instances, truth.instances, "masks of frame {position}");
        // Depth beyond the reader's 8 m range reads as invalid.
        let expected = |truth: f32| if truth <= 8.0 { truth } else { 0.0 };
        let worst = read
            .depth_m
            .iter()
            .zip(&truth.depth_m)
            .map(|(&a, &b)| (a - expected(b)).abs())
            .fold(0.0f32, f32::max);
        assert!(worst <= 1.01e-4, "depth within half of TUM's 0.2 mm unit: {worst}");
    }
}
