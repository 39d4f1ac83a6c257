use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use super::*;
use crate::ids::{ClassId, FrameIndex, ObjectId};

const W: u32 = 20;
const H: u32 = 10;
const POLE: ObjectId = ObjectId(4);

fn camera() -> CameraIntrinsics {
    CameraIntrinsics {
        width: W,
        height: H,
        fx: 10.0,
        fy: 10.0,
        cx: 9.5,
        cy: 4.5,
    }
}

/// A 20×10 frame of a wall at `depth_m` everywhere, object 4 labelled in columns
/// `pole_from..pole_to`, the rest background.
fn frame(index: u32, depth_m: f32, pole_from: u32, pole_to: u32) -> RgbdFrame {
    let n = (W * H) as usize;
    let labels = (0..n).map(|i| {
        let u = i as u32 % W;
        if (pole_from..pole_to).contains(&u) {
            InstanceLabel::Object(POLE)
        } else {
            InstanceLabel::Background
        }
    });
    RgbdFrame {
        index: FrameIndex(u64::from(index)),
        world_from_camera: Isometry3::identity(),
        intrinsics: camera(),
        rgb: vec![[0; 3]; n],
        depth_m: vec![depth_m; n],
        instances: InstanceMask::from_labels(labels),
        classes: vec![ClassId(0); n],
    }
}

fn history_of(frames: &[RgbdFrame]) -> LabelHistory {
    let mut history = LabelHistory::default();
    for f in frames {
        history.push(f, &f.instances, 8);
    }
    history
}

/// Every pixel of the band (all of it here: the whole frame).
fn whole_band() -> Vec<bool> {
    vec![true; (W * H) as usize]
}

fn at(frame: &RgbdFrame, u: u32, v: u32) -> InstanceLabel {
    frame.instances.label((v * W + u) as usize)
}

const ON: BorderVotes = BorderVotes {
    frames: 8,
    min_votes: 3,
    tolerance_m: 0.03,
    tolerance_per_m2: 0.006,
};

#[test]
fn a_pole_inside_the_band_keeps_its_pixels_when_the_frames_before_agree() {
    // The pole is column 9; the segmenter's mask is column 9 in two frames, columns 8..11 in one
    // (grown) and none in one (shrunk away).
    let history = history_of(&[
        frame(0, 2.0, 9, 10),
        frame(1, 2.0, 8, 11),
        frame(2, 2.0, 9, 9),
        frame(3, 2.0, 9, 10),
    ]);
    let now = frame(4, 2.0, 9, 10);
    let decided = vote_on_band(&now, &whole_band(), &history, &ON);
    assert_eq!(at(&decided, 9, 5), InstanceLabel::Object(POLE), "4 of 5 votes");
    assert_eq!(at(&decided, 8, 5), InstanceLabel::Background, "grown in one frame only");
    assert_eq!(at(&decided, 15, 2), InstanceLabel::Background);
}

#[test]
fn a_mask_grown_onto_the_wall_in_this_frame_leaves_those_pixels_unsure() {
    let history = history_of(&[frame(0, 2.0, 9, 10), frame(1, 2.0, 9, 10), frame(2, 2.0, 9, 10)]);
    let grown = frame(3, 2.0, 7, 12);
    let decided = vote_on_band(&grown, &whole_band(), &history, &ON);
    for u in [7, 8, 10, 11] {
        assert_eq!(
            at(&decided, u, 4),
            InstanceLabel::Unsure,
            "column {u}: the frames before saw wall"
        );
    }
    assert_eq!(at(&decided, 9, 4), InstanceLabel::Object(POLE));
}

#[test]
fn without_frames_before_the_band_stays_unsure() {
    let now = frame(0, 2.0, 9, 10);
    let decided = vote_on_band(&now, &whole_band(), &LabelHistory::default(), &ON);
    assert!((0..(W * H) as usize).all(|i| decided.instances.label(i) == InstanceLabel::Unsure));
}

#[test]
fn only_the_band_is_decided_and_pixels_without_depth_stay_unsure() {
    let history = history_of(&[frame(0, 2.0, 9, 10), frame(1, 2.0, 9, 10), frame(2, 2.0, 9, 10)]);
    let mut now = frame(3, 2.0, 8, 10);
    now.depth_m[(5 * W + 9) as usize] = 0.0;
    let mut band = vec![false; (W * H) as usize];
    band[(5 * W + 8) as usize] = true;
    band[(5 * W + 9) as usize] = true;
    let decided = vote_on_band(&now, &band, &history, &ON);
    assert_eq!(
        at(&decided, 8, 5),
        InstanceLabel::Unsure,
        "the frames before saw wall there"
    );
    assert_eq!(
        at(&decided, 9, 5),
        InstanceLabel::Unsure,
        "no depth, no point to vote on"
    );
    assert_eq!(
        at(&decided, 8, 4),
        InstanceLabel::Object(POLE),
        "outside the band: as labelled"
    );
}

#[test]
fn frames_that_see_through_the_point_vote_for_no_label_and_nearer_ones_abstain() {
    // This frame sees the pole's pixels at 2 m; two frames before saw 3 m there (through the
    // point), one saw the pole.
    let history = history_of(&[frame(0, 3.0, 9, 10), frame(1, 3.0, 9, 10), frame(2, 2.0, 9, 10)]);
    let now = frame(3, 2.0, 9, 10);
    let decided = vote_on_band(&now, &whole_band(), &history, &ON);
    assert_eq!(at(&decided, 9, 5), InstanceLabel::Unsure, "2 of 4 votes for the pole");
    // Frames that saw something nearer (1 m) say nothing: the two agreeing votes are all.
    let occluded = history_of(&[
        frame(0, 1.0, 9, 10),
        frame(1, 1.0, 9, 10),
        frame(2, 2.0, 9, 10),
        frame(3, 2.0, 9, 10),
    ]);
    let decided = vote_on_band(&now, &whole_band(), &occluded, &ON);
    assert_eq!(at(&decided, 9, 5), InstanceLabel::Object(POLE), "3 of 3 votes");
}

#[test]
fn a_frame_votes_where_the_point_lands_in_it_not_at_the_same_pixel() {
    // The camera moved 0.2 m along x: the pole's point at 2 m lands one pixel to the left.
    let mut moved = frame(0, 2.0, 8, 9);
    moved.world_from_camera = Isometry3::from_parts(Translation3::new(0.2, 0.0, 0.0), UnitQuaternion::identity());
    let history = history_of(&[moved.clone(), moved.clone(), moved]);
    let now = frame(3, 2.0, 9, 10);
    let decided = vote_on_band(&now, &whole_band(), &history, &ON);
    assert_eq!(at(&decided, 9, 5), InstanceLabel::Object(POLE));
    assert_eq!(at(&decided, 8, 5), InstanceLabel::Background);
}

#[test]
fn the_history_keeps_the_last_frames_only() {
    let mut history = LabelHistory::default();
    for i in 0..5 {
        let f = frame(i, 2.0, 9, 10);
        history.push(&f, &f.instances, 3);
    }
    assert_eq!(history.len(), 3);
    let f = frame(5, 2.0, 9, 10);
    history.push(&f, &f.instances, 0);
    assert!(history.is_empty(), "votes off keep nothing");
}

#[test]
fn the_segment_stage_keeps_a_poles_pixels_the_band_alone_loses_once_frames_before_confirm_them() {
    use crate::objects::config::ObjectConfig;
    use crate::objects::instance_association::InstanceTracker;
    use crate::objects::segment::segment_frame;
    let banded = ObjectConfig {
        mask_border_px: 2,
        min_box_side_px: 0,
        ..ObjectConfig::default()
    };
    let voted = ObjectConfig {
        border_votes: BorderVotes {
            frames: 4,
            ..BorderVotes::default()
        },
        ..banded.clone()
    };
    let pole_pixels = |cfg: &ObjectConfig| {
        let (mut tracker, mut history) = (InstanceTracker::default(), LabelHistory::default());
        (0..4)
            .map(|i| {
                let (changed, _) = segment_frame(&frame(i, 2.0, 9, 11), cfg, &mut tracker, &mut history);
                let now = changed.expect("the band changes the frame");
                (0..(W * H) as usize)
                    .filter(|&p| now.instances.label(p) == InstanceLabel::Object(POLE))
                    .count()
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(
        pole_pixels(&banded),
        [0, 0, 0, 0],
        "a 2 px pole lies inside a 2 px band"
    );
    assert_eq!(
        pole_pixels(&voted),
        [0, 0, 20, 20],
        "the pole's 20 pixels return once two frames before agree with the frame's own label"
    );
}
