use std::path::Path;

use nalgebra::Vector3;

use super::*;

fn rgb_txt() -> &'static Path {
    Path::new("seq/rgb.txt")
}

#[test]
fn file_lists_skip_comments_and_keep_line_numbers() {
    let text = "# color images\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n\
                1305031102.175304 rgb/1305031102.175304.png\n\n  1305031102.211214   rgb/1305031102.211214.png  \n";
    let files = parse_file_list(text, rgb_txt()).expect("TUM's own header and two images");
    assert_eq!(
        files,
        [
            TimedFile {
                timestamp_s: 1305031102.175304,
                path: "rgb/1305031102.175304.png".to_owned(),
                line: 4
            },
            TimedFile {
                timestamp_s: 1305031102.211214,
                path: "rgb/1305031102.211214.png".to_owned(),
                line: 6
            },
        ]
    );
    assert_eq!(parse_file_list("# only comments\n", rgb_txt()).expect("empty"), []);
}

/// The error text of `parse_file_list(text)`.
fn list_error(text: &str) -> String {
    parse_file_list(text, rgb_txt()).expect_err("a bad list").to_string()
}

#[test]
fn bad_file_list_lines_are_errors_naming_the_file_and_line() {
    let error = list_error("# c\n1.0 rgb/1.png\n2.0\n");
    assert!(
        error.contains("seq/rgb.txt:3: expected `timestamp path`, found 1 fields"),
        "{error}"
    );
    let error = list_error("1.0 rgb/1.png extra\n");
    assert!(
        error.contains("rgb.txt:1:") && error.contains("found 3 fields"),
        "{error}"
    );
    let error = list_error("one rgb/1.png\n");
    assert!(error.contains(":1: timestamp \"one\" is not a number"), "{error}");
    let error = list_error("nan rgb/1.png\n");
    assert!(error.contains(":1: timestamp NaN is not a finite"), "{error}");
    let error = list_error("1.0 rgb/1.png\n\n0.5 rgb/0.png\n");
    assert!(
        error.contains(":3: timestamp 0.5 is not after 1 on line 1: timestamps must increase"),
        "{error}"
    );
    let error = list_error("1.0 rgb/1.png\n1.0 rgb/1b.png\n");
    assert!(
        error.contains(":2:") && error.contains("must increase"),
        "equal timestamps: {error}"
    );
    for outside in ["/etc/passwd", "../rgb/1.png", "rgb/../../x.png"] {
        let error = list_error(&format!("1.0 {outside}\n"));
        assert!(
            error.contains(":1:") && error.contains("inside the sequence folder"),
            "{error}"
        );
    }
}

#[test]
fn groundtruth_lines_are_tum_poses_in_the_world() {
    // A quarter turn about z: (qx, qy, qz, qw) = (0, 0, sin 45°, cos 45°).
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let text = format!("# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n1.5 1 2 3 0 0 {h} {h}\n");
    let poses = parse_groundtruth(&text, Path::new("groundtruth.txt")).expect("one pose");
    assert_eq!(poses.len(), 1);
    let pose = &poses[0];
    assert_eq!((pose.timestamp_s, pose.line), (1.5, 3));
    assert_eq!(pose.world_from_camera.translation.vector, Vector3::new(1.0, 2.0, 3.0));
    let x_in_world = pose.world_from_camera.rotation * Vector3::x();
    assert!(
        (x_in_world - Vector3::y()).norm() < 1e-6,
        "the camera's x axis points along the world's y: {x_in_world}"
    );
    let rounded = parse_groundtruth("0 0 0 0 0 0 0.7071 0.7071\n", Path::new("g.txt")).expect("4 decimals");
    assert!(
        (rounded[0].world_from_camera.rotation.norm() - 1.0).abs() < 1e-6,
        "normalised"
    );
}

#[test]
fn bad_groundtruth_lines_are_errors_naming_the_file_and_line() {
    let error = |text: &str| {
        parse_groundtruth(text, Path::new("seq/groundtruth.txt"))
            .expect_err("a bad pose")
            .to_string()
    };
    let seven = error("# c\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n");
    assert!(
        seven.contains("groundtruth.txt:3: expected `timestamp tx ty tz qx qy qz qw`, found 7"),
        "{seven}"
    );
    let word = error("1 0 0 x 0 0 0 1\n");
    assert!(word.contains(":1: \"x\" is not a number"), "{word}");
    let scaled = error("1 0 0 0 0 0 0 2\n");
    assert!(
        scaled.contains(":1: quaternion") && scaled.contains("norm 2.0000, expected 1"),
        "{scaled}"
    );
    let nan = error("1 0 0 0 0 0 nan 1\n");
    assert!(nan.contains("NaN or infinite"), "{nan}");
    let far = error("1 1e39 0 0 0 0 0 1\n");
    assert!(
        far.contains(":1: translation") && far.contains("from the origin"),
        "{far}"
    );
    let back = error("2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n");
    assert!(back.contains(":2: timestamp 1 is not after 2 on line 1"), "{back}");
}
