//! How far the instance masks' borders sit from the depth edges they should follow, estimated
//! from the frames: exact masks (rendered, annotated) end where their object's silhouette does; a
//! 2D segmenter's are a pixel or two too large or too small.
//!
//! At every pixel of an object's mask beside a pixel of another label (a border, in one of the
//! four directions), the line through it across the border is searched `SEARCH_PX` pixels each
//! way for the silhouette: a step from a nearer depth inside to a farther one outside by more
//! than 0.1 m + 5 % of the depth (a noisy depth's steps along a surface are far smaller; pixels
//! without a depth are stepped over). The signed distance from the mask's border to the nearest
//! such step is one sample: 0 where they coincide, negative where the mask reaches beyond the
//! silhouette (it takes in what lies behind), positive where it stops short. Borders with no
//! silhouette within reach (an object touching the floor, an occluder in front) give none.
//!
//! The estimate is the share of samples off by at least a pixel and the 90th percentile of how
//! far off they are.

use serde::{Deserialize, Serialize};

use crate::sensor::frame::{InstanceLabel, InstanceMask};

/// How far each way from a border the silhouette is searched, pixels.
const SEARCH_PX: i64 = 4;
/// A silhouette: a step of more than this plus `EDGE_STEP_SHARE` of the depth, metres.
const EDGE_STEP_M: f32 = 0.1;
const EDGE_STEP_SHARE: f32 = 0.05;

/// What the masks' borders are like.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaskBorderModel {
    /// Share of border samples whose silhouette lies a pixel or more away.
    pub off_share: f32,
    /// Share of border samples whose mask reaches beyond the silhouette (onto what lies behind).
    pub beyond_share: f32,
    /// 90th percentile of the distance between a border and its silhouette, pixels.
    pub p90_px: u32,
    /// Border samples the estimate rests on.
    pub samples: u64,
}

/// Accumulates frames into a [`MaskBorderModel`] (module doc).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MaskBorderEstimator {
    /// Samples by signed offset, −`SEARCH_PX`..=`SEARCH_PX` (index + `SEARCH_PX`).
    counts: [u64; (2 * SEARCH_PX + 1) as usize],
}

impl MaskBorderEstimator {
    /// Adds one frame: its labels and depth (metres, 0 where none), `width` pixels a row.
    pub fn add_frame(&mut self, instances: &InstanceMask, depth: &[f32], width: usize) {
        let n = depth.len();
        if instances.len() != n || width == 0 {
            return;
        }
        let height = n / width;
        for i in 0..n {
            let InstanceLabel::Object(id) = instances.label(i) else {
                continue;
            };
            let (u, v) = ((i % width) as i64, (i / width) as i64);
            for (du, dv) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                let (x, y) = (u + du, v + dv);
                if x < 0 || y < 0 || x >= width as i64 || y >= height as i64 {
                    continue;
                }
                if instances.object_at(y as usize * width + x as usize) == Some(id) {
                    continue;
                }
                let depth_at = |t: i64| {
                    let (x, y) = (u + t * du, v + t * dv);
                    if x < 0 || y < 0 || x >= width as i64 || y >= height as i64 {
                        return None;
                    }
                    let d = depth[y as usize * width + x as usize];
                    (d > 0.0 && d.is_finite()).then_some(d)
                };
                if let Some(offset) = silhouette_offset(depth_at) {
                    self.counts[(offset + SEARCH_PX) as usize] += 1;
                }
            }
        }
    }

    /// The borders seen so far; `None` without a sample.
    pub fn estimate(&self) -> Option<MaskBorderModel> {
        let samples: u64 = self.counts.iter().sum();
        if samples == 0 {
            return None;
        }
        let at = |offset: i64| self.counts[(offset + SEARCH_PX) as usize];
        let exact = at(0);
        let beyond: u64 = (-SEARCH_PX..0).map(at).sum();
        let mut by_distance = [0u64; SEARCH_PX as usize + 1];
        for offset in -SEARCH_PX..=SEARCH_PX {
            by_distance[offset.unsigned_abs() as usize] += at(offset);
        }
        let mut below = 0;
        let mut p90_px = SEARCH_PX as u32;
        for (distance, &count) in by_distance.iter().enumerate() {
            below += count;
            if below as f64 >= 0.9 * samples as f64 {
                p90_px = distance as u32;
                break;
            }
        }
        Some(MaskBorderModel {
            off_share: (samples - exact) as f32 / samples as f32,
            beyond_share: beyond as f32 / samples as f32,
            p90_px,
            samples,
        })
    }
}

/// Where the silhouette lies on the line across a border: position 0 is the mask's last pixel,
/// 1 the first outside it, `depth_at(t)` the depth at position t. The step between positions a
/// and b (the next with a depth) is a silhouette when the depth rises by more than the edge step;
/// its offset is the position within [a, b − 1] nearest 0. The silhouette nearest the border
/// wins (the one inside on a tie); none when pixels without a depth hide on which side of the
/// border it lies (a < 0 < b, or a ≤ 0 < b − 1).
fn silhouette_offset(depth_at: impl Fn(i64) -> Option<f32>) -> Option<i64> {
    let mut best: Option<(i64, bool)> = None;
    let mut last: Option<(i64, f32)> = None;
    for t in -SEARCH_PX..=SEARCH_PX {
        let Some(d) = depth_at(t) else {
            continue;
        };
        if let Some((a, near)) = last
            && d - near > EDGE_STEP_M + EDGE_STEP_SHARE * near
        {
            let offset = 0.clamp(a, t - 1);
            let hidden = t > a + 1 && a <= 0 && t > 0;
            if best.is_none_or(|(b, _)| offset.abs() < b.abs()) {
                best = Some((offset, hidden));
            }
        }
        last = Some((t, d));
    }
    best.filter(|&(_, hidden)| !hidden).map(|(offset, _)| offset)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::ObjectId;

    /// A 40 × 30 frame: a wall at 3 m, an object at 1.5 m over columns 10..30 and rows 5..25,
    /// its mask grown (`grow` > 0) or shrunk by `grow` pixels on every side.
    fn frame(grow: i64) -> (InstanceMask, Vec<f32>) {
        let inside = |u: i64, v: i64, by: i64| (10 - by..30 + by).contains(&u) && (5 - by..25 + by).contains(&v);
        let depth = (0..1200)
            .map(|i| if inside(i % 40, i / 40, 0) { 1.5 } else { 3.0 })
            .collect();
        let labels = (0..1200).map(|i| {
            if inside(i % 40, i / 40, grow) {
                InstanceLabel::Object(ObjectId(7))
            } else {
                InstanceLabel::Background
            }
        });
        (InstanceMask::from_labels(labels), depth)
    }

    #[test]
    fn exact_masks_sit_on_their_silhouette() {
        let (mask, depth) = frame(0);
        let mut estimator = MaskBorderEstimator::default();
        estimator.add_frame(&mask, &depth, 40);
        let model = estimator.estimate().expect("borders");
        assert_eq!((model.off_share, model.p90_px), (0.0, 0));
        assert_eq!(
            model.samples,
            2 * (20 + 20),
            "every border pixel once per direction out"
        );
    }

    #[test]
    fn grown_and_shrunk_masks_are_off_by_their_growth() {
        for (grow, beyond) in [(2, 1.0), (-2, 0.0), (1, 1.0)] {
            let (mask, depth) = frame(grow);
            let mut estimator = MaskBorderEstimator::default();
            estimator.add_frame(&mask, &depth, 40);
            let model = estimator.estimate().expect("borders");
            assert_eq!(model.p90_px, grow.unsigned_abs() as u32, "{grow}: {model:?}");
            assert!(model.off_share > 0.9, "{grow}: {model:?}");
            assert!((model.beyond_share - beyond).abs() < 0.1, "{grow}: {model:?}");
        }
    }

    #[test]
    fn a_hole_across_the_border_and_a_floor_contact_give_no_sample() {
        // The border between positions 0 and 1; no depth at 0 and 1.
        let depth = |t: i64| match t {
            0 | 1 => None,
            t if t < 0 => Some(1.5),
            _ => Some(3.0),
        };
        assert_eq!(
            silhouette_offset(depth),
            None,
            "which side the silhouette is on is hidden"
        );
        let beyond = |t: i64| match t {
            2 => None,
            t if t < 2 => Some(1.5),
            _ => Some(3.0),
        };
        assert_eq!(
            silhouette_offset(beyond),
            Some(1),
            "a hole outside the border: at least 1 px off"
        );
        assert_eq!(silhouette_offset(|_| Some(2.0)), None, "no step");
        assert_eq!(silhouette_offset(|t| Some(if t < 3 { 1.5 } else { 3.0 })), Some(2));
        assert_eq!(silhouette_offset(|t| Some(if t < -1 { 1.5 } else { 3.0 })), Some(-2));
    }
}
