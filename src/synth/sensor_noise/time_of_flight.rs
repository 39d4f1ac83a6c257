//! A time-of-flight depth camera (Kinect v2, Azure Kinect): modulated infrared light, the depth
//! from the phase of its return at each pixel.
//!
//! In this order, on the rendered depth:
//! 1. **Range**: nothing nearer than `min_range_m` or farther than `max_range_m` (5.46 m, the
//!    Azure Kinect's narrow field of view binned 2×2; the Kinect v2 says 4.5 m).
//! 2. **Flying pixels**: a pixel beside a depth step of more than `flying_jump_m` mixes the two
//!    surfaces' returns with probability `flying_probability`: its depth lies anywhere between
//!    its own and its neighbour's (uniform), as at the silhouettes of every ToF image.
//! 3. **Multipath in concave corners**: light bounced off the other face of a corner arrives
//!    late, so a pixel in a concave corner reads farther: + `multipath_gain` · c · z, at most
//!    `multipath_max_m`, c the corner's [`concavity`] on a ring `multipath_ring_rad` wide
//!    (Fuchs, *Multipath interference compensation in time-of-flight camera images*, ICPR 2010:
//!    centimetres in room corners).
//! 4. **Axial noise**: z + N(0, σ(z, θ)²) with σ(z, θ) = 1.5 − 0.5 z + 0.3 z² +
//!    0.1 z^1.5 θ² / (π/2 − θ)² mm (z in m, θ the angle between the surface's normal and the ray,
//!    at most `max_angle_deg`; Fankhauser, Bloesch, Rodriguez, Kaestner, Hutter and Siegwart,
//!    *Kinect v2 for mobile robot navigation: evaluation and modeling*, ICAR 2015).
//! 5. **Dropouts**: `dropout_probability` of the pixels return nothing.

use std::f32::consts::FRAC_PI_2;

use rand::RngExt;

use super::depth_image::{concavity, incidence_cos, largest_step};
use crate::rng::standard_normal_f32;
use crate::synth::render::RenderedFrame;

/// The time-of-flight camera's parameters (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeOfFlight {
    /// Nearest depth returned, metres (0.5).
    pub min_range_m: f32,
    /// Farthest depth returned, metres (5.46).
    pub max_range_m: f32,
    /// A depth step to a 4-neighbour larger than this may make a flying pixel, metres (0.05).
    pub flying_jump_m: f32,
    /// Chance a pixel at such a step flies (0.7).
    pub flying_probability: f32,
    /// Depth added per unit of concavity and metre of depth (0.5).
    pub multipath_gain: f32,
    /// Most depth multipath adds, metres (0.03).
    pub multipath_max_m: f32,
    /// Radius of the ring the concavity is read on, as an angle, radians (0.02: 10 px at a
    /// 512 px focal length).
    pub multipath_ring_rad: f32,
    /// Largest angle from the normal σ(z, θ) is evaluated at, degrees (75).
    pub max_angle_deg: f32,
    /// Chance any pixel returns nothing (0.001).
    pub dropout_probability: f32,
}

impl Default for TimeOfFlight {
    fn default() -> Self {
        Self {
            min_range_m: 0.5,
            max_range_m: 5.46,
            flying_jump_m: 0.05,
            flying_probability: 0.7,
            multipath_gain: 0.5,
            multipath_max_m: 0.03,
            multipath_ring_rad: 0.02,
            max_angle_deg: 75.0,
            dropout_probability: 0.001,
        }
    }
}

impl TimeOfFlight {
    /// σ(z, θ) of the module doc at depth `z_m` and angle `theta_rad` from the normal, metres.
    pub fn sigma_m(&self, z_m: f32, theta_rad: f32) -> f32 {
        let theta = theta_rad.clamp(0.0, self.max_angle_deg.to_radians());
        let angle = 0.1 * z_m.powf(1.5) * theta * theta / (FRAC_PI_2 - theta).powi(2);
        (1.5 - 0.5 * z_m + 0.3 * z_m * z_m + angle) * 1e-3
    }

    /// Degrades `frame`'s depth (module doc).
    pub fn degrade(&self, frame: &mut RenderedFrame, rng: &mut impl rand::Rng) {
        let k = frame.intrinsics;
        let (w, h) = (k.width as usize, k.height as usize);
        let clean = frame.depth_m.clone();
        let ring = ((self.multipath_ring_rad * k.fx).round() as usize).max(1);
        for (i, depth) in frame.depth_m.iter_mut().enumerate() {
            let z = clean[i];
            if z <= 0.0 {
                continue;
            }
            let step = largest_step(&clean, w, h, i, self.flying_jump_m);
            let flies = step.is_some() && rng.random::<f32>() < self.flying_probability;
            let mix: f32 = rng.random();
            let surface = match step {
                Some(other) if flies => z + mix * (other - z),
                _ => {
                    z + (self.multipath_gain * concavity(&clean, w, h, i, ring, 0.25) * z)
                        .clamp(0.0, self.multipath_max_m)
                }
            };
            let theta = incidence_cos(&clean, &k, i, self.flying_jump_m).map_or(0.0, |c| c.clamp(0.0, 1.0).acos());
            let noisy = surface + self.sigma_m(z, theta) * standard_normal_f32(rng);
            let dropped = rng.random::<f32>() < self.dropout_probability;
            *depth = if dropped || z < self.min_range_m || z > self.max_range_m || noisy <= 0.0 {
                0.0
            } else {
                noisy
            };
        }
    }
}
