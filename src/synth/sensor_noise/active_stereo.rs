//! An active stereo depth camera (Intel RealSense D4xx): two infrared imagers `baseline_m` apart
//! match a projected dot pattern along the rows; the depth is f·b over the disparity.
//!
//! In this order, on the rendered depth:
//! 1. **Edges fattened**: a pixel within `fattening_px` (at 640 px wide) of a pixel nearer by
//!    more than `fattening_jump_m` takes the nearer depth (the matching window straddles the
//!    edge and the nearer surface's texture wins).
//! 2. **The second imager's occlusions**: what the right imager cannot see, behind an object or
//!    beyond the left edge of its view, has no depth.
//! 3. **Range**: nothing nearer than `min_range_m` or farther than `max_range_m`.
//! 4. **Holes on dark surfaces and where the pattern fades**: a pixel whose colour is darker than
//!    `dark_luminance` loses its depth with a chance rising to `dark_hole_probability` at black
//!    (infrared absorbed); one on a textureless patch (3 × 3 luminance range below
//!    `textureless_range`) farther than `pattern_fade_start_m` with a chance rising to
//!    `fade_hole_probability` at `max_range_m` (the projected dots too faint to match).
//! 5. **Disparity noise**: the disparity f·b/z plus N(0, `subpixel_rms_px`²), so σ(z) ≈
//!    z²·σ_s/(f·b): f = 424 px (848 × 480), b = 50 mm, σ_s = 0.08 px — 3.8 mm at 1 m, 15 mm at
//!    2 m (Grunnet-Jepsen, Sweetser and Woodfill, *Tuning depth cameras for best performance*,
//!    Intel RealSense white paper, 2018: RMS error = z²·subpixel/(f·b), subpixel ≈ 0.08).

use rand::RngExt;

use super::depth_image::{hidden_from_baseline, luminance};
use crate::rng::standard_normal_f32;
use crate::synth::render::RenderedFrame;

/// The active stereo camera's parameters (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveStereo {
    /// Between the two imagers, metres (0.05).
    pub baseline_m: f32,
    /// The sensor's own focal length, pixels (424, at 848 px wide).
    pub sensor_focal_px: f32,
    /// Disparity error, pixels RMS (0.08).
    pub subpixel_rms_px: f32,
    /// Nearest depth returned, metres (0.3).
    pub min_range_m: f32,
    /// Farthest depth returned, metres (6.0).
    pub max_range_m: f32,
    /// How far a nearer surface's depth spreads over a farther one, pixels at 640 px wide (2).
    pub fattening_px: f32,
    /// A nearer surface spreads over a farther one that lies beyond it by more than this, metres
    /// (0.05).
    pub fattening_jump_m: f32,
    /// Below this luminance (0–1) a surface is dark (0.15).
    pub dark_luminance: f32,
    /// Chance a black pixel loses its depth (0.9).
    pub dark_hole_probability: f32,
    /// A 3 × 3 luminance range below this is textureless (0.02).
    pub textureless_range: f32,
    /// Beyond this depth the pattern fades on textureless surfaces, metres (3.5).
    pub pattern_fade_start_m: f32,
    /// Chance a textureless pixel at `max_range_m` loses its depth (0.6).
    pub fade_hole_probability: f32,
}

impl Default for ActiveStereo {
    fn default() -> Self {
        Self {
            baseline_m: 0.05,
            sensor_focal_px: 424.0,
            subpixel_rms_px: 0.08,
            min_range_m: 0.3,
            max_range_m: 6.0,
            fattening_px: 2.0,
            fattening_jump_m: 0.05,
            dark_luminance: 0.15,
            dark_hole_probability: 0.9,
            textureless_range: 0.02,
            pattern_fade_start_m: 3.5,
            fade_hole_probability: 0.6,
        }
    }
}

impl ActiveStereo {
    /// σ(z) ≈ z²·σ_s/(f·b), metres.
    pub fn sigma_m(&self, z_m: f32) -> f32 {
        z_m * z_m * self.subpixel_rms_px / (self.sensor_focal_px * self.baseline_m)
    }

    /// Degrades `frame`'s depth (module doc).
    pub fn degrade(&self, frame: &mut RenderedFrame, rng: &mut impl rand::Rng) {
        let k = frame.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let fattened = self.fattened(&frame.depth_m, w, h);
        let hidden = hidden_from_baseline(&fattened, &k, self.baseline_m, true);
        let light: Vec<f32> = frame.rgb.iter().map(|&c| luminance(c)).collect();
        let fb = self.sensor_focal_px * self.baseline_m;
        for (i, depth) in frame.depth_m.iter_mut().enumerate() {
            let z = fattened[i];
            if z <= 0.0 {
                *depth = 0.0;
                continue;
            }
            let dark = ((self.dark_luminance - light[i]) / self.dark_luminance).clamp(0.0, 1.0);
            let fade = if self.textureless(&light, w, h, i) {
                ((z - self.pattern_fade_start_m) / (self.max_range_m - self.pattern_fade_start_m)).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let hole_chance = (dark * self.dark_hole_probability).max(fade * self.fade_hole_probability);
            let disparity = fb / z + self.subpixel_rms_px * standard_normal_f32(rng);
            let holed = rng.random::<f32>() < hole_chance;
            *depth = if hidden[i] || holed || z < self.min_range_m || z > self.max_range_m || disparity <= 0.0 {
                0.0
            } else {
                fb / disparity
            };
        }
    }

    /// Step 1: every pixel takes the nearest depth within the fattening radius that lies before
    /// its own by more than the jump.
    fn fattened(&self, depth: &[f32], w: usize, h: usize) -> Vec<f32> {
        let r = (self.fattening_px * w as f32 / 640.0).round() as i64;
        (0..w * h)
            .map(|i| {
                let z = depth[i];
                let (u, v) = ((i % w) as i64, (i / w) as i64);
                let mut nearest = z;
                if z <= 0.0 {
                    return z;
                }
                for dv in -r..=r {
                    for du in -r..=r {
                        let (x, y) = (u + du, v + dv);
                        if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                            continue;
                        }
                        let d = depth[y as usize * w + x as usize];
                        if d > 0.0 && d < z - self.fattening_jump_m {
                            nearest = nearest.min(d);
                        }
                    }
                }
                nearest
            })
            .collect()
    }

    /// Whether the 3 × 3 luminance range around pixel `i` is below `textureless_range`.
    fn textureless(&self, light: &[f32], w: usize, h: usize, i: usize) -> bool {
        let (u, v) = (i % w, i / w);
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for y in v.saturating_sub(1)..(v + 2).min(h) {
            for x in u.saturating_sub(1)..(u + 2).min(w) {
                lo = lo.min(light[y * w + x]);
                hi = hi.max(light[y * w + x]);
            }
        }
        hi - lo < self.textureless_range
    }
}
