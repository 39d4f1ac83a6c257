//! Whether a dataset's instance ids name one object over the sequence or are numbered anew in
//! every frame, read off pairs of consecutive frames: an id that names one object labels the same
//! surface in the next frame, while a per-frame id names whatever its frame's segmenter numbered
//! so.
//!
//! Every [`PIXEL_STRIDE`]th pixel of the first frame with an id and a depth is carried into the
//! next frame (its pose and intrinsics); where the next frame sees that surface (its depth there
//! within [`SAME_SURFACE`] of the point's), the pixel **agrees** when the next frame gives it the
//! same id. An id with at least [`MIN_SEEN`] such pixels agrees when most of them do. The share
//! of agreeing ids is about 1 with consistent ids and near 0 with per-frame ids.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::ids::ObjectId;
use crate::sensor::frame::RgbdFrame;

/// Pixels of the first frame of a pair looked at: one in this many along each row and column.
pub const PIXEL_STRIDE: usize = 2;

/// The next frame sees a point when its depth there is within this share of the point's.
pub const SAME_SURFACE: f32 = 0.05;

/// Pixels of an id the next frame must see for the id to count.
pub const MIN_SEEN: usize = 20;

/// What the pairs of frames showed.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct InstanceIdModel {
    /// Pairs of consecutive frames compared.
    pub pairs: usize,
    /// Ids counted (seen in the next frame by [`MIN_SEEN`] pixels or more).
    pub ids: usize,
    /// Ids most of whose pixels the next frame gave the same id.
    pub agreeing: usize,
}

impl InstanceIdModel {
    /// Share of the counted ids that agreed (`None` without any).
    pub fn agreeing_share(&self) -> Option<f32> {
        (self.ids > 0).then(|| self.agreeing as f32 / self.ids as f32)
    }

    /// True when most ids named one object in both frames of their pair (module doc); with no
    /// evidence, the ids are taken as given.
    pub fn consistent(&self) -> bool {
        self.agreeing_share().is_none_or(|share| share > 0.5)
    }

    /// Counts the pair `first`, `next` (consecutive frames).
    pub fn add_pair(&mut self, first: &RgbdFrame, next: &RgbdFrame) {
        let k = next.intrinsics;
        let next_from_world = next.world_from_camera.inverse();
        let width = first.intrinsics.width as usize;
        // Per id: pixels the next frame sees, and those it gives the same id.
        let mut tally: BTreeMap<ObjectId, (usize, usize)> = BTreeMap::new();
        for i in (0..first.instances.len())
            .filter(|i| (i / width).is_multiple_of(PIXEL_STRIDE) && i.is_multiple_of(PIXEL_STRIDE))
        {
            let (Some(id), Some(world)) = (first.instances.object_at(i), first.point_in_world(i)) else {
                continue;
            };
            let p = next_from_world * world;
            let Some((u, v)) = k.project(&p) else {
                continue;
            };
            let (u, v) = (u.floor(), v.floor());
            if u < 0.0 || v < 0.0 || u >= k.width as f32 || v >= k.height as f32 {
                continue;
            }
            let j = v as usize * k.width as usize + u as usize;
            let depth = next.depth_m.get(j).copied().unwrap_or(0.0);
            if depth <= 0.0 || (depth - p.z).abs() > SAME_SURFACE * p.z {
                continue;
            }
            let e = tally.entry(id).or_default();
            e.0 += 1;
            e.1 += usize::from(next.instances.object_at(j) == Some(id));
        }
        self.pairs += 1;
        for (seen, same) in tally.into_values().filter(|&(seen, _)| seen >= MIN_SEEN) {
            self.ids += 1;
            self.agreeing += usize::from(2 * same > seen);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::FrameSource;
    use crate::synth::{InstanceIds, Preset, SensorModel, SensorSettings, SyntheticScene};

    fn model(sensor: SensorSettings) -> InstanceIdModel {
        let scene = SyntheticScene::generate(1, Preset::Small)
            .expect("small scene")
            .with_sensor(sensor);
        let mut m = InstanceIdModel::default();
        for p in [3, 14, 25] {
            m.add_pair(
                &scene.read_frame(p).expect("frame"),
                &scene.read_frame(p + 1).expect("frame"),
            );
        }
        m
    }

    #[test]
    fn consistent_ids_agree_across_a_pair_and_per_frame_ids_do_not() {
        let exact = model(SensorSettings::default());
        assert!(exact.agreeing_share().expect("ids") > 0.9, "{exact:?}");
        assert!(exact.consistent());
        let kinect = model(SensorSettings::new(SensorModel::Kinect, InstanceIds::Consistent));
        assert!(kinect.agreeing_share().expect("ids") >= 0.6, "{kinect:?}");
        assert!(kinect.consistent());
        for family in [SensorModel::None, SensorModel::Kinect, SensorModel::StructuredLight] {
            let per_frame = model(SensorSettings::new(family, InstanceIds::PerFrame));
            assert!(
                per_frame.agreeing_share().expect("ids") < 0.1,
                "{family:?}: {per_frame:?}"
            );
            assert!(!per_frame.consistent());
        }
        assert!(InstanceIdModel::default().consistent(), "no evidence: as the ids say");
    }
}
