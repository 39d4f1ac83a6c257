//! Training samples of one step: per field, R rays × S samples along each ray.
//!
//! Samples are stored ray by ray (the S samples of ray r at `r·S .. (r+1)·S`, in increasing
//! depth), with one target per ray: the measured depth, colour and the pixel's state relative
//! to the field's object.

use super::free_space::CarveCounts;
use crate::error::{CatmapError, Result};
use crate::objects::object_view::PixelState;

/// One field's rays for one training step.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RaySamples {
    /// Samples per ray (S).
    pub samples_per_ray: usize,
    /// Sample positions, `R·S`, in the frame the field is defined in (world for vMAP).
    pub points: Vec<[f32; 3]>,
    /// Depth of each sample along its ray (camera z, same unit as `depth_m`), `R·S`.
    pub z: Vec<f32>,
    /// Measured depth of each ray's pixel in metres; 0 = invalid. `R`.
    pub depth_m: Vec<f32>,
    /// Measured colour of each ray's pixel in [0, 1]. `R`.
    pub rgb: Vec<[f32; 3]>,
    /// State of each ray's pixel relative to the field's object. `R`.
    pub states: Vec<PixelState>,
    /// How many samples lie inside the object's box and how many of those carve free space
    /// (zero when the sampler was given no box).
    pub carve: CarveCounts,
    /// Weight of the solid prior on the samples of `HiddenSolid` rays (see [`super::loss`]).
    pub solid_weight: f32,
}

impl RaySamples {
    /// Number of rays.
    pub fn num_rays(&self) -> usize {
        self.depth_m.len()
    }

    /// Number of samples (rays × samples per ray).
    pub fn num_samples(&self) -> usize {
        self.points.len()
    }

    /// These rays, then `other`'s (same samples per ray; the carving counts and solid weight
    /// stay these rays').
    pub fn followed_by(mut self, other: RaySamples) -> Self {
        debug_assert!(other.num_rays() == 0 || other.samples_per_ray == self.samples_per_ray);
        self.points.extend(other.points);
        self.z.extend(other.z);
        self.depth_m.extend(other.depth_m);
        self.rgb.extend(other.rgb);
        self.states.extend(other.states);
        self
    }

    /// Checks that the arrays agree in length.
    pub fn validate(&self) -> Result<()> {
        let rays = self.num_rays();
        let ok = self.samples_per_ray > 0
            && self.points.len() == rays * self.samples_per_ray
            && self.z.len() == self.points.len()
            && self.rgb.len() == rays
            && self.states.len() == rays;
        if ok {
            Ok(())
        } else {
            Err(CatmapError::mismatch(
                "ray samples (points, depths, colours, states)",
                format!(
                    "{rays} rays × {} samples (> 0): {}, {}, {rays}, {rays}",
                    self.samples_per_ray,
                    rays * self.samples_per_ray,
                    rays * self.samples_per_ray
                ),
                format!(
                    "{}, {}, {}, {}",
                    self.points.len(),
                    self.z.len(),
                    self.rgb.len(),
                    self.states.len()
                ),
            ))
        }
    }
}

impl RaySamples {
    /// The same rays reordered so that those whose colour the loss reads (this object's and
    /// unknown pixels) come first, each group in its original order. A training step then runs
    /// the colour branch on a prefix of each chunk only ([`super::heads`]).
    pub fn with_colour_rays_first(self) -> Self {
        let reads_colour = |s: &PixelState| s.reads_colour();
        if self.states.is_sorted_by_key(|s| !reads_colour(s)) {
            return self;
        }
        let spr = self.samples_per_ray;
        let mut order: Vec<usize> = (0..self.num_rays()).collect();
        order.sort_by_key(|&r| !reads_colour(&self.states[r]));
        Self {
            samples_per_ray: spr,
            points: order
                .iter()
                .flat_map(|&r| self.points[r * spr..(r + 1) * spr].iter().copied())
                .collect(),
            z: order
                .iter()
                .flat_map(|&r| self.z[r * spr..(r + 1) * spr].iter().copied())
                .collect(),
            depth_m: order.iter().map(|&r| self.depth_m[r]).collect(),
            rgb: order.iter().map(|&r| self.rgb[r]).collect(),
            states: order.iter().map(|&r| self.states[r]).collect(),
            carve: self.carve,
            solid_weight: self.solid_weight,
        }
    }

    /// Random rays for benchmarks and gradient checks: origins in a ±`half_box_m` cube, sample
    /// depths increasing from 0.2–0.6 m in steps of 1–20 cm, measured depths in 0.3–3 m (a
    /// fraction `invalid_fraction` of them invalid), random colours and all three pixel states.
    pub fn random(
        rng: &mut impl rand::Rng,
        rays: usize,
        samples_per_ray: usize,
        half_box_m: f32,
        invalid_fraction: f32,
    ) -> Self {
        use rand::RngExt;
        let mut out = Self {
            samples_per_ray,
            ..Self::default()
        };
        for _ in 0..rays {
            let origin: [f32; 3] = std::array::from_fn(|_| rng.random_range(-half_box_m..half_box_m));
            let dir: [f32; 3] = std::array::from_fn(|_| rng.random_range(-0.5..0.5));
            let mut z = rng.random_range(0.2f32..0.6);
            for _ in 0..samples_per_ray {
                out.points.push(std::array::from_fn(|c| origin[c] + z * dir[c]));
                out.z.push(z);
                z += rng.random_range(0.01f32..0.2);
            }
            let invalid = rng.random::<f32>() < invalid_fraction;
            out.depth_m.push(if invalid { 0.0 } else { rng.random_range(0.3..3.0) });
            out.rgb.push(std::array::from_fn(|_| rng.random_range(0.0..1.0)));
            out.states.push(match rng.random_range(0..3) {
                0 => PixelState::OtherObject,
                1 => PixelState::ThisObject,
                _ => PixelState::Unknown,
            });
        }
        out
    }
}
