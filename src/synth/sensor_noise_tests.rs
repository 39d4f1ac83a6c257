use std::collections::{BTreeMap, BTreeSet};

use nalgebra::Isometry3;

use super::*;
use crate::dataset::classes::replica;
use crate::sensor::frame::CameraIntrinsics;

const W: u32 = 80;
const H: u32 = 60;

/// A frame of a wall at `wall_m` with a square object (id 5, a chair) at `object_m` covering
/// columns 20..50 and rows 15..45, and a stool (id 8) at columns 60..70, rows 20..30.
fn frame(wall_m: f32, object_m: f32) -> RenderedFrame {
    let n = (W * H) as usize;
    let mut f = RenderedFrame {
        world_from_camera: Isometry3::identity(),
        intrinsics: CameraIntrinsics {
            width: W,
            height: H,
            fx: 60.0,
            fy: 60.0,
            cx: 39.5,
            cy: 29.5,
        },
        rgb: vec![[128; 3]; n],
        depth_m: vec![wall_m; n],
        instance_ids: vec![101; n],
        classes: vec![replica::WALL; n],
    };
    for i in 0..n {
        let (u, v) = (i as u32 % W, i as u32 / W);
        if (20..50).contains(&u) && (15..45).contains(&v) {
            (f.depth_m[i], f.instance_ids[i], f.classes[i]) = (object_m, 5, replica::CHAIR);
        }
        if (60..70).contains(&u) && (20..30).contains(&v) {
            (f.depth_m[i], f.instance_ids[i], f.classes[i]) = (object_m, 8, replica::STOOL);
        }
    }
    f
}

fn kinect() -> SensorSettings {
    SensorSettings::new(SensorModel::Kinect, InstanceIds::Consistent)
}

const CLASSES: [ClassId; 3] = [replica::CHAIR, replica::STOOL, replica::TABLE];

fn pixels_of(f: &RenderedFrame, id: u16) -> BTreeSet<usize> {
    (0..f.instance_ids.len())
        .filter(|&i| f.instance_ids[i] == id && is_object(f, i))
        .collect()
}

#[test]
fn the_depth_part_keeps_the_masks_and_the_masks_part_keeps_the_depth() {
    let clean = frame(3.0, 1.5);
    let with = |model: SensorModel| {
        let mut f = frame(3.0, 1.5);
        let settings = SensorSettings::new(model, InstanceIds::Consistent);
        settings.apply(&mut f, 1, 4, &CLASSES);
        f
    };
    let depth = with(SensorModel::KinectDepth);
    assert_ne!(depth.depth_m, clean.depth_m);
    assert_eq!(
        (&depth.instance_ids, &depth.classes),
        (&clean.instance_ids, &clean.classes)
    );
    let masks = with(SensorModel::SegmenterMasks);
    assert_eq!(masks.depth_m, clean.depth_m);
    let all = with(SensorModel::Kinect);
    assert_ne!(all.instance_ids, clean.instance_ids, "the whole model moves the masks");
    assert_eq!(
        all.depth_m, depth.depth_m,
        "the depth part draws first, as in the whole model"
    );
}

#[test]
fn exact_settings_leave_the_frame_as_rendered() {
    let mut f = frame(3.0, 1.5);
    SensorSettings::default().apply(&mut f, 1, 0, &CLASSES);
    assert_eq!(f, frame(3.0, 1.5));
}

#[test]
fn depth_noise_grows_with_distance_as_the_kinect_model_says() {
    let noise = KinectNoise::default();
    for z in [1.0f32, 3.0] {
        let mut deviations = Vec::new();
        for position in 0..20 {
            let mut f = frame(z, z);
            kinect().apply(&mut f, 7, position, &CLASSES);
            deviations.extend(f.depth_m.iter().filter(|&&d| d > 0.0).map(|&d| f64::from(d - z)));
        }
        let n = deviations.len() as f64;
        let mean = deviations.iter().sum::<f64>() / n;
        let sd = (deviations.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
        let expected = f64::from(noise.sigma_m(z));
        assert!(
            (sd / expected - 1.0).abs() < 0.05,
            "z {z}: sd {sd} against σ {expected}"
        );
        assert!(mean.abs() < 0.1 * expected, "z {z}: unbiased, mean {mean}");
    }
    assert!(noise.sigma_m(3.0) > 5.0 * noise.sigma_m(1.0));
}

#[test]
fn holes_open_at_depth_edges_and_rarely_elsewhere() {
    let (mut edge_holes, mut edges, mut flat_holes, mut flat) = (0, 0, 0, 0);
    for position in 0..10 {
        let clean = frame(3.0, 1.5);
        let mut f = clean.clone();
        kinect().apply(&mut f, 3, position, &CLASSES);
        let w = W as usize;
        for i in 0..f.depth_m.len() {
            let (u, v) = (i % w, i / w);
            let z = clean.depth_m[i];
            let differs = |j: usize| (clean.depth_m[j] - z).abs() > 0.04;
            let edge = (u > 0 && differs(i - 1))
                || (u + 1 < w && differs(i + 1))
                || (v > 0 && differs(i - w))
                || (v + 1 < H as usize && differs(i + w));
            if edge {
                edges += 1;
                edge_holes += usize::from(f.depth_m[i] == 0.0);
            } else if (25..45).contains(&u) && (20..40).contains(&v) {
                flat += 1;
                flat_holes += usize::from(f.depth_m[i] == 0.0);
            }
        }
    }
    let edge_share = edge_holes as f64 / edges as f64;
    let flat_share = flat_holes as f64 / flat as f64;
    assert!(
        (0.5..0.7).contains(&edge_share),
        "edge pixels lose depth at 0.6: {edge_share}"
    );
    assert!(flat_share < 0.02, "inside a surface only the dropout: {flat_share}");
}

#[test]
fn masks_grow_shrink_or_go_missing_but_stay_on_their_object() {
    let clean = frame(3.0, 1.5);
    let truth = pixels_of(&clean, 5);
    let (mut grew, mut shrank, mut missed) = (0, 0, 0);
    for position in 0..200 {
        let mut f = clean.clone();
        kinect().apply(&mut f, 11, position, &CLASSES);
        let seen = pixels_of(&f, 5);
        if seen.is_empty() {
            missed += 1;
            continue;
        }
        let inter = seen.intersection(&truth).count() as f64;
        let union = seen.union(&truth).count() as f64;
        assert!(inter / union > 0.75, "frame {position}: IoU {}", inter / union);
        grew += usize::from(seen.len() > truth.len());
        shrank += usize::from(seen.len() < truth.len());
        assert!(seen.iter().all(|&i| clean.instance_ids[i] != 8), "never onto the stool");
    }
    assert!(grew > 40 && shrank > 40, "grew {grew}, shrank {shrank}");
    assert!(
        (3..=20).contains(&missed),
        "missed in about 5 % of 200 frames: {missed}"
    );
}

#[test]
fn a_confused_mask_carries_another_scene_class() {
    let mut said: BTreeMap<ClassId, usize> = BTreeMap::new();
    for position in 0..400 {
        let mut f = frame(3.0, 1.5);
        kinect().apply(&mut f, 5, position, &CLASSES);
        if let Some(&i) = pixels_of(&f, 5).first() {
            *said.entry(f.classes[i]).or_default() += 1;
        }
    }
    let wrong: usize = said.iter().filter(|(c, _)| **c != replica::CHAIR).map(|(_, n)| n).sum();
    assert!((2..=20).contains(&wrong), "about 2 % of 400: {said:?}");
    assert!(said.keys().all(|c| CLASSES.contains(c)), "{said:?}");
}

#[test]
fn per_frame_ids_renumber_each_frame_but_keep_its_partition() {
    let settings = SensorSettings::new(SensorModel::None, InstanceIds::PerFrame);
    let clean = frame(3.0, 1.5);
    let mut ids_seen = BTreeSet::new();
    for position in 0..6 {
        let mut f = clean.clone();
        settings.apply(&mut f, 2, position, &CLASSES);
        assert_eq!(f.depth_m, clean.depth_m);
        let (chair, stool) = (
            f.instance_ids[30 * W as usize + 30],
            f.instance_ids[25 * W as usize + 65],
        );
        assert_ne!(chair, stool);
        assert_eq!(pixels_of(&f, chair), pixels_of(&clean, 5));
        assert_eq!(pixels_of(&f, stool), pixels_of(&clean, 8));
        assert!((1..=99).contains(&chair) && (1..=99).contains(&stool));
        ids_seen.insert(chair);
        let mut again = clean.clone();
        settings.apply(&mut again, 2, position, &CLASSES);
        assert_eq!(again, f, "a frame reads the same every time");
    }
    assert!(ids_seen.len() >= 4, "frames number their masks anew: {ids_seen:?}");
}
