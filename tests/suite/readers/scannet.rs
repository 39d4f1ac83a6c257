//! The ScanNet reader on tiny fixtures written to temporary folders: sorting, cropping, skipped
//! poses, and errors that name the file (and line) and the reason; and a synthetic scene written in
//! ScanNet's layout read back as the scene's own frames.

use catmap::dataset::FrameSource;
use catmap::dataset::scannet::{ScanNetOptions, ScanNetSequence};
use catmap::{CameraIntrinsics, ClassId, FrameIndex, InstanceLabel, ObjectId};
use tempfile::TempDir;

use crate::common::{assert_mentions, pixel, write_grey8, write_grey16, write_rgb};

// and 5, where 5 has lost tracking.
const SW: u32 = 48;
const SH: u32 = 36;

/// `(instance, label)` at depth pixel `(u, v)`: a chair-like object (instance 2, label 5), a wall
/// (instance 4, label 1), unlabelled floor (0, 0) and labelled pixels without an instance (0, 7).
fn scannet_labels(u: u32, v: u32) -> (u8, u16) {
    match (u, v) {
        (14..26, 12..20) => (2, 5),
        (32.., _) => (4, 1),
        (..14, 22..) => (0, 7),
        _ => (0, 0),
    }
}

fn scannet_fixture() -> TempDir {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path();
    for n in [2u32, 10, 1, 5] {
        let color = |u: u32, _| if u < 48 { [200, 30, 30] } else { [30, 30, 200] };
        write_rgb(&root.join(format!("color/{n}.jpg")), (2 * SW, 2 * SH), color);
        write_grey16(&root.join(format!("depth/{n}.png")), (SW, SH), |u, v| match (u, v) {
            (35, 20) => 7000,
            _ => (500 + 10 * u + 100 * v + n) as u16,
        });
        write_grey8(
            &root.join(format!("instance-filt/{n}.png")),
            (2 * SW, 2 * SH),
            |u, v| scannet_labels(u / 2, v / 2).0,
        );
        write_grey16(&root.join(format!("label-filt/{n}.png")), (2 * SW, 2 * SH), |u, v| {
            scannet_labels(u / 2, v / 2).1
        });
        let pose = if n == 5 {
            "-inf -inf -inf -inf\n".repeat(4)
        } else {
            format!("1 0 0 {n}\n0 1 0 0\n0 0 1 0\n0 0 0 1\n")
        };
        std::fs::create_dir_all(root.join("pose")).expect("mkdir");
        std::fs::write(root.join(format!("pose/{n}.txt")), pose).expect("write pose");
    }
    std::fs::create_dir_all(root.join("intrinsic")).expect("mkdir");
    let k = "40 0 23.5 0\n0 41 17.5 0\n0 0 1 0\n0 0 0 1\n";
    std::fs::write(root.join("intrinsic/intrinsic_depth.txt"), k).expect("write intrinsics");
    dir
}

#[test]
fn scannet_frames_are_sorted_by_number_cropped_and_lost_poses_skipped() {
    let dir = scannet_fixture();
    let sequence = ScanNetSequence::open(dir.path(), &ScanNetOptions::default()).expect("valid sequence");
    assert_eq!(sequence.len(), 3, "frame 5 has an -inf pose and is skipped");
    let numbers: Vec<_> = (0..3).filter_map(|p| sequence.file_number(p)).collect();
    assert_eq!(numbers, [1, 2, 10], "integer order, not lexicographic");
    let cropped = CameraIntrinsics {
        width: 28,
        height: 16,
        fx: 40.0,
        fy: 41.0,
        cx: 13.5,
        cy: 7.5,
    };
    assert_eq!(
        sequence.intrinsics(),
        cropped,
        "a 10-px border is cropped and the centre shifts"
    );

    let frame = sequence.read_frame(2).expect("frame 10 decodes");
    frame.validate().expect("all images have the cropped size");
    assert_eq!(frame.index, FrameIndex(10));
    assert!(
        (frame.world_from_camera.translation.x - 10.0).abs() < 1e-6,
        "pose of file 10"
    );
    assert!(
        (frame.depth_m[0] - 1.610).abs() < 1e-6,
        "cropped (0, 0) is depth pixel (10, 10)"
    );
    assert_eq!(frame.depth_m[pixel(&frame, 25, 10)], 0.0, "7 m is beyond ScanNet's 6 m");
    let red = frame.rgb[pixel(&frame, 3, 5)];
    let blue = frame.rgb[pixel(&frame, 20, 5)];
    let close = |a: [u8; 3], b: [u8; 3]| a.iter().zip(b).all(|(&x, y)| x.abs_diff(y) <= 12);
    assert!(
        close(red, [200, 30, 30]) && close(blue, [30, 30, 200]),
        "colour resized: {red:?} {blue:?}"
    );

    let label = |u, v| frame.instances.label(pixel(&frame, u, v));
    assert_eq!(
        label(8, 5),
        InstanceLabel::Object(ObjectId(3)),
        "instance 2 becomes object 3 (+1)"
    );
    assert_eq!(label(24, 5), InstanceLabel::Background, "wall label");
    assert_eq!(label(0, 0), InstanceLabel::Background, "unlabelled instance 0");
    assert_eq!(
        label(1, 14),
        InstanceLabel::Unknown,
        "a labelled pixel without an instance"
    );
    assert_eq!(frame.classes[pixel(&frame, 8, 5)], ClassId(5));
}

#[test]
fn a_malformed_scannet_pose_names_file_and_line() {
    let dir = scannet_fixture();
    std::fs::write(dir.path().join("pose/2.txt"), "1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n").expect("write pose");
    let err = ScanNetSequence::open(dir.path(), &ScanNetOptions::default()).expect_err("3 numbers on line 2");
    assert_mentions(&err, &["2.txt:2:", "expected 4 numbers, found 3"]);
}

#[test]
fn a_missing_scannet_label_folder_is_named() {
    let dir = scannet_fixture();
    std::fs::remove_dir_all(dir.path().join("label-filt")).expect("remove labels");
    let err = ScanNetSequence::open(dir.path(), &ScanNetOptions::default()).expect_err("no labels");
    assert_mentions(&err, &["label-filt", "does not exist"]);
}

#[test]
fn a_synthetic_scene_written_in_scannets_layout_reads_back_as_its_own_frames() {
    use catmap::dataset::class_names::ClassNames;
    use catmap::synth::{Preset, SyntheticScene, write_scannet_layout};

    let dir = tempfile::tempdir().expect("tempdir");
    let scene = SyntheticScene::generate(1, Preset::Small).expect("small scene");
    write_scannet_layout(&scene, dir.path(), |_, _| {}).expect("written");
    // No crop, and the scene's whole depth range, so that every pixel compares.
    let options = ScanNetOptions {
        border_px: 0,
        max_depth_m: 60.0,
        ..ScanNetOptions::default()
    };
    let sequence = ScanNetSequence::open(dir.path(), &options).expect("ScanNet layout");
    assert_eq!(sequence.len(), scene.len(), "every frame read");
    assert_eq!(sequence.intrinsics(), scene.intrinsics());
    let names = ClassNames::find_scannet(dir.path());
    assert_eq!(names.get(ClassId(20)), Some("chair"), "the label map names the classes");
    for position in [0, scene.len() - 1] {
        let (read, truth) = (
            sequence.read_frame(position).expect("frame"),
            scene.read_frame(position).expect("rendered"),
        );
        let pose_error = read.world_from_camera.inverse() * truth.world_from_camera;
        assert!(
            pose_error.translation.vector.norm() < 1e-5 && pose_error.rotation.angle() < 1e-5,
            "the pose of frame {position}: {pose_error:?}"
        );
        let worst = (read.depth_m.iter().zip(&truth.depth_m))
            .map(|(&a, &b)| (a - b).abs())
            .fold(0.0f32, f32::max);
        assert!(worst <= 5.01e-4, "depth within half a millimetre: {worst}");
        // ScanNet's instance 0 is an instance: the reader shifts ids by one.
        let mut objects = 0;
        for i in 0..truth.instances.len() {
            match truth.instances.label(i) {
                InstanceLabel::Object(ObjectId(k)) => {
                    objects += 1;
                    assert_eq!(
                        read.instances.label(i),
                        InstanceLabel::Object(ObjectId(k + 1)),
                        "pixel {i}"
                    );
                    assert_eq!(read.classes[i], truth.classes[i], "pixel {i}");
                }
                other => assert_eq!(read.instances.label(i), other, "pixel {i}"),
            }
        }
        assert!(objects > 0, "frame {position} shows objects");
        let colour_error = (read.rgb.iter().flatten().zip(truth.rgb.iter().flatten()))
            .map(|(&a, &b)| f64::from(a.abs_diff(b)))
            .sum::<f64>()
            / (3 * truth.rgb.len()) as f64;
        assert!(
            colour_error < 3.0,
            "JPEG colour within 3 levels on average: {colour_error}"
        );
    }
}
