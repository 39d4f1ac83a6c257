//! Dataset readers on tiny fixtures written to temporary folders: what a good sequence decodes to,
//! and, for each kind of bad input, an error that names the file (and line) and the reason.

use std::path::Path;

use catmap::dataset::FrameSource;
use catmap::dataset::camera_spec::parse_camera_spec;
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::scannet::{ScanNetOptions, ScanNetSequence};
use catmap::{CameraIntrinsics, CatmapError, ClassId, FrameIndex, InstanceLabel, ObjectId};
use tempfile::TempDir;

use crate::common::{assert_mentions, pixel, write_grey8, write_grey16, write_rgb};

const W: u32 = 32;
const H: u32 = 24;
const CHAIR: u32 = 20;
const TABLE: u32 = 80;
const FLOOR: u32 = 40;

/// Replica scene: a chair (instance 3) and a table (instance 9) over a floor strip whose
/// instance id (5) must be merged into the background; depth 1 m + 1 cm per column, with an
/// invalid pixel at (0, 0) and a too-far one (9 m) at (31, 0).
fn replica_class(u: u32, v: u32) -> (u32, u32) {
    match (u, v) {
        (_, 18..) => (FLOOR, 5),
        (2..10, 2..10) => (CHAIR, 3),
        (16..28, 4..14) => (TABLE, 9),
        _ => (0, 0),
    }
}

/// Pose of frame `i`: a rotation of 0.1·i rad about z and a translation (i, 2i, 0.5).
fn replica_pose_line(i: usize) -> String {
    let (s, c) = (0.1 * i as f64).sin_cos();
    let (x, y) = (i as f64, 2.0 * i as f64);
    format!("{c} {} 0 {x} {s} {c} 0 {y} 0 0 1 0.5 0 0 0 1", -s)
}

fn replica_fixture(frames: usize) -> TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path();
    for i in 0..frames {
        write_rgb(&root.join(format!("rgb/rgb_{i}.png")), (W, H), |u, v| {
            [u as u8 * 8, v as u8 * 10, i as u8]
        });
        write_grey16(&root.join(format!("depth/depth_{i}.png")), (W, H), |u, v| {
            match (u, v) {
                (0, 0) => 0,
                (31, 0) => 9000,
                _ => 1000 + 10 * u as u16,
            }
        });
        write_grey8(
            &root.join(format!("semantic_class/semantic_class_{i}.png")),
            (W, H),
            |u, v| replica_class(u, v).0 as u8,
        );
        write_grey16(
            &root.join(format!("semantic_instance/semantic_instance_{i}.png")),
            (W, H),
            |u, v| replica_class(u, v).1 as u16,
        );
    }
    let traj: Vec<String> = (0..frames).map(replica_pose_line).collect();
    std::fs::write(root.join("traj_w_c.txt"), traj.join("\n") + "\n").expect("write traj");
    let json = r#"{"width": 32, "height": 24, "fx": 20.0, "fy": 21.0, "cx": 15.5, "cy": 11.5, "depth_scale": 1000.0}"#;
    std::fs::write(root.join("intrinsics.json"), json).expect("write intrinsics");
    dir
}

fn open_replica(dir: &Path) -> Result<ReplicaSequence, CatmapError> {
    ReplicaSequence::open(dir, &ReplicaOptions::default())
}

#[test]
fn a_replica_frame_decodes_metric_depth_merged_background_objects_and_pose() {
    let dir = replica_fixture(3);
    let sequence = open_replica(dir.path()).expect("valid sequence");
    assert_eq!(sequence.len(), 3);
    let frame = sequence.read_frame(2).expect("frame 2 decodes");
    frame.validate().expect("all images have the camera's size");

    assert_eq!(frame.index, FrameIndex(2));
    assert_eq!(frame.depth_m[pixel(&frame, 5, 3)], 1.05, "1050 mm is 1.05 m");
    assert_eq!(frame.depth_m[pixel(&frame, 0, 0)], 0.0, "0 stays invalid");
    assert_eq!(
        frame.depth_m[pixel(&frame, 31, 0)],
        0.0,
        "9 m is beyond max_depth_m = 8 m"
    );
    assert_eq!(frame.rgb[pixel(&frame, 3, 2)], [24, 20, 2]);
    assert_eq!(
        frame.instances.label(pixel(&frame, 4, 4)),
        InstanceLabel::Object(ObjectId(3)),
        "chair"
    );
    assert_eq!(
        frame.instances.label(pixel(&frame, 20, 6)),
        InstanceLabel::Object(ObjectId(9)),
        "table"
    );
    let floor = pixel(&frame, 5, 20);
    assert_eq!(
        frame.instances.label(floor),
        InstanceLabel::Background,
        "floor instance 5 is background"
    );
    assert_eq!(frame.classes[floor], ClassId(FLOOR), "the class survives the merge");
    assert_eq!(
        frame.instances.label(pixel(&frame, 12, 15)),
        InstanceLabel::Background,
        "instance 0"
    );

    let pose = frame.world_from_camera;
    assert!((pose.translation.vector - nalgebra::Vector3::new(2.0, 4.0, 0.5)).norm() < 1e-6);
    let (axis, angle) = pose.rotation.axis_angle().expect("frame 2 is rotated");
    assert!(
        (angle - 0.2).abs() < 1e-5 && (axis.z - 1.0).abs() < 1e-5,
        "0.2 rad about z"
    );
}

#[test]
fn replica_intrinsics_come_from_the_camera_spec_then_the_json_then_the_default() {
    let dir = replica_fixture(1);
    let spec = parse_camera_spec("32,24,30,31,16,12").expect("valid spec");
    let options = ReplicaOptions {
        camera: Some(spec),
        ..ReplicaOptions::default()
    };
    let with_spec = ReplicaSequence::open(dir.path(), &options).expect("opens");
    assert_eq!(
        with_spec.intrinsics(),
        spec,
        "the camera spec wins over intrinsics.json"
    );

    let json = CameraIntrinsics {
        width: 32,
        height: 24,
        fx: 20.0,
        fy: 21.0,
        cx: 15.5,
        cy: 11.5,
    };
    assert_eq!(
        open_replica(dir.path()).expect("opens").intrinsics(),
        json,
        "then intrinsics.json"
    );

    std::fs::remove_file(dir.path().join("intrinsics.json")).expect("remove json");
    let default = open_replica(dir.path()).expect("opens");
    assert_eq!(default.intrinsics(), CameraIntrinsics::REPLICA, "then Replica's camera");
    let err = default
        .read_frame(0)
        .expect_err("32×24 images do not match the 1200×680 camera");
    assert_mentions(&err, &["depth_0.png", "32×24", "1200×680", "intrinsics"]);
}

#[test]
fn a_one_frame_sequence_works() {
    let dir = replica_fixture(1);
    let sequence = open_replica(dir.path()).expect("opens");
    assert_eq!(sequence.len(), 1);
    sequence.read_frame(0).expect("decodes");
    let err = sequence.read_frame(1).expect_err("position 1 is out of range");
    assert_mentions(&err, &["out of range", "1 frames"]);
}

#[test]
fn empty_masks_give_a_frame_without_objects() {
    let dir = replica_fixture(1);
    let root = dir.path();
    write_grey8(&root.join("semantic_class/semantic_class_0.png"), (W, H), |_, _| 0);
    write_grey16(
        &root.join("semantic_instance/semantic_instance_0.png"),
        (W, H),
        |_, _| 0,
    );
    let frame = open_replica(root).expect("opens").read_frame(0).expect("decodes");
    assert!(
        (0..frame.instances.len()).all(|i| frame.instances.object_at(i).is_none()),
        "no objects"
    );
}

#[test]
fn a_missing_folder_is_named() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("no_such_scene");
    let err = open_replica(&missing).expect_err("no folder");
    assert_mentions(&err, &["no_such_scene", "does not exist"]);
    let err = ScanNetSequence::open(&missing, &ScanNetOptions::default()).expect_err("no folder");
    assert_mentions(&err, &["no_such_scene", "does not exist"]);
}

#[test]
fn a_missing_rgb_file_fails_that_frame_only() {
    let dir = replica_fixture(3);
    std::fs::remove_file(dir.path().join("rgb/rgb_1.png")).expect("remove rgb");
    let sequence = open_replica(dir.path()).expect("opening does not read images");
    let err = sequence.read_frame(1).expect_err("rgb_1.png is missing");
    assert!(matches!(err, CatmapError::Io { .. }), "an I/O error: {err}");
    assert_mentions(&err, &["rgb_1.png", "No such file"]);
    sequence.read_frame(2).expect("other frames still decode");
}

#[test]
fn a_corrupt_png_is_an_image_error_naming_the_file() {
    let dir = replica_fixture(2);
    let mut state = 0x2545_f491_u32; // seeded xorshift: random-looking bytes, same every run
    let noise: Vec<u8> = (0..512)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as u8
        })
        .collect();
    std::fs::write(dir.path().join("depth/depth_1.png"), &noise).expect("write noise");
    let sequence = open_replica(dir.path()).expect("opens");
    let err = sequence.read_frame(1).expect_err("noise is not a PNG");
    assert_mentions(&err, &["depth_1.png", "bad image"]);

    let good = std::fs::read(dir.path().join("semantic_instance/semantic_instance_0.png")).expect("read");
    let truncated = dir.path().join("semantic_instance/semantic_instance_0.png");
    std::fs::write(&truncated, &good[..good.len() / 2]).expect("truncate");
    let err = sequence.read_frame(0).expect_err("a truncated PNG does not decode");
    assert_mentions(&err, &["semantic_instance_0.png", "bad image"]);
}

#[test]
fn an_rgb_image_of_another_size_than_depth_is_rejected() {
    let dir = replica_fixture(1);
    write_rgb(&dir.path().join("rgb/rgb_0.png"), (16, 12), |_, _| [1, 2, 3]);
    let err = open_replica(dir.path())
        .expect("opens")
        .read_frame(0)
        .expect_err("16×12 rgb");
    assert_mentions(&err, &["rgb_0.png", "16×12", "32×24", "depth"]);
}

fn replica_with_traj(line: usize, text: &str) -> CatmapError {
    let dir = replica_fixture(3);
    let mut lines: Vec<String> = (0..3).map(replica_pose_line).collect();
    lines[line] = text.to_owned();
    std::fs::write(dir.path().join("traj_w_c.txt"), lines.join("\n")).expect("write traj");
    open_replica(dir.path()).expect_err("the trajectory is malformed")
}

#[test]
fn a_non_numeric_pose_is_reported_with_file_and_line() {
    let err = replica_with_traj(1, "1 0 0 abc 0 1 0 0 0 0 1 0 0 0 0 1");
    assert!(matches!(err, CatmapError::Parse { line: 2, .. }), "{err}");
    assert_mentions(&err, &["traj_w_c.txt:2:", "\"abc\" is not a number"]);
}

#[test]
fn a_pose_line_with_fifteen_numbers_is_reported() {
    let err = replica_with_traj(2, "1 0 0 0 0 1 0 0 0 0 1 0 0 0 0");
    assert_mentions(&err, &["traj_w_c.txt:3:", "expected 16 numbers, found 15"]);
}

#[test]
fn a_nan_pose_fails_at_open() {
    let err = replica_with_traj(0, "NaN 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1");
    assert_mentions(&err, &["traj_w_c.txt:1:", "NaN"]);
}

#[test]
fn a_trajectory_shorter_than_the_depth_frames_fails_at_open() {
    let dir = replica_fixture(3);
    let two: Vec<String> = (0..2).map(replica_pose_line).collect();
    std::fs::write(dir.path().join("traj_w_c.txt"), two.join("\n") + "\n\n").expect("write traj");
    let err = open_replica(dir.path()).expect_err("frame 2 has no pose");
    assert_mentions(&err, &["traj_w_c.txt:3:", "depth_2.png", "only 2 poses"]);

    std::fs::remove_file(dir.path().join("traj_w_c.txt")).expect("remove traj");
    assert_mentions(&open_replica(dir.path()).expect_err("no trajectory"), &["traj_w_c.txt"]);
}

// ScanNet: 48×36 depth (28×16 after the 10-px crop), 96×72 colour and labels, frames 2, 10, 1
