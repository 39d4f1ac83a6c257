//! An object found to be part of another ([`crate::objects::instance_association::ObjectMerge`]):
//! what the map kept of its sightings — class votes, keyframes, visible frames, depth coverage
//! and observed cloud — is taken into the object that keeps its id. Its box, field and class
//! registration follow from those (their stages see the grown cloud and keyframes).

use std::collections::BTreeMap;

use rand::Rng;

use crate::ids::ClassId;
use crate::objects::config::KeyframeConfig;
use crate::objects::frame_observation::{DepthCoverage, majority_class};
use crate::objects::keyframes::KeyframeWindow;
use crate::objects::object_view::ObjectView;
use crate::objects::observed_cloud::ObservedCloud;

/// What the map keeps of an object's sightings, borrowed from where it is kept.
pub struct Sightings<'a> {
    /// Pixel votes per class over every view.
    pub class_votes: &'a mut BTreeMap<ClassId, u64>,
    /// Its keyframe window.
    pub keyframes: &'a mut KeyframeWindow<ObjectView>,
    /// Frames it was seen in.
    pub visible_frames: &'a mut u64,
    /// Its mask pixels and those with a depth.
    pub depth_coverage: &'a mut DepthCoverage,
    /// Its observed cloud.
    pub cloud: &'a mut ObservedCloud,
}

/// Takes `absorbed` into `kept` (left empty: its object is gone). Keyframes of one frame in both
/// windows become one view; beyond the window's capacity the newest are kept
/// ([`KeyframeWindow::absorb`]). Every kept view's pixels of other objects become unsure
/// ([`ObjectView::others_unsure`]): in a frame that showed the two apart, each saw the other's
/// surface as another object's. Returns the merged object's majority class.
pub fn absorb_sightings(
    kept: Sightings<'_>,
    absorbed: Sightings<'_>,
    cfg: &KeyframeConfig,
    rng: &mut impl Rng,
) -> Option<ClassId> {
    for (&class, &n) in absorbed.class_votes.iter() {
        *kept.class_votes.entry(class).or_default() += n;
    }
    absorbed.class_votes.clear();
    let mut window = std::mem::take(absorbed.keyframes);
    kept.keyframes
        .data_mut()
        .chain(window.data_mut())
        .for_each(ObjectView::others_unsure);
    kept.keyframes
        .absorb(window, cfg.capacity, rng, |mine, theirs| mine.absorb(&theirs));
    *kept.visible_frames += std::mem::take(absorbed.visible_frames);
    kept.depth_coverage.absorb(std::mem::take(absorbed.depth_coverage));
    kept.cloud.absorb(absorbed.cloud);
    *absorbed.cloud = ObservedCloud::new(absorbed.cloud.voxel_m());
    majority_class(kept.class_votes)
}

#[cfg(test)]
mod tests {
    use nalgebra::Point3;

    use super::*;
    use crate::ids::FrameIndex;
    use crate::objects::keyframes::KeyframeRole;
    use crate::objects::object_view::PixelState;
    use crate::objects::view_fixtures::render;
    use crate::rng::{RngStream, seeded_rng};

    /// A small view of frame `frame`.
    fn view_of(frame: FrameIndex) -> ObjectView {
        ObjectView {
            frame,
            ..render([0.0, -2.0, 0.5], 0.0, &[])
        }
    }

    struct Owned {
        votes: BTreeMap<ClassId, u64>,
        keyframes: KeyframeWindow<ObjectView>,
        visible: u64,
        coverage: DepthCoverage,
        cloud: ObservedCloud,
    }

    impl Owned {
        /// An object seen in `frames` (each a keyframe) with `votes`, its cloud one point per frame.
        fn seen(frames: &[u64], votes: &[(u32, u64)], x: f32, states: PixelState) -> Self {
            let cfg = KeyframeConfig {
                object_stride: 1,
                ..KeyframeConfig::default()
            };
            let mut rng = seeded_rng(0, RngStream::Object(crate::ids::ObjectId(1)));
            let mut keyframes = KeyframeWindow::default();
            let mut cloud = ObservedCloud::new(0.01);
            for &f in frames {
                let mut view = view_of(FrameIndex(f));
                view.states.fill(states);
                keyframes.offer(FrameIndex(f), view, KeyframeRole::Object, &cfg, &mut rng);
                cloud.add_point(&Point3::new(x, f as f32, 0.0));
            }
            Self {
                votes: votes.iter().map(|&(c, n)| (ClassId(c), n)).collect(),
                keyframes,
                visible: frames.len() as u64,
                coverage: DepthCoverage {
                    pixels: 10 * frames.len() as u64,
                    with_depth: 9 * frames.len() as u64,
                },
                cloud,
            }
        }

        fn sightings(&mut self) -> Sightings<'_> {
            Sightings {
                class_votes: &mut self.votes,
                keyframes: &mut self.keyframes,
                visible_frames: &mut self.visible,
                depth_coverage: &mut self.coverage,
                cloud: &mut self.cloud,
            }
        }
    }

    #[test]
    fn the_kept_object_takes_every_sighting_and_one_frame_seen_by_both_becomes_one_view() {
        let mut kept = Owned::seen(&[0, 2, 4], &[(30, 100), (20, 30)], 0.0, PixelState::OtherObject);
        let mut absorbed = Owned::seen(&[4, 6, 8, 10], &[(20, 50), (30, 10)], 1.0, PixelState::ThisObject);
        let cfg = KeyframeConfig::default();
        let mut rng = seeded_rng(0, RngStream::Object(crate::ids::ObjectId(1)));
        let class = absorb_sightings(kept.sightings(), absorbed.sightings(), &cfg, &mut rng);
        assert_eq!(class, Some(ClassId(30)), "110 votes against 80");
        assert_eq!(kept.keyframes.frames(), [0, 2, 4, 6, 8, 10].map(FrameIndex));
        let frame_4 = &kept.keyframes.slots()[2].data;
        assert!(
            frame_4.states.iter().all(|&s| s == PixelState::ThisObject),
            "what showed the absorbed object in frame 4 shows the kept one"
        );
        let frame_2 = &kept.keyframes.slots()[1].data;
        assert!(
            frame_2.states.iter().all(|&s| s == PixelState::Unsure),
            "what the kept object saw as another object's may be the absorbed one's: unsure"
        );
        assert_eq!(kept.keyframes.recent_slots(), [4, 5]);
        assert_eq!((kept.visible, kept.keyframes.visible_count()), (7, 7));
        assert_eq!(
            kept.coverage,
            DepthCoverage {
                pixels: 70,
                with_depth: 63
            }
        );
        assert_eq!(kept.cloud.len(), 7, "three points and four (frame 4's twice)");
        assert_eq!(kept.cloud.points_added(), 7);
        assert!(absorbed.cloud.is_empty() && absorbed.keyframes.is_empty() && absorbed.votes.is_empty());
    }

    #[test]
    fn windows_over_capacity_keep_the_two_newest_and_thin_the_older_evenly() {
        let mut kept = Owned::seen(&[0, 1, 2, 3, 4], &[(20, 1)], 0.0, PixelState::ThisObject);
        let mut absorbed = Owned::seen(&[5, 6, 7, 8, 9, 10, 11], &[(20, 1)], 1.0, PixelState::ThisObject);
        let cfg = KeyframeConfig {
            capacity: 5,
            ..KeyframeConfig::default()
        };
        let mut rng = seeded_rng(0, RngStream::Object(crate::ids::ObjectId(1)));
        absorb_sightings(kept.sightings(), absorbed.sightings(), &cfg, &mut rng);
        assert_eq!(kept.keyframes.frames(), [0, 3, 6, 10, 11].map(FrameIndex));
        assert_eq!(kept.keyframes.recent_slots(), [3, 4]);
    }
}
