//! Edge-preserving smoothing of a depth image, before anything reads it (`dataset.depth_smoothing`).
//!
//! A depth camera's noise grows with distance (a Kinect's σ is ~2 mm at 1 m and ~14 mm at 3 m)
//! and is mostly independent from pixel to pixel; fields trained on it grow bumps, and the
//! boxes and hidden-space evidence built from the observed clouds grow with its outliers.
//! [`DepthSmoothing::Bilateral`] replaces each valid pixel by a weighted mean of the valid pixels
//! in a square window, as KinectFusion does before anything else: the weight of a neighbour falls
//! with its distance in the image (`spatial_sigma_px`) and with its depth difference, in units of
//! `range_sigma_m_at_1m · z²` at the pixel's depth z (the noise's quadratic growth). A depth edge
//! — a step of several range sigmas — keeps both sides apart; invalid pixels (0) stay invalid and
//! take no part.

use serde::{Deserialize, Serialize};

/// How depth images are smoothed before use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DepthSmoothing {
    /// Depth as read (the default: exact depth, Replica's and the synthetic scenes').
    #[default]
    None,
    /// The bilateral filter of [`BilateralDepth`] (a depth camera's noise).
    Bilateral,
}

/// What the depth images are like (`catmap run --depth`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DepthImages {
    /// Exact, as rendered (Replica, the synthetic scenes without noise).
    Exact,
    /// A depth camera's: noise growing with distance, stray points, no depth beyond its range.
    Camera,
}

/// The bilateral filter's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BilateralDepth {
    /// Half the window's edge, pixels (2: a 5 × 5 window).
    pub radius_px: u32,
    /// Standard deviation of the spatial weight, pixels.
    pub spatial_sigma_px: f32,
    /// Standard deviation of the depth weight at 1 m, metres; it grows with the square of depth.
    pub range_sigma_m_at_1m: f32,
}

impl Default for BilateralDepth {
    fn default() -> Self {
        Self {
            radius_px: 2,
            spatial_sigma_px: 1.5,
            range_sigma_m_at_1m: 0.006,
        }
    }
}

impl BilateralDepth {
    /// Why the parameters are invalid, if they are.
    pub fn invalid(&self) -> Option<&'static str> {
        if self.radius_px == 0 || self.radius_px > 8 {
            Some("dataset.bilateral.radius_px must be between 1 and 8")
        } else if !(self.spatial_sigma_px > 0.0 && self.spatial_sigma_px <= 16.0) {
            Some("dataset.bilateral.spatial_sigma_px must be above 0 and at most 16")
        } else if !(self.range_sigma_m_at_1m > 0.0 && self.range_sigma_m_at_1m <= 1.0) {
            Some("dataset.bilateral.range_sigma_m_at_1m must be above 0 and at most 1")
        } else {
            None
        }
    }

    /// `depth_m` (row-major, `width` × `height`, 0 = invalid) smoothed.
    pub fn smooth(&self, depth_m: &[f32], width: usize, height: usize) -> Vec<f32> {
        debug_assert_eq!(depth_m.len(), width * height);
        let r = self.radius_px as isize;
        let spatial: Vec<f32> = (-r..=r)
            .flat_map(|dv| (-r..=r).map(move |du| (du, dv)))
            .map(|(du, dv)| (-((du * du + dv * dv) as f32) / (2.0 * self.spatial_sigma_px.powi(2))).exp())
            .collect();
        let side = (2 * r + 1) as usize;
        let (w, h) = (width as isize, height as isize);
        let mut out = vec![0.0; depth_m.len()];
        for v in 0..h {
            for u in 0..w {
                let i = (v * w + u) as usize;
                let z = depth_m[i];
                if z <= 0.0 {
                    continue;
                }
                let range_sigma = self.range_sigma_m_at_1m * z * z;
                let inv_two_var = 1.0 / (2.0 * range_sigma * range_sigma);
                let (mut sum, mut weight) = (0.0f32, 0.0f32);
                for dv in -r..=r {
                    let y = v + dv;
                    if !(0..h).contains(&y) {
                        continue;
                    }
                    for du in -r..=r {
                        let x = u + du;
                        if !(0..w).contains(&x) {
                            continue;
                        }
                        let zn = depth_m[(y * w + x) as usize];
                        if zn <= 0.0 {
                            continue;
                        }
                        let dz = zn - z;
                        let k = spatial[(dv + r) as usize * side + (du + r) as usize] * (-dz * dz * inv_two_var).exp();
                        sum += k * zn;
                        weight += k;
                    }
                }
                out[i] = sum / weight;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    use super::*;
    use crate::rng::standard_normal_f32;

    fn noisy_step(seed: u64) -> (Vec<f32>, Vec<f32>, usize, usize) {
        let (w, h) = (40, 30);
        let mut rng = StdRng::seed_from_u64(seed);
        let truth: Vec<f32> = (0..w * h).map(|i| if i % w < 20 { 2.0 } else { 2.5 }).collect();
        let noisy = truth
            .iter()
            .map(|&z| z + 0.0061 * standard_normal_f32(&mut rng))
            .collect();
        (truth, noisy, w, h)
    }

    fn rms(a: &[f32], b: &[f32], keep: impl Fn(usize) -> bool) -> f32 {
        let (mut s, mut n) = (0.0, 0.0);
        for i in (0..a.len()).filter(|&i| keep(i)) {
            s += (a[i] - b[i]).powi(2);
            n += 1.0;
        }
        (s / n).sqrt()
    }

    #[test]
    fn noise_on_a_plane_falls_and_a_depth_step_stays_sharp() {
        let (truth, noisy, w, h) = noisy_step(7);
        let smoothed = BilateralDepth::default().smooth(&noisy, w, h);
        let before = rms(&truth, &noisy, |_| true);
        let after = rms(&truth, &smoothed, |_| true);
        assert!(after < 0.5 * before, "rms {before} → {after}");
        for v in 0..h {
            let (near, far) = (smoothed[v * w + 19], smoothed[v * w + 20]);
            assert!(
                (near - 2.0).abs() < 0.02 && (far - 2.5).abs() < 0.02,
                "row {v}: {near} | {far}"
            );
        }
    }

    #[test]
    fn invalid_pixels_stay_invalid_and_take_no_part() {
        let (w, h) = (5, 5);
        let mut depth = vec![1.0; w * h];
        depth[12] = 0.0;
        depth[0] = 0.0;
        let smoothed = BilateralDepth::default().smooth(&depth, w, h);
        assert_eq!(smoothed[12], 0.0);
        assert_eq!(smoothed[0], 0.0);
        assert!(
            smoothed
                .iter()
                .enumerate()
                .all(|(i, &z)| i == 0 || i == 12 || (z - 1.0).abs() < 1e-6)
        );
    }

    #[test]
    fn the_parameters_are_checked() {
        assert_eq!(BilateralDepth::default().invalid(), None);
        let zero = BilateralDepth {
            radius_px: 0,
            ..BilateralDepth::default()
        };
        assert!(zero.invalid().is_some());
        let nan = BilateralDepth {
            range_sigma_m_at_1m: f32::NAN,
            ..BilateralDepth::default()
        };
        assert!(nan.invalid().is_some());
    }
}
