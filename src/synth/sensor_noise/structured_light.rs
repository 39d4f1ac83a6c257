//! A structured-light depth camera (Kinect v1, Structure sensor): an infrared projector beside
//! the camera casts a dot pattern whose shift (disparity) along the rows gives the depth.
//!
//! In this order, on the rendered depth:
//! 1. **The projector's shadows**: what the projector, `baseline_m` to the camera's right, cannot
//!    light has no depth (a strip left of every object, as wide as fx·b·(1/z_near − 1/z_far)).
//! 2. **Range**: nothing nearer than `min_range_m` or farther than `max_range_m` (4.5 m).
//! 3. **Holes at depth edges**: a pixel beside a depth step of more than `edge_jump_m` loses its
//!    depth with probability `edge_hole_probability` (the correlation window straddles two
//!    surfaces); a surface seen at more than `grazing_angle_deg` from its normal loses it with
//!    probability `grazing_hole_probability` (the dots smear).
//! 4. **Axial noise**: z + N(0, σ_N(z)²), σ_N(z) = a + b·(z − z₀)² (Nguyen, Izadi and Lovell,
//!    *Modeling Kinect sensor noise for improved 3D reconstruction and tracking*, 3DIMPVT 2012:
//!    a = 1.2 mm, b = 1.9 mm/m², z₀ = 0.4 m).
//! 5. **Disparity quantised to 1/8 px** of the sensor's own 580 px focal length and 7.5 cm
//!    baseline (Khoshelham and Oude Elberink, *Accuracy and resolution of Kinect depth data for
//!    indoor mapping applications*, Sensors 12, 2012): the depth steps by z²/(8·f·b), 2.9 mm at
//!    1 m, 4.6 cm at 4 m.
//! 6. **Speckle holes**: `speckles_per_megapixel` disks of 1–3 px (at 640 px wide) lose their
//!    depth where the pattern is not decoded.
//!
//! σ(z) of the whole ([`StructuredLight::sigma_m`]) is √(σ_N² + Δ²/12), Δ the quantisation step.

use rand::RngExt;

use super::depth_image::{hidden_from_baseline, incidence_cos, largest_step};
use crate::rng::standard_normal_f32;
use crate::synth::render::RenderedFrame;

/// The structured-light camera's parameters (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StructuredLight {
    /// Projector to camera, metres (0.075).
    pub baseline_m: f32,
    /// The sensor's own focal length, pixels (580, at 640 px wide).
    pub sensor_focal_px: f32,
    /// Disparity step, pixels (1/8).
    pub disparity_step_px: f32,
    /// σ_N's a, metres (0.0012).
    pub sigma_base_m: f32,
    /// σ_N's b, metres per square metre (0.0019).
    pub sigma_quadratic_per_m: f32,
    /// σ_N's z₀, metres (0.4).
    pub sigma_offset_m: f32,
    /// Nearest depth returned, metres (0.5).
    pub min_range_m: f32,
    /// Farthest depth returned, metres (4.5).
    pub max_range_m: f32,
    /// A depth step to a 4-neighbour larger than this makes an edge pixel, metres (0.05).
    pub edge_jump_m: f32,
    /// Chance an edge pixel loses its depth (0.5).
    pub edge_hole_probability: f32,
    /// Beyond this angle between the surface's normal and the ray, degrees (75).
    pub grazing_angle_deg: f32,
    /// Chance a pixel seen beyond `grazing_angle_deg` loses its depth (0.8).
    pub grazing_hole_probability: f32,
    /// Speckle holes per million pixels and frame (800).
    pub speckles_per_megapixel: f32,
}

impl Default for StructuredLight {
    fn default() -> Self {
        Self {
            baseline_m: 0.075,
            sensor_focal_px: 580.0,
            disparity_step_px: 0.125,
            sigma_base_m: 0.0012,
            sigma_quadratic_per_m: 0.0019,
            sigma_offset_m: 0.4,
            min_range_m: 0.5,
            max_range_m: 4.5,
            edge_jump_m: 0.05,
            edge_hole_probability: 0.5,
            grazing_angle_deg: 75.0,
            grazing_hole_probability: 0.8,
            speckles_per_megapixel: 800.0,
        }
    }
}

impl StructuredLight {
    /// σ_N(z), metres.
    fn axial_sigma_m(&self, z_m: f32) -> f32 {
        self.sigma_base_m + self.sigma_quadratic_per_m * (z_m - self.sigma_offset_m).powi(2)
    }

    /// The depth step of one disparity step at `z_m`, metres.
    pub fn quantisation_step_m(&self, z_m: f32) -> f32 {
        z_m * z_m * self.disparity_step_px / (self.sensor_focal_px * self.baseline_m)
    }

    /// The whole depth error's standard deviation at `z_m` on a surface facing the camera, metres.
    pub fn sigma_m(&self, z_m: f32) -> f32 {
        let step = self.quantisation_step_m(z_m);
        (self.axial_sigma_m(z_m).powi(2) + step * step / 12.0).sqrt()
    }

    /// Degrades `frame`'s depth (module doc).
    pub fn degrade(&self, frame: &mut RenderedFrame, rng: &mut impl rand::Rng) {
        let k = frame.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let clean = frame.depth_m.clone();
        let shadow = hidden_from_baseline(&clean, &k, self.baseline_m, false);
        let grazing_cos = self.grazing_angle_deg.to_radians().cos();
        let fb = self.sensor_focal_px * self.baseline_m;
        for (i, depth) in frame.depth_m.iter_mut().enumerate() {
            let z = clean[i];
            if z <= 0.0 {
                continue;
            }
            let edge = largest_step(&clean, w, h, i, self.edge_jump_m).is_some();
            let grazing = !edge && incidence_cos(&clean, &k, i, self.edge_jump_m).is_some_and(|c| c < grazing_cos);
            let hole_chance = if edge {
                self.edge_hole_probability
            } else if grazing {
                self.grazing_hole_probability
            } else {
                0.0
            };
            let noisy = z + self.axial_sigma_m(z) * standard_normal_f32(rng);
            let holed = rng.random::<f32>() < hole_chance;
            *depth = if shadow[i] || holed || z < self.min_range_m || z > self.max_range_m || noisy <= 0.0 {
                0.0
            } else {
                let disparity = (fb / noisy / self.disparity_step_px).round() * self.disparity_step_px;
                if disparity > 0.0 { fb / disparity } else { 0.0 }
            };
        }
        let scale = w as f32 / 640.0;
        let speckles = (self.speckles_per_megapixel * (w * h) as f32 / 1e6).round() as usize;
        for _ in 0..speckles {
            let (cu, cv) = (rng.random_range(0..w) as i64, rng.random_range(0..h) as i64);
            let r = (rng.random_range(1.0f32..=3.0) * scale).max(0.5);
            let reach = r.ceil() as i64;
            for dv in -reach..=reach {
                for du in -reach..=reach {
                    let (x, y) = (cu + du, cv + dv);
                    if x >= 0 && y >= 0 && x < w as i64 && y < h as i64 && ((du * du + dv * dv) as f32) <= r * r {
                        frame.depth_m[y as usize * w + x as usize] = 0.0;
                    }
                }
            }
        }
    }
}
