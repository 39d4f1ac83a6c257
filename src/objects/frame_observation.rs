//! What one frame says about each object: its pixels, 2D box and class votes.
//!
//! This is the "masks" stage: a single pass over the instance mask groups pixels by object.

use std::collections::BTreeMap;

use crate::ids::{ClassId, ObjectId};
use crate::objects::config::ObjectConfig;
use crate::objects::instance_association::ObjectMerge;
use crate::sensor::frame::{InstanceLabel, RgbdFrame};
use crate::sensor::pixel_box::PixelBox;

/// One object as seen in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjectObservation {
    /// Row-major indices of the object's pixels.
    pub pixels: Vec<u32>,
    /// Tight 2D box of those pixels.
    pub tight_box: PixelBox,
    /// The box enlarged by `ObjectConfig::box_enlargement`; training samples pixels inside it.
    pub sample_box: PixelBox,
    /// Pixel count per semantic class inside the object's mask.
    pub class_votes: BTreeMap<ClassId, u32>,
}

/// Everything one frame says about the objects in it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrameObservation {
    /// Objects whose box is large enough to count, by id.
    pub objects: BTreeMap<ObjectId, ObjectObservation>,
    /// Objects seen in the frame but ignored because their 2D box is too small.
    pub ignored_small: Vec<ObjectId>,
    /// Pixel indices of the background, thinned by `background_pixel_stride` in each direction.
    pub background_pixels: Vec<u32>,
    /// Objects the association found to be one in this frame (per-frame ids only).
    pub merges: Vec<ObjectMerge>,
}

/// Groups the pixels of `frame` by object and computes boxes and class votes.
///
/// Instances whose tight box is at most `min_box_side_px` wide or high are listed in
/// `ignored_small` and otherwise ignored in this frame (METHOD.md §1).
pub fn observe_objects(frame: &RgbdFrame, cfg: &ObjectConfig) -> FrameObservation {
    let (width, height) = (frame.intrinsics.width, frame.intrinsics.height);
    let stride = cfg.background_pixel_stride.max(1);
    let mut found: Vec<(ObjectId, Accumulator)> = Vec::new();
    let mut background_pixels = Vec::new();
    // Neighbouring pixels usually share a label: remember the last object's slot.
    let mut last_slot = usize::MAX;
    let pixels = (0..height).flat_map(|v| (0..width).map(move |u| (u, v)));
    for (i, (u, v)) in pixels.enumerate().take(frame.instances.len()) {
        match frame.instances.label(i) {
            InstanceLabel::Object(id) => {
                if found.get(last_slot).is_none_or(|(last_id, _)| *last_id != id) {
                    last_slot = match found.iter().position(|(other, _)| *other == id) {
                        Some(slot) => slot,
                        None => {
                            found.push((id, Accumulator::starting_at(u, v)));
                            found.len() - 1
                        }
                    };
                }
                found[last_slot].1.add(i as u32, u, v, frame.classes[i]);
            }
            InstanceLabel::Background if u % stride == 0 && v % stride == 0 => background_pixels.push(i as u32),
            InstanceLabel::Background | InstanceLabel::Unknown | InstanceLabel::Unsure => {}
        }
    }
    let mut objects: BTreeMap<ObjectId, ObjectObservation> = found
        .into_iter()
        .map(|(id, acc)| {
            let observation = ObjectObservation {
                pixels: acc.pixels,
                tight_box: acc.tight_box,
                sample_box: acc.tight_box.enlarged(cfg.box_enlargement, width, height),
                class_votes: acc.class_votes.into_iter().collect(),
            };
            (id, observation)
        })
        .collect();
    let mut ignored_small = Vec::new();
    objects.retain(|&id, obs| {
        let big_enough = obs.tight_box.width() > cfg.min_box_side_px && obs.tight_box.height() > cfg.min_box_side_px;
        if !big_enough {
            ignored_small.push(id);
        }
        big_enough
    });
    FrameObservation {
        objects,
        ignored_small,
        background_pixels,
        merges: Vec::new(),
    }
}

/// Pixels, box and votes of one object while the frame is scanned.
struct Accumulator {
    pixels: Vec<u32>,
    tight_box: PixelBox,
    class_votes: Vec<(ClassId, u32)>,
}

impl Accumulator {
    fn starting_at(u: u32, v: u32) -> Self {
        Self {
            pixels: Vec::new(),
            tight_box: PixelBox::at(u, v),
            class_votes: Vec::new(),
        }
    }

    #[inline]
    fn add(&mut self, pixel: u32, u: u32, v: u32, class: ClassId) {
        self.pixels.push(pixel);
        self.tight_box.include(u, v);
        match self.class_votes.iter_mut().find(|(c, _)| *c == class) {
            Some((_, n)) => *n += 1,
            None => self.class_votes.push((class, 1)),
        }
    }
}

/// The class with the most votes; ties go to the smaller class id. `None` without votes.
pub fn majority_class(votes: &BTreeMap<ClassId, u64>) -> Option<ClassId> {
    votes
        .iter()
        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
        .map(|(&class, _)| class)
}

impl ObjectObservation {
    /// The class most of this observation's pixels vote for (`None` without pixels).
    pub fn majority_class(&self) -> Option<ClassId> {
        majority_class(&self.class_votes.iter().map(|(&c, &n)| (c, u64::from(n))).collect())
    }

    /// How many of its pixels have a depth in `depth_m` (the frame's, row-major; 0 = none).
    pub fn pixels_with_depth(&self, depth_m: &[f32]) -> usize {
        self.pixels
            .iter()
            .filter(|&&i| depth_m.get(i as usize).is_some_and(|&d| d > 0.0 && d.is_finite()))
            .count()
    }
}

/// An object's mask pixels over its views, and how many of them had a depth: an object whose
/// pixels mostly lack one (beyond the camera's range, dark or shiny) is mapped from little.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct DepthCoverage {
    /// Mask pixels over every view.
    pub pixels: u64,
    /// Those with a depth.
    pub with_depth: u64,
}

impl DepthCoverage {
    /// Adds one view: `observation` in a frame of depth `depth_m`.
    pub fn add(&mut self, observation: &ObjectObservation, depth_m: &[f32]) {
        self.pixels += observation.pixels.len() as u64;
        self.with_depth += observation.pixels_with_depth(depth_m) as u64;
    }

    /// Adds the views of an object found to be part of this one.
    pub fn absorb(&mut self, other: DepthCoverage) {
        self.pixels += other.pixels;
        self.with_depth += other.with_depth;
    }

    /// The share of pixels with a depth (`None` before any pixel).
    pub fn share(&self) -> Option<f32> {
        (self.pixels > 0).then(|| self.with_depth as f32 / self.pixels as f32)
    }
}

/// Below this share of its pixels with a depth, an object is reported as mapped from little.
pub const LOW_DEPTH_SHARE: f32 = 0.5;

/// Adds this frame's votes `new` to an object's `votes`; returns its class now (the majority).
pub fn add_class_votes(votes: &mut BTreeMap<ClassId, u64>, new: &BTreeMap<ClassId, u32>) -> Option<ClassId> {
    for (&class, &n) in new {
        *votes.entry(class).or_insert(0) += u64::from(n);
    }
    majority_class(votes)
}

#[cfg(test)]
mod tests {
    use nalgebra::Isometry3;

    use super::*;
    use crate::ids::FrameIndex;
    use crate::sensor::frame::{CameraIntrinsics, InstanceMask};

    fn frame_with(labels: &[InstanceLabel], classes: &[u32], width: u32) -> RgbdFrame {
        let height = labels.len() as u32 / width;
        RgbdFrame {
            index: FrameIndex(0),
            world_from_camera: Isometry3::identity(),
            intrinsics: CameraIntrinsics {
                width,
                height,
                fx: 10.0,
                fy: 10.0,
                cx: 1.0,
                cy: 1.0,
            },
            rgb: vec![[0; 3]; labels.len()],
            depth_m: vec![1.0; labels.len()],
            instances: InstanceMask::from_labels(labels.iter().copied()),
            classes: classes.iter().map(|&c| ClassId(c)).collect(),
        }
    }

    #[test]
    fn pixels_are_grouped_by_object_with_boxes_and_votes() {
        use InstanceLabel::{Background as B, Object as O};
        let a = O(ObjectId(3));
        let labels = [B, a, a, B, B, a, B, B, B];
        let classes = [0, 20, 20, 0, 0, 80, 0, 0, 0];
        let cfg = ObjectConfig {
            min_box_side_px: 0,
            background_pixel_stride: 1,
            ..ObjectConfig::default()
        };
        let obs = observe_objects(&frame_with(&labels, &classes, 3), &cfg);
        let chair = &obs.objects[&ObjectId(3)];
        assert_eq!(chair.pixels, [1, 2, 5]);
        assert_eq!(
            chair.tight_box,
            PixelBox {
                u_min: 1,
                v_min: 0,
                u_max: 2,
                v_max: 1
            }
        );
        assert_eq!(chair.class_votes[&ClassId(20)], 2);
        assert_eq!(obs.background_pixels, [0, 3, 4, 6, 7, 8]);
    }

    #[test]
    fn an_objects_depth_coverage_counts_its_pixels_with_a_depth_over_its_views() {
        use InstanceLabel::{Background as B, Object as O};
        let a = O(ObjectId(3));
        let mut frame = frame_with(&[B, a, a, B, B, a, B, B, B], &[0, 20, 20, 0, 0, 20, 0, 0, 0], 3);
        frame.depth_m[2] = 0.0;
        frame.depth_m[5] = f32::NAN;
        let cfg = ObjectConfig {
            min_box_side_px: 0,
            ..ObjectConfig::default()
        };
        let chair = &observe_objects(&frame, &cfg).objects[&ObjectId(3)];
        assert_eq!(chair.pixels_with_depth(&frame.depth_m), 1);
        let mut coverage = DepthCoverage::default();
        assert_eq!(coverage.share(), None);
        coverage.add(chair, &frame.depth_m);
        frame.depth_m = vec![2.0; 9];
        coverage.add(chair, &frame.depth_m);
        assert_eq!((coverage.pixels, coverage.with_depth), (6, 4));
        assert_eq!(coverage.share(), Some(4.0 / 6.0));
    }

    #[test]
    fn instances_with_tiny_boxes_are_ignored_in_that_frame() {
        use InstanceLabel::{Background as B, Object as O};
        let labels = [O(ObjectId(1)), B, B, B];
        let obs = observe_objects(&frame_with(&labels, &[20, 0, 0, 0], 2), &ObjectConfig::default());
        assert!(obs.objects.is_empty(), "a 1-pixel instance is below the 10 px rule");
        assert_eq!(obs.ignored_small, [ObjectId(1)]);
    }

    #[test]
    fn majority_vote_breaks_ties_towards_the_smaller_class() {
        let votes = BTreeMap::from([(ClassId(80), 5), (ClassId(20), 5), (ClassId(18), 2)]);
        assert_eq!(majority_class(&votes), Some(ClassId(20)));
        assert_eq!(majority_class(&BTreeMap::new()), None);
    }

    #[test]
    fn votes_add_up_over_frames_and_the_majority_can_change() {
        let mut votes = BTreeMap::new();
        let frame = |pairs: &[(u32, u32)]| pairs.iter().map(|&(c, n)| (ClassId(c), n)).collect::<BTreeMap<_, _>>();
        assert_eq!(add_class_votes(&mut votes, &frame(&[(3, 5), (4, 2)])), Some(ClassId(3)));
        assert_eq!(
            add_class_votes(&mut votes, &frame(&[(4, 4)])),
            Some(ClassId(4)),
            "6 votes beat 5"
        );
        assert_eq!(votes[&ClassId(4)], 6);
        assert_eq!(
            add_class_votes(&mut votes, &frame(&[(3, 1)])),
            Some(ClassId(3)),
            "a tie goes to the smaller id"
        );
    }
}
