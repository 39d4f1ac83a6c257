//! A depth camera's noise, estimated from its own frames: σ(d) = σ₀ + k·d² and the farthest
//! depth it returns.
//!
//! Every frame is cut into 7 × 7 px patches; a patch whose 49 pixels all have a depth, with no
//! step of more than 10 % of the depth between neighbours (a depth edge), is fitted with a plane
//! (inverse depth is affine in the pixel coordinates on a plane, so the fit is a linear
//! least-squares one). When that plane faces the camera within 45° (σ is the noise along the ray
//! on a surface seen head on; at grazing angles it grows), the root mean square of its depth
//! residuals (over 49 − 3 degrees of freedom) is one sample of σ at the patch's depth. Most
//! patches of an indoor scene lie on one surface; those across a small step or on a curved part
//! give large residuals, so each 0.25 m depth bin keeps the **median** of its samples (a histogram of log σ, so memory stays fixed
//! however long the stream). σ₀ and k are then fitted to the bins' medians by least squares on
//! the relative error, each bin weighted by the square root of its patch count.
//!
//! The range is the depth below which 99.9 % of the valid depths lie.
//!
//! Exact depth gives σ ≈ 0 (the quantisation of its files); a camera's noise its σ(d) within
//! the tolerance the tests state for each camera family of [`crate::synth::sensor_noise`].

use serde::{Deserialize, Serialize};

use crate::sensor::frame::CameraIntrinsics;

/// Side of a patch, pixels.
const PATCH: usize = 7;
/// Width of a depth bin, metres.
const BIN_M: f32 = 0.25;
/// Depth bins (to 10 m).
const DEPTH_BINS: usize = 40;
/// Log-σ bins per decade, and the decades from 10 µm to 1 m.
const PER_DECADE: f32 = 40.0;
const SIGMA_BINS: usize = 200;
const LOG_SIGMA_MIN: f32 = -5.0;
/// Range histogram: 5 cm bins to 20 m; every 4th pixel in each direction.
const RANGE_BIN_M: f32 = 0.05;
const RANGE_BINS: usize = 400;
const RANGE_STRIDE: usize = 4;
/// Patches a depth bin needs before its median counts.
pub const MIN_PATCHES_PER_BIN: u32 = 40;
/// A step between neighbours of more than this share of the depth is a depth edge.
const EDGE_STEP: f32 = 0.1;
/// Largest angle between a patch's plane and the ray to it, as its cosine (45°).
const MIN_FACING_COS: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// A depth camera's noise: σ(d) = `sigma_floor_m` + `sigma_per_m2` · d², and its range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthNoiseModel {
    /// σ at zero depth, metres.
    pub sigma_floor_m: f32,
    /// σ's growth with the square of the depth, metres per square metre.
    pub sigma_per_m2: f32,
    /// The farthest depth returned, metres.
    pub range_m: f32,
}

impl DepthNoiseModel {
    /// σ at depth `d_m`, metres.
    pub fn sigma_m(&self, d_m: f32) -> f32 {
        self.sigma_floor_m + self.sigma_per_m2 * d_m * d_m
    }

    /// Exact depth: no noise, no range.
    pub fn exact() -> Self {
        Self {
            sigma_floor_m: 0.0,
            sigma_per_m2: 0.0,
            range_m: f32::INFINITY,
        }
    }
}

/// One depth bin's estimate: its centre, the median of its patches' σ, and how many there were.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthNoiseBin {
    /// Centre of the bin, metres.
    pub depth_m: f32,
    /// Median σ of its patches, metres.
    pub sigma_m: f32,
    /// Patches in the bin.
    pub patches: u32,
}

/// Accumulates frames' depth images into a [`DepthNoiseModel`] (module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DepthNoiseEstimator {
    /// Per depth bin, a histogram of log σ.
    sigma_counts: Vec<Vec<u32>>,
    /// Histogram of valid depths.
    range_counts: Vec<u64>,
    /// Pixels seen, and those with a depth.
    pixels: u64,
    valid: u64,
}

impl Default for DepthNoiseEstimator {
    fn default() -> Self {
        Self {
            sigma_counts: vec![vec![0; SIGMA_BINS]; DEPTH_BINS],
            range_counts: vec![0; RANGE_BINS],
            pixels: 0,
            valid: 0,
        }
    }
}

impl DepthNoiseEstimator {
    /// Adds one depth image (metres, 0 where there is none) of a camera with intrinsics `k`.
    pub fn add_frame(&mut self, depth: &[f32], k: &CameraIntrinsics) {
        let (w, h) = (k.width as usize, k.height as usize);
        if depth.len() != w * h {
            return;
        }
        self.pixels += depth.len() as u64;
        self.valid += depth.iter().filter(|&&d| d > 0.0 && d.is_finite()).count() as u64;
        for v in (0..h).step_by(RANGE_STRIDE) {
            for u in (0..w).step_by(RANGE_STRIDE) {
                let d = depth[v * w + u];
                if d > 0.0 && d.is_finite() {
                    self.range_counts[((d / RANGE_BIN_M) as usize).min(RANGE_BINS - 1)] += 1;
                }
            }
        }
        for v0 in (0..h.saturating_sub(PATCH - 1)).step_by(PATCH) {
            for u0 in (0..w.saturating_sub(PATCH - 1)).step_by(PATCH) {
                if let Some((z, sigma)) = patch_sigma(depth, k, u0, v0) {
                    let bin = (z / BIN_M) as usize;
                    if bin < DEPTH_BINS {
                        self.sigma_counts[bin][sigma_bin(sigma)] += 1;
                    }
                }
            }
        }
    }

    /// The depth bins with at least [`MIN_PATCHES_PER_BIN`] patches, nearest first.
    pub fn bins(&self) -> Vec<DepthNoiseBin> {
        self.sigma_counts
            .iter()
            .enumerate()
            .filter_map(|(b, counts)| {
                let patches: u32 = counts.iter().sum();
                (patches >= MIN_PATCHES_PER_BIN).then(|| DepthNoiseBin {
                    depth_m: (b as f32 + 0.5) * BIN_M,
                    sigma_m: histogram_median(counts),
                    patches,
                })
            })
            .collect()
    }

    /// Share of the pixels seen that had a depth (1 before any frame).
    pub fn valid_share(&self) -> f32 {
        if self.pixels == 0 {
            1.0
        } else {
            self.valid as f32 / self.pixels as f32
        }
    }

    /// The noise model the frames so far support; `None` before any depth bin has enough
    /// patches.
    pub fn estimate(&self) -> Option<DepthNoiseModel> {
        let bins = self.bins();
        let (sigma_floor_m, sigma_per_m2) = fit_floor_and_quadratic(&bins)?;
        Some(DepthNoiseModel {
            sigma_floor_m,
            sigma_per_m2,
            range_m: self.range_m(),
        })
    }

    /// The depth below which 99.9 % of the valid depths lie (the top of its 5 cm bin).
    fn range_m(&self) -> f32 {
        let total: u64 = self.range_counts.iter().sum();
        if total == 0 {
            return f32::INFINITY;
        }
        let mut below = 0;
        for (b, &count) in self.range_counts.iter().enumerate() {
            below += count;
            if below as f64 >= 0.999 * total as f64 {
                return (b + 1) as f32 * RANGE_BIN_M;
            }
        }
        RANGE_BINS as f32 * RANGE_BIN_M
    }
}

/// The patch at (`u0`, `v0`): its centre depth and the RMS of its depth residuals about the
/// plane of its points, when all its pixels have a depth, none steps by more than
/// [`EDGE_STEP`] of its depth to a neighbour, and the plane faces the camera within 45°.
fn patch_sigma(depth: &[f32], k: &CameraIntrinsics, u0: usize, v0: usize) -> Option<(f32, f32)> {
    let w = k.width as usize;
    let half = (PATCH / 2) as f64;
    let mut inverse = [0.0f64; PATCH * PATCH];
    for dv in 0..PATCH {
        for du in 0..PATCH {
            let d = depth[(v0 + dv) * w + u0 + du];
            if !(d > 0.0 && d.is_finite()) {
                return None;
            }
            let step = |other: f32| (other - d).abs() > EDGE_STEP * d;
            if (du > 0 && step(depth[(v0 + dv) * w + u0 + du - 1]))
                || (dv > 0 && step(depth[(v0 + dv - 1) * w + u0 + du]))
            {
                return None;
            }
            inverse[dv * PATCH + du] = 1.0 / f64::from(d);
        }
    }
    // Centred coordinates on a full square grid: the normal equations are diagonal.
    let n = (PATCH * PATCH) as f64;
    let spread: f64 = (0..PATCH).map(|i| (i as f64 - half).powi(2)).sum::<f64>() * PATCH as f64;
    let (mut mean, mut slope_u, mut slope_v) = (0.0, 0.0, 0.0);
    for dv in 0..PATCH {
        for du in 0..PATCH {
            let q = inverse[dv * PATCH + du];
            mean += q;
            slope_u += (du as f64 - half) * q;
            slope_v += (dv as f64 - half) * q;
        }
    }
    let (mean, slope_u, slope_v) = (mean / n, slope_u / spread, slope_v / spread);
    // The plane n·X = 1 has 1/z = n_z + n_x·(u − cx)/fx + n_y·(v − cy)/fy.
    let (x, y) = (
        (u0 as f64 + half - f64::from(k.cx)) / f64::from(k.fx),
        (v0 as f64 + half - f64::from(k.cy)) / f64::from(k.fy),
    );
    let (nx, ny) = (slope_u * f64::from(k.fx), slope_v * f64::from(k.fy));
    let normal = nalgebra::Vector3::new(nx, ny, mean - nx * x - ny * y);
    let ray = nalgebra::Vector3::new(x, y, 1.0);
    if normal.dot(&ray).abs() < MIN_FACING_COS * normal.norm() * ray.norm() {
        return None;
    }
    let mut squares = 0.0;
    for dv in 0..PATCH {
        for du in 0..PATCH {
            let plane = mean + slope_u * (du as f64 - half) + slope_v * (dv as f64 - half);
            if plane <= 0.0 {
                return None;
            }
            squares += (1.0 / inverse[dv * PATCH + du] - 1.0 / plane).powi(2);
        }
    }
    Some(((1.0 / mean) as f32, (squares / (n - 3.0)).sqrt() as f32))
}

fn sigma_bin(sigma: f32) -> usize {
    if sigma <= 0.0 {
        return 0;
    }
    ((sigma.log10() - LOG_SIGMA_MIN) * PER_DECADE).clamp(0.0, (SIGMA_BINS - 1) as f32) as usize
}

/// The median of a log-σ histogram, interpolated within its bin (in log σ).
fn histogram_median(counts: &[u32]) -> f32 {
    let total: u32 = counts.iter().sum();
    let half = f64::from(total) / 2.0;
    let mut below = 0.0;
    for (b, &count) in counts.iter().enumerate() {
        let next = below + f64::from(count);
        if next >= half && count > 0 {
            let within = ((half - below) / f64::from(count)) as f32;
            return 10f32.powf(LOG_SIGMA_MIN + (b as f32 + within) / PER_DECADE);
        }
        below = next;
    }
    0.0
}

/// σ₀ and k of σ(d) = σ₀ + k·d², fitted to `bins` on the relative error (weights √patches),
/// both at least 0; `None` without a bin.
fn fit_floor_and_quadratic(bins: &[DepthNoiseBin]) -> Option<(f32, f32)> {
    let rows: Vec<(f64, f64, f64)> = bins
        .iter()
        .filter(|b| b.sigma_m > 0.0)
        .map(|b| {
            let weight = f64::from(b.patches).sqrt();
            let s = f64::from(b.sigma_m);
            let d2 = f64::from(b.depth_m).powi(2);
            (weight / s, weight * d2 / s, weight)
        })
        .collect();
    if rows.is_empty() {
        return bins.first().map(|_| (0.0, 0.0));
    }
    // Minimise Σ (x·σ₀ + y·k − t)² with (x, y, t) = w·(1/s, d²/s, 1).
    let (mut xx, mut xy, mut yy, mut xt, mut yt) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y, t) in &rows {
        (xx, xy, yy, xt, yt) = (xx + x * x, xy + x * y, yy + y * y, xt + x * t, yt + y * t);
    }
    let det = xx * yy - xy * xy;
    let (floor, quadratic) = if det.abs() > 1e-12 * xx * yy {
        ((xt * yy - yt * xy) / det, (yt * xx - xt * xy) / det)
    } else {
        (0.0, yt / yy)
    };
    let (floor, quadratic) = if quadratic < 0.0 {
        (xt / xx, 0.0)
    } else if floor < 0.0 {
        (0.0, yt / yy)
    } else {
        (floor, quadratic)
    };
    Some((floor.max(0.0) as f32, quadratic.max(0.0) as f32))
}

#[cfg(test)]
#[path = "depth_noise_tests.rs"]
mod tests;
