//! How one field's rays are drawn for a training step: the sampler's settings
//! ([`super::ray_sampler`] draws them).

use serde::{Deserialize, Serialize};

use crate::objects::hidden_space::{FreeCells, HiddenCells, UnseenCells};
use crate::objects::object_bounds::MirrorPlanes;

/// How one field's rays are drawn for a training step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RaySamplerConfig {
    /// Keyframes that take part in one step (the two newest always do).
    pub keyframes_per_step: usize,
    /// Pixels drawn inside each taking-part keyframe's 2D box.
    pub pixels_per_keyframe: usize,
    /// Of those, how many are drawn among the object's own pixels (up to
    /// [`super::ray_sampler::OWN_PIXEL_TRIES`] draws each, uniform in the box; the rest uniform
    /// in the box, as vMAP). A thin part (a lamp's 2.6 cm pole, 3 % of its box) gets rays in
    /// proportion to its share of the object's pixels instead of the box's. Only objects alone
    /// in their class draw them ([`super::sample_window_rays`] with a hidden space). 0: vMAP's
    /// draws.
    pub own_pixel_draws: usize,
    /// Stratified samples in free space before the surface, from the camera (vMAP's).
    pub free_samples: usize,
    /// Stratified free-space samples on the part of the ray inside the object's box before the
    /// surface band (the carving sampler, [`super::free_space`]). 0: vMAP's sampler.
    pub box_free_samples: usize,
    /// Samples around (own pixels) or just before and behind (other pixels) the measured depth.
    pub surface_samples: usize,
    /// Half-width of the surface band, metres (the Gaussian's σ is a third of it).
    pub surface_band_m: f32,
    /// How far behind an occluder's depth a ray of another object's pixel is sampled, metres.
    pub behind_occluder_m: f32,
    /// Prior rays per step in the cells of the object's box that no view saw into, each sample
    /// asked to be solid ([`crate::objects::hidden_space`]). 0: no solid prior.
    pub hidden_solid_rays: usize,
    /// Which hidden cells the solid prior draws from.
    pub hidden_cells: HiddenCells,
    /// Whether the cells no view saw under the object are hidden cells too.
    pub unseen_cells: UnseenCells,
    /// Prior rays per step under the object's box, below the lowest point it was seen at, each
    /// sample asked to be empty (what the object stands on: the region it is meshed in reaches
    /// below the floor). 0: none.
    pub below_support_rays: usize,
    /// Prior rays per step around the centres of the cells of the object's box that a view saw
    /// free, each sample asked to be empty. 0: none.
    pub seen_free_rays: usize,
    /// Which cells the seen-free prior draws from.
    pub free_cells: FreeCells,
    /// Mirrored pixel draws per step for an object with a vertical mirror plane: keyframe rays
    /// drawn as above and reflected across the plane, as if a camera on the other side had seen
    /// the mirror image (a sofa seen from one end learns the other end's shape and the free space
    /// before it). Only rays of the object's own pixels are kept, and not those whose reflected
    /// surface point a view saw free. 0: none.
    pub mirror_rays: usize,
    /// Which of the object's vertical mirror planes its rays are reflected across
    /// (`mirror_rays` across each).
    pub mirror_planes: MirrorPlanes,
    /// Weight of the priors' loss (mean over their samples of −ln o, or −ln(1 − o) under the box).
    pub hidden_solid_weight: f32,
    /// What a ray of an unsure pixel (a segmenter's mask border, a bleeding or held-back mask)
    /// teaches.
    pub unsure_pixels: UnsurePixels,
}

/// What a ray of an [unsure](crate::objects::object_view::PixelState::Unsure) pixel teaches a
/// field. Its label is not trusted, its depth is: whoever's surface the ray met at depth d, it
/// passed through empty space before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnsurePixels {
    /// Free space before the return: the ray is sampled as another object's would be were its
    /// return at d − the view's depth noise allowance (`dataset.depth_noise_per_m2` × d²), but
    /// stopped short of it — its surface samples in the band before d − allowance −
    /// `surface_band_m`, where every sample ends — and its rendered opacity is asked to be 0. A
    /// pixel without depth gives no ray.
    #[default]
    FreeBeforeReturn,
    /// No ray: the pixel teaches nothing.
    Skipped,
}

impl RaySamplerConfig {
    /// The same sampler drawing about `rays` rays per step: pixels per keyframe rounded up so that
    /// keyframes × pixels ≥ `rays`.
    pub fn with_rays_per_step(mut self, rays: usize) -> Self {
        self.pixels_per_keyframe = rays.div_ceil(self.keyframes_per_step.max(1));
        self
    }

    /// vMAP's object sampler: 5 keyframes × 24 pixels, 1 + 9 samples per ray.
    pub const OBJECT: Self = Self {
        keyframes_per_step: 5,
        pixels_per_keyframe: 24,
        own_pixel_draws: 0,
        free_samples: 1,
        box_free_samples: 0,
        surface_samples: 9,
        surface_band_m: 0.1,
        behind_occluder_m: 0.05,
        hidden_solid_rays: 0,
        hidden_cells: HiddenCells::Enclosed,
        unseen_cells: UnseenCells::HiddenUnderTheObject,
        below_support_rays: 0,
        seen_free_rays: 0,
        free_cells: FreeCells::SeenOpenAndBeyond,
        mirror_rays: 0,
        mirror_planes: MirrorPlanes::BothWhenFound,
        hidden_solid_weight: 1.0,
        unsure_pixels: UnsurePixels::FreeBeforeReturn,
    };

    /// catmap's object sampler (the `fast` profile's): vMAP's, with 3 box samples per ray, 8 rays
    /// per step for each of the solid, seen-free and support priors, 24 mirrored rays, and 8 of
    /// each keyframe's 24 pixels drawn among the object's own (the priors, mirrored rays and own
    /// pixels only for objects alone in their class).
    pub const FAST_OBJECT: Self = Self {
        box_free_samples: 3,
        hidden_solid_rays: 8,
        seen_free_rays: 8,
        below_support_rays: 8,
        mirror_rays: 24,
        own_pixel_draws: 8,
        ..Self::OBJECT
    };

    /// vMAP's background sampler: 5 keyframes × 240 pixels (1 200 rays), 5 + 9 samples per ray.
    pub const BACKGROUND: Self = Self {
        keyframes_per_step: 5,
        pixels_per_keyframe: 240,
        own_pixel_draws: 0,
        free_samples: 5,
        box_free_samples: 0,
        surface_samples: 9,
        surface_band_m: 0.1,
        behind_occluder_m: 0.05,
        hidden_solid_rays: 0,
        hidden_cells: HiddenCells::Enclosed,
        unseen_cells: UnseenCells::HiddenUnderTheObject,
        below_support_rays: 0,
        seen_free_rays: 0,
        free_cells: FreeCells::SeenAndOpen,
        mirror_rays: 0,
        mirror_planes: MirrorPlanes::BothWhenFound,
        hidden_solid_weight: 1.0,
        unsure_pixels: UnsurePixels::FreeBeforeReturn,
    };

    /// Samples per ray.
    pub fn samples_per_ray(&self) -> usize {
        self.free_samples + self.carving_samples() + self.surface_samples
    }

    /// The box samples this sampler draws.
    pub fn carving_samples(&self) -> usize {
        self.box_free_samples
    }

    /// The solid prior's rays per step.
    pub fn solid_prior_rays(&self) -> usize {
        self.hidden_solid_rays
    }

    /// The seen-free prior's rays per step.
    pub fn seen_free_rays(&self) -> usize {
        self.seen_free_rays
    }

    /// The support prior's rays per step.
    pub fn below_support_rays(&self) -> usize {
        self.below_support_rays
    }

    /// The pixels per keyframe drawn among the object's own.
    pub fn own_pixel_draws(&self) -> usize {
        self.own_pixel_draws
    }

    /// The same sampler drawing `draws` pixels per keyframe among the object's own.
    pub fn with_own_pixel_draws(mut self, draws: usize) -> Self {
        self.own_pixel_draws = draws;
        self
    }

    /// The mirrored rays per step.
    pub fn mirror_rays(&self) -> usize {
        self.mirror_rays
    }

    /// Rays per step when every keyframe slot is filled.
    pub fn rays_per_step(&self) -> usize {
        self.keyframes_per_step * self.pixels_per_keyframe
    }
}

impl Default for RaySamplerConfig {
    fn default() -> Self {
        Self::FAST_OBJECT
    }
}
