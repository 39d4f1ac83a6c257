//! Fuzzing of the reader paths (issue 6, Resilience): PNG decoding, Replica trajectories, ScanNet
//! poses, intrinsics (intrinsics.json, `--camera`, ScanNet's intrinsic matrix) and config TOML;
//! the folder readers are fuzzed in `fuzz_folders.rs`.
//!
//! Each target runs `CATMAP_FUZZ_INPUTS` inputs (a fixed number by default, see `fuzz_support`), or
//! for `CATMAP_FUZZ_SECONDS` seconds when that is set, from seed `CATMAP_FUZZ_SEED` (default 0),
//! and fails on any panic, any error that does not name its file, and any decoded
//! frame that is inconsistent or holds a NaN. A long run, with the per-target report:
//!
//! ```text
//! CATMAP_FUZZ_SECONDS=600 cargo test --test suite readers::fuzz_readers -- --nocapture --test-threads 1
//! ```

use std::path::Path;

use crate::fuzz_support::checks::check_pose;
use crate::fuzz_support::fixtures::{Folder, replica_files, rgb_image, scannet_files};
use crate::fuzz_support::mutate::{mutate_bytes, mutate_text, random_text};
use crate::fuzz_support::png::{generate_png, mutate_png};
use crate::fuzz_support::{Execution, Verdict, fuzz, pick, rejected_naming};
use catmap::MapperConfig;
use catmap::dataset::FrameSource;
use catmap::dataset::camera_spec::{
    intrinsics_problem, parse_camera_spec, parse_numbers, read_intrinsic_matrix, read_intrinsics_json,
    world_from_camera_from_rows,
};
use catmap::dataset::images::{Image, grey_from_bytes, grey_from_bytes_as, grey16_from_bytes, rgb_from_bytes};
use catmap::dataset::replica::{ReplicaOptions, ReplicaSequence};
use catmap::dataset::resize::{resize_bilinear_rgb, resize_nearest};
use catmap::dataset::scannet::{ScanNetOptions, ScanNetSequence};
use image::ImageFormat;
use nalgebra::{Rotation3, Vector3};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

#[expect(
    clippy::ptr_arg,
    reason = "the fuzz harness saves inputs of type &I, here I = Vec<u8>"
)]
fn save_bytes(bytes: &Vec<u8>) -> (String, Vec<u8>) {
    (format!("{} bytes", bytes.len()), bytes.clone())
}

fn png_seeds() -> Vec<Vec<u8>> {
    let size = (7, 5);
    let f = |u: u32, v: u32| (u * 37 + v * 11) as u8;
    let mut seeds = vec![
        crate::fuzz_support::fixtures::grey8_png(size, f),
        crate::fuzz_support::fixtures::grey16_png(size, |u, v| 1000 + (u * 300 + v) as u16),
        rgb_image(size, ImageFormat::Png, |u, v| [f(u, v), 3, 200]),
        rgb_image(size, ImageFormat::Jpeg, |u, v| [f(u, v), 90, 20]),
    ];
    let rgba = image::RgbaImage::from_fn(5, 4, |u, v| image::Rgba([u as u8, v as u8, 7, 128]));
    let mut bytes = Vec::new();
    rgba.write_to(&mut std::io::Cursor::new(&mut bytes), ImageFormat::Png)
        .expect("encode rgba");
    seeds.push(bytes);
    seeds
}

/// Runs every decoder of `images.rs` on `bytes`; decoded images are also cropped and resized.
fn decode_everything(bytes: &[u8]) -> Execution {
    let path = Path::new("fuzz/input.png");
    let mut accepted = false;
    let checked = |size: (u32, u32), len: usize| -> Result<(), String> {
        match size.0 as usize * size.1 as usize == len {
            true => Ok(()),
            false => Err(format!("decoded {size:?} image has {len} pixels")),
        }
    };
    let (w, h) = (bytes.len() as u32 % 13 + 1, bytes.len() as u32 % 11 + 1);
    match grey_from_bytes(bytes, path) {
        Ok(image) => {
            accepted = true;
            checked(image.size(), image.pixels.len())?;
            let resized = resize_nearest(image.clone(), w, h);
            checked(resized.size(), resized.pixels.len())?;
            if let Some(cropped) = image.crop_border(bytes.len() as u32 % 4) {
                checked(cropped.size(), cropped.pixels.len())?;
            }
        }
        Err(e) => rejected_naming(&e, "input.png").map(drop)?,
    }
    match grey16_from_bytes(bytes, path) {
        Ok(image) => checked(image.size(), image.pixels.len())?,
        Err(e) => rejected_naming(&e, "input.png").map(drop)?,
    }
    match grey_from_bytes_as::<f32>(bytes, path) {
        Ok(image) => checked(image.size(), image.pixels.len())?,
        Err(e) => rejected_naming(&e, "input.png").map(drop)?,
    }
    match rgb_from_bytes(bytes, path) {
        Ok(image) => {
            accepted = true;
            checked(image.size(), image.pixels.len())?;
            let resized: Image<[u8; 3]> = resize_bilinear_rgb(image, w, h);
            checked(resized.size(), resized.pixels.len())?;
        }
        Err(e) => rejected_naming(&e, "input.png").map(drop)?,
    }
    Ok(if accepted { Verdict::Accepted } else { Verdict::Rejected })
}

#[test]
fn png_decoding_never_panics_and_errors_name_the_file() {
    let seeds = png_seeds();
    let others: Vec<&[u8]> = seeds.iter().map(Vec::as_slice).collect();
    let generate = |rng: &mut ChaCha8Rng| match rng.random_range(0..4) {
        0 => generate_png(rng),
        1 => mutate_png(pick::<Vec<u8>>(&seeds, rng), rng),
        2 => mutate_bytes(pick::<Vec<u8>>(&seeds, rng), &others, rng),
        _ => mutate_png(&generate_png(rng), rng),
    };
    fuzz("png_decode", generate, |bytes| decode_everything(bytes), save_bytes);
}

/// A pose line of 16 numbers: a random rotation and translation, sometimes scaled, sheared or
/// given a special value.
fn random_pose_line(rng: &mut ChaCha8Rng) -> String {
    let axis = Vector3::new(
        rng.random::<f64>() - 0.5,
        rng.random::<f64>() - 0.5,
        rng.random::<f64>() - 0.5,
    );
    let rotation = Rotation3::new(axis * 6.0);
    let mut m = [0.0f64; 16];
    for r in 0..3 {
        for c in 0..3 {
            m[4 * r + c] = rotation[(r, c)];
        }
        m[4 * r + 3] = rng.random_range(-5.0..5.0);
    }
    m[15] = 1.0;
    const SPECIAL: [f64; 9] = [
        0.0,
        -0.0,
        1e-300,
        1e300,
        f64::MAX,
        f64::MIN_POSITIVE,
        1.0005,
        -1.0,
        5e-324,
    ];
    for _ in 0..rng.random_range(0..3) {
        let i = rng.random_range(0..16);
        m[i] = match rng.random_range(0..3) {
            0 => *pick(&SPECIAL, rng),
            1 => m[i] * rng.random_range(0.9..1.1),
            _ => m[i] + rng.random_range(-1e-3..1e-3),
        };
    }
    m.map(|x| format!("{x:e}")).join(" ")
}

/// Parses every line of `text` as a pose, as the readers do line by line.
fn parse_pose_lines(text: &str) -> Result<(), String> {
    for line in text.lines() {
        let Ok(numbers) = parse_numbers(line) else { continue };
        if let Ok(rows) = <[f64; 16]>::try_from(numbers)
            && let Ok(pose) = world_from_camera_from_rows(&rows)
        {
            check_pose(&pose)?;
        }
    }
    Ok(())
}

#[test]
fn replica_trajectories_never_panic_and_errors_name_the_file() {
    let files = replica_files(3);
    let folder = Folder::new(files.clone());
    let seed = String::from_utf8(files["traj_w_c.txt"].clone()).expect("ASCII trajectory");
    let generate = |rng: &mut ChaCha8Rng| match rng.random_range(0..6) {
        0 => (0..3)
            .map(|_| random_pose_line(rng) + "\n")
            .collect::<String>()
            .into_bytes(),
        1 => random_text(200, rng).into_bytes(),
        _ => mutate_text(&seed, &[], rng),
    };
    let traj = folder.path().join("traj_w_c.txt");
    let execute = |bytes: &Vec<u8>| {
        parse_pose_lines(&String::from_utf8_lossy(bytes))?;
        std::fs::write(&traj, bytes).map_err(|e| e.to_string())?;
        match ReplicaSequence::open(folder.path(), &ReplicaOptions::default()) {
            Err(e) => rejected_naming(&e, "traj_w_c.txt"),
            Ok(sequence) => {
                for position in 0..sequence.len() {
                    check_pose(&sequence.world_from_camera(position).ok_or("no pose")?)?;
                }
                Ok(Verdict::Accepted)
            }
        }
    };
    fuzz("replica_trajectory", generate, execute, save_bytes);
}

#[test]
fn scannet_poses_never_panic_and_errors_name_the_file() {
    let files = scannet_files(2);
    let folder = Folder::new(files.clone());
    let seed = String::from_utf8(files["pose/0.txt"].clone()).expect("ASCII pose");
    let generate = |rng: &mut ChaCha8Rng| match rng.random_range(0..6) {
        0 => {
            let line = random_pose_line(rng);
            let numbers: Vec<&str> = line.split(' ').collect();
            numbers
                .chunks(4)
                .map(|row| row.join(" ") + "\n")
                .collect::<String>()
                .into_bytes()
        }
        1 => random_text(120, rng).into_bytes(),
        _ => mutate_text(&seed, &[], rng),
    };
    let pose = folder.path().join("pose/0.txt");
    let execute = |bytes: &Vec<u8>| {
        std::fs::write(&pose, bytes).map_err(|e| e.to_string())?;
        match ScanNetSequence::open(folder.path(), &ScanNetOptions::default()) {
            Err(e) => rejected_naming(&e, "pose/0.txt"),
            Ok(sequence) => {
                for position in 0..sequence.len() {
                    check_pose(&sequence.world_from_camera(position).ok_or("no pose")?)?;
                }
                Ok(Verdict::Accepted)
            }
        }
    };
    fuzz("scannet_pose", generate, execute, save_bytes);
}

/// One intrinsics input: an `intrinsics.json`, a ScanNet matrix file with an image size, or a
/// `--camera` spec.
#[derive(Debug, Clone)]
enum IntrinsicsInput {
    Json(Vec<u8>),
    Matrix(Vec<u8>, u32, u32),
    Spec(String),
}

#[test]
fn intrinsics_never_panic_and_errors_name_the_file() {
    let json_seed = String::from_utf8(replica_files(1)["intrinsics.json"].clone()).expect("ASCII json");
    let matrix_seed =
        String::from_utf8(scannet_files(1)["intrinsic/intrinsic_depth.txt"].clone()).expect("ASCII matrix");
    let spec_seed = "640,480,500.5,501,319.5,239.5";
    let generate = |rng: &mut ChaCha8Rng| match rng.random_range(0..3) {
        0 => IntrinsicsInput::Json(mutate_text(&json_seed, &[], rng)),
        1 => {
            let size = |rng: &mut ChaCha8Rng| *pick(&[0, 1, 12, 640, u32::MAX], rng);
            IntrinsicsInput::Matrix(mutate_text(&matrix_seed, &[], rng), size(rng), size(rng))
        }
        _ => {
            let mutated = mutate_text(&spec_seed.replace(',', " , "), &[], rng);
            IntrinsicsInput::Spec(String::from_utf8_lossy(&mutated).replace(" , ", ","))
        }
    };
    let dir = tempfile::tempdir().expect("temp dir");
    let (json, matrix) = (
        dir.path().join("intrinsics.json"),
        dir.path().join("intrinsic_depth.txt"),
    );
    let execute = |input: &IntrinsicsInput| {
        let (result, needle) = match input {
            IntrinsicsInput::Json(bytes) => {
                std::fs::write(&json, bytes).map_err(|e| e.to_string())?;
                (read_intrinsics_json(&json), "intrinsics.json")
            }
            IntrinsicsInput::Matrix(bytes, w, h) => {
                std::fs::write(&matrix, bytes).map_err(|e| e.to_string())?;
                (read_intrinsic_matrix(&matrix, *w, *h), "intrinsic_depth.txt")
            }
            IntrinsicsInput::Spec(spec) => (parse_camera_spec(spec), "--camera"),
        };
        match result {
            Ok(k) => match intrinsics_problem(&k) {
                None => Ok(Verdict::Accepted),
                Some(problem) => Err(format!("accepted intrinsics with a problem: {problem}")),
            },
            Err(e) => rejected_naming(&e, needle),
        }
    };
    let save = |input: &IntrinsicsInput| match input {
        IntrinsicsInput::Json(b) => ("intrinsics.json".to_owned(), b.clone()),
        IntrinsicsInput::Matrix(b, w, h) => (format!("intrinsic matrix for {w}×{h}"), b.clone()),
        IntrinsicsInput::Spec(s) => ("--camera spec".to_owned(), s.clone().into_bytes()),
    };
    fuzz("intrinsics", generate, execute, save);
}

#[test]
fn config_files_never_panic_and_valid_ones_build_a_mapper() {
    let seeds = [
        MapperConfig::default().to_toml(),
        "seed = 3\n[stream]\nchannel_capacity = 2\nmax_frames = 10\n".to_owned(),
        "[fields]\nsteps_per_frame = 5\nobject_scale = 2.0\n[meshes.object]\nvoxel_size_m = 0.01\n".to_owned(),
        "[categories]\nenabled = true\n[category_fields]\nenabled = true\niterations = 10\n".to_owned(),
    ];
    let others: Vec<&[u8]> = seeds.iter().map(|s| s.as_bytes()).collect();
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("config.toml");
    let generate = |rng: &mut ChaCha8Rng| mutate_text(pick::<String>(&seeds, rng), &others, rng);
    let execute = |bytes: &Vec<u8>| {
        std::fs::write(&path, bytes).map_err(|e| e.to_string())?;
        let config = match MapperConfig::load(&path) {
            Ok(config) => config,
            Err(e) => return rejected_naming(&e, "config.toml"),
        };
        let printed = config.to_toml();
        let reparsed = MapperConfig::from_toml(&printed).map_err(|e| format!("printed config does not parse: {e}"))?;
        if reparsed.to_toml() != printed {
            return Err("the printed config does not round-trip".to_owned());
        }
        catmap_systems::Mapper::new(config).map_err(|e| format!("a validated config is refused: {e}"))?;
        Ok(Verdict::Accepted)
    };
    fuzz("config_toml", generate, execute, save_bytes);
}
