//! catmap's own Kinect-like camera and segmenter (`catmap synth --noise kinect`): the model the
//! mapper's camera and segmenter settings were first tuned on, kept as it was so that earlier
//! measurements stay reproducible. In this order:
//! 1. **Holes at depth edges**: a pixel whose depth differs from a 4-neighbour's by more than
//!    `edge_jump_m` loses its depth with probability `edge_hole_probability`.
//! 2. **Depth noise growing with distance**: z + N(0, σ(z)²) with σ(z) = a + b·(z − z₀)², the
//!    axial model measured for the Kinect v1 (Nguyen, Izadi and Lovell, 3DIMPVT 2012); beyond
//!    `max_range_m` no depth; `dropout_probability` of the other pixels lose theirs at random.
//! 3. **Mask boundary jitter**: each object's mask grows (into pixels of no object) or shrinks
//!    (its border pixels become unlabelled) by a whole number of pixels drawn in
//!    `−mask_jitter_px..=mask_jitter_px`, per object and frame.
//! 4. **Missed masks**: with probability `mask_miss_probability` an object is not segmented in a
//!    frame (its pixels unlabelled; the depth stays).
//! 5. **Class confusion**: with probability `class_confusion_probability` an object's mask carries
//!    another of the scene's object classes in a frame.

use std::collections::BTreeMap;

use rand::RngExt;

use super::is_object;
use crate::ids::ClassId;
use crate::rng::standard_normal_f32;
use crate::synth::render::RenderedFrame;

/// The Kinect-like model's parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KinectNoise {
    /// σ(z) = `sigma_base_m` + `sigma_quadratic_per_m` · (z − `sigma_offset_m`)², metres
    /// (0.0012, 0.0019, 0.4: 1.5 mm at 0.8 m, 6.6 mm at 2 m, 18 mm at 3.5 m).
    pub sigma_base_m: f32,
    /// See `sigma_base_m`.
    pub sigma_quadratic_per_m: f32,
    /// See `sigma_base_m`.
    pub sigma_offset_m: f32,
    /// No depth beyond this, metres (5.0).
    pub max_range_m: f32,
    /// A depth step larger than this to a 4-neighbour makes a pixel an edge pixel, metres (0.04).
    pub edge_jump_m: f32,
    /// Chance an edge pixel loses its depth (0.6).
    pub edge_hole_probability: f32,
    /// Chance any other pixel loses its depth (0.005).
    pub dropout_probability: f32,
    /// Largest growth or shrinkage of a mask, pixels (2).
    pub mask_jitter_px: u32,
    /// Chance an object is not segmented in a frame (0.05).
    pub mask_miss_probability: f32,
    /// Chance an object's mask carries another class in a frame (0.02).
    pub class_confusion_probability: f32,
}

impl Default for KinectNoise {
    fn default() -> Self {
        Self {
            sigma_base_m: 0.0012,
            sigma_quadratic_per_m: 0.0019,
            sigma_offset_m: 0.4,
            max_range_m: 5.0,
            edge_jump_m: 0.04,
            edge_hole_probability: 0.6,
            dropout_probability: 0.005,
            mask_jitter_px: 2,
            mask_miss_probability: 0.05,
            class_confusion_probability: 0.02,
        }
    }
}

impl KinectNoise {
    /// Axial depth noise at depth `z_m`, metres.
    pub fn sigma_m(&self, z_m: f32) -> f32 {
        self.sigma_base_m + self.sigma_quadratic_per_m * (z_m - self.sigma_offset_m).powi(2)
    }
}

/// Steps 1 and 2 of the module doc.
pub(super) fn degrade_depth(frame: &mut RenderedFrame, noise: &KinectNoise, rng: &mut impl rand::Rng) {
    let (w, h) = (frame.intrinsics.width as usize, frame.intrinsics.height as usize);
    let clean = frame.depth_m.clone();
    let jump = |a: f32, b: f32| a > 0.0 && b > 0.0 && (a - b).abs() > noise.edge_jump_m;
    for (i, depth) in frame.depth_m.iter_mut().enumerate() {
        let z = clean[i];
        if z <= 0.0 {
            continue;
        }
        let (u, v) = (i % w, i / w);
        let edge = (u > 0 && jump(z, clean[i - 1]))
            || (u + 1 < w && jump(z, clean[i + 1]))
            || (v > 0 && jump(z, clean[i - w]))
            || (v + 1 < h && jump(z, clean[i + w]));
        let hole = if edge {
            noise.edge_hole_probability
        } else {
            noise.dropout_probability
        };
        let noisy = z + noise.sigma_m(z) * standard_normal_f32(rng);
        *depth = if rng.random::<f32>() < hole || z > noise.max_range_m || noisy <= 0.0 {
            0.0
        } else {
            noisy
        };
    }
}

/// Steps 3–5 of the module doc, objects in id order.
pub(super) fn degrade_masks(
    frame: &mut RenderedFrame,
    noise: &KinectNoise,
    classes: &[ClassId],
    rng: &mut impl rand::Rng,
) {
    let (w, h) = (frame.intrinsics.width as i64, frame.intrinsics.height as i64);
    let mut pixels: BTreeMap<u16, Vec<usize>> = BTreeMap::new();
    for i in 0..frame.instance_ids.len() {
        if is_object(frame, i) {
            pixels.entry(frame.instance_ids[i]).or_default().push(i);
        }
    }
    let original_ids = frame.instance_ids.clone();
    let original_object: Vec<bool> = (0..original_ids.len()).map(|i| is_object(frame, i)).collect();
    let reach = i64::from(noise.mask_jitter_px);
    for (&id, own) in &pixels {
        let jitter = rng.random_range(-reach..=reach);
        let missed = rng.random::<f32>() < noise.mask_miss_probability;
        let confused = rng.random::<f32>() < noise.class_confusion_probability;
        let class = frame.classes[own[0]];
        let others: Vec<ClassId> = classes.iter().copied().filter(|&c| c != class).collect();
        let said = if confused && !others.is_empty() {
            others[rng.random_range(0..others.len())]
        } else {
            class
        };
        let near = |i: usize, r: i64, hit: &dyn Fn(usize) -> bool| {
            let (u, v) = ((i as i64) % w, (i as i64) / w);
            (-r..=r).any(|dv| {
                (-r..=r).any(|du| {
                    let (x, y) = (u + du, v + dv);
                    x >= 0 && y >= 0 && x < w && y < h && hit((y * w + x) as usize)
                })
            })
        };
        let mut members: Vec<usize> = if jitter < 0 {
            let outside = |j: usize| original_ids[j] != id || !original_object[j];
            own.iter().copied().filter(|&i| !near(i, -jitter, &outside)).collect()
        } else {
            own.clone()
        };
        if jitter > 0 {
            let mut grown: Vec<usize> = own
                .iter()
                .flat_map(|&i| {
                    let (u, v) = ((i as i64) % w, (i as i64) / w);
                    (-jitter..=jitter).flat_map(move |dv| (-jitter..=jitter).map(move |du| (u + du, v + dv)))
                })
                .filter(|&(x, y)| x >= 0 && y >= 0 && x < w && y < h)
                .map(|(x, y)| (y * w + x) as usize)
                .filter(|&j| !original_object[j] && !is_object(frame, j))
                .collect();
            grown.sort_unstable();
            grown.dedup();
            members.extend(grown);
        }
        for &i in own {
            frame.instance_ids[i] = 0;
            frame.classes[i] = ClassId(0);
        }
        if !missed {
            for &i in &members {
                frame.instance_ids[i] = id;
                frame.classes[i] = said;
            }
        }
    }
}
