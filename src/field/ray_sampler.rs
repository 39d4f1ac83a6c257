//! The depth-guided ray sampler (METHOD.md §2): which pixels of an object's keyframes one
//! training step uses, and where along each pixel's ray the field is sampled.
//!
//! Per step, `keyframes_per_step` views take part — the (up to) two newest keyframes always,
//! the rest drawn uniformly from the older ones — and each gives `pixels_per_keyframe` pixels
//! drawn uniformly inside the view's stored (enlarged) 2D box. Along the ray
//! `r(z) = o + z·R·((u − cx)/fx, (v − cy)/fy, 1)` (z is camera depth) with measured depth `d`:
//! - `free_samples` stratified in `[0, d − band]` (free space before the surface);
//! - if the pixel is the object's (or unknown): `surface_samples` sorted at
//!   `d + clip(N(0, (band/3)²), ±band)`;
//! - if it shows another object or the background: `surface_samples` stratified in
//!   `[d − band, d + behind]` — the ray stops just behind the occluder;
//! - invalid depth: all samples stratified in `[0, max valid depth of the step's rays]`.

use nalgebra::{Point3, Vector3};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

use super::samples::RaySamples;
use crate::objects::keyframes::KeyframeWindow;
use crate::objects::object_view::{ObjectView, PixelState};

/// How one field's rays are drawn for a training step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RaySamplerConfig {
    /// Keyframes that take part in one step (the two newest always do).
    pub keyframes_per_step: usize,
    /// Pixels drawn inside each taking-part keyframe's 2D box.
    pub pixels_per_keyframe: usize,
    /// Stratified samples in free space before the surface.
    pub free_samples: usize,
    /// Samples around (own pixels) or just before and behind (other pixels) the measured depth.
    pub surface_samples: usize,
    /// Half-width of the surface band, metres (the Gaussian's σ is a third of it).
    pub surface_band_m: f32,
    /// How far behind an occluder's depth a ray of another object's pixel is sampled, metres.
    pub behind_occluder_m: f32,
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
        free_samples: 1,
        surface_samples: 9,
        surface_band_m: 0.1,
        behind_occluder_m: 0.05,
    };

    /// vMAP's background sampler: 5 keyframes × 240 pixels (1 200 rays), 5 + 9 samples per ray.
    pub const BACKGROUND: Self = Self {
        keyframes_per_step: 5,
        pixels_per_keyframe: 240,
        free_samples: 5,
        surface_samples: 9,
        surface_band_m: 0.1,
        behind_occluder_m: 0.05,
    };

    /// Samples per ray.
    pub fn samples_per_ray(&self) -> usize {
        self.free_samples + self.surface_samples
    }

    /// Rays per step when every keyframe slot is filled.
    pub fn rays_per_step(&self) -> usize {
        self.keyframes_per_step * self.pixels_per_keyframe
    }
}

impl Default for RaySamplerConfig {
    fn default() -> Self {
        Self::OBJECT
    }
}

/// The keyframes of one step: `recent` always, then draws (with replacement) from the other
/// views until `count` views are chosen. With no other view, the recent ones are drawn again.
pub fn choose_step_views(len: usize, recent: &[usize], count: usize, rng: &mut impl Rng) -> Vec<usize> {
    if len == 0 || count == 0 {
        return Vec::new();
    }
    let mut chosen: Vec<usize> = recent.iter().copied().filter(|&s| s < len).take(count).collect();
    let older: Vec<usize> = (0..len).filter(|s| !chosen.contains(s)).collect();
    let pool = if older.is_empty() { chosen.clone() } else { older };
    let pool = if pool.is_empty() { (0..len).collect() } else { pool };
    while chosen.len() < count {
        chosen.push(pool[rng.random_range(0..pool.len())]);
    }
    chosen
}

/// The rays of one training step of the field at `field_origin` whose views are `window`'s
/// keyframes (its newest ones always take part; see [`sample_training_rays`]).
pub fn sample_window_rays(
    window: &KeyframeWindow<ObjectView>,
    field_origin: &Point3<f32>,
    cfg: &RaySamplerConfig,
    rng: &mut impl Rng,
) -> RaySamples {
    let views: Vec<&ObjectView> = window.slots().iter().map(|s| &s.data).collect();
    sample_training_rays(&views, window.recent_slots(), field_origin, cfg, rng)
}

/// Draws one step's rays for one field from its keyframe `views` (`recent` = indices of the two
/// newest in `views`). Sample points are returned relative to `field_origin` (world minus
/// origin), the frame the field is defined in.
pub fn sample_training_rays(
    views: &[&ObjectView],
    recent: &[usize],
    field_origin: &Point3<f32>,
    cfg: &RaySamplerConfig,
    rng: &mut impl Rng,
) -> RaySamples {
    let chosen = choose_step_views(views.len(), recent, cfg.keyframes_per_step, rng);
    let mut pixels = Vec::with_capacity(chosen.len() * cfg.pixels_per_keyframe);
    for &v in &chosen {
        let view = views[v];
        let (w, h) = (view.region.width(), view.region.height());
        for _ in 0..cfg.pixels_per_keyframe {
            let du = rng.random_range(0..w);
            let dv = rng.random_range(0..h);
            pixels.push((v, du, dv));
        }
    }
    let max_depth = pixels
        .iter()
        .map(|&(v, du, dv)| views[v].depth_m[(dv * views[v].region.width() + du) as usize])
        .filter(|d| d.is_finite() && *d > 0.0)
        .fold(0.0f32, f32::max);

    let s = cfg.samples_per_ray();
    let mut out = RaySamples {
        samples_per_ray: s,
        points: Vec::with_capacity(pixels.len() * s),
        z: Vec::with_capacity(pixels.len() * s),
        depth_m: Vec::with_capacity(pixels.len()),
        rgb: Vec::with_capacity(pixels.len()),
        states: Vec::with_capacity(pixels.len()),
    };
    let mut z = Vec::with_capacity(s);
    for (v, du, dv) in pixels {
        let view = views[v];
        let i = (dv * view.region.width() + du) as usize;
        let (u, row) = (view.region.u_min + du, view.region.v_min + dv);
        let raw_depth = view.depth_m[i];
        let depth = if raw_depth.is_finite() && raw_depth > 0.0 {
            raw_depth
        } else {
            0.0
        };
        let state = view.states[i];
        depths_along_ray(depth, state, max_depth, cfg, rng, &mut z);

        let k = &view.intrinsics;
        let dir_camera = Vector3::new((u as f32 - k.cx) / k.fx, (row as f32 - k.cy) / k.fy, 1.0);
        let dir = view.world_from_camera.rotation * dir_camera;
        let origin = Point3::from(view.world_from_camera.translation.vector) - field_origin.coords;
        for &zi in &z {
            let p = origin + dir * zi;
            out.points.push([p.x, p.y, p.z]);
        }
        out.z.extend_from_slice(&z);
        out.depth_m.push(depth);
        let c = view.rgb[i];
        out.rgb.push(c.map(|x| f32::from(x) / 255.0));
        out.states.push(state);
    }
    out
}

/// The sorted sample depths of one ray (see the module doc), written into `z`.
fn depths_along_ray(
    depth: f32,
    state: PixelState,
    max_depth: f32,
    cfg: &RaySamplerConfig,
    rng: &mut impl Rng,
    z: &mut Vec<f32>,
) {
    z.clear();
    let band = cfg.surface_band_m;
    if depth <= 0.0 {
        let far = if max_depth > 0.0 { max_depth } else { band };
        stratified(0.0, far, cfg.samples_per_ray(), rng, z);
        return;
    }
    stratified(0.0, (depth - band).max(0.0), cfg.free_samples, rng, z);
    match state {
        PixelState::ThisObject | PixelState::Unknown => {
            let sigma = band / 3.0;
            let start = z.len();
            for _ in 0..cfg.surface_samples {
                let offset = (standard_normal(rng) * sigma).clamp(-band, band);
                z.push((depth + offset).max(0.0));
            }
            z[start..].sort_by(f32::total_cmp);
        }
        PixelState::OtherObject => {
            stratified(
                (depth - band).max(0.0),
                depth + cfg.behind_occluder_m,
                cfg.surface_samples,
                rng,
                z,
            );
        }
    }
}

/// `n` stratified samples in `[near, far]`: one uniform draw in each of `n` equal bins.
fn stratified(near: f32, far: f32, n: usize, rng: &mut impl Rng, z: &mut Vec<f32>) {
    let step = (far - near).max(0.0) / n.max(1) as f32;
    for b in 0..n {
        z.push(near + (b as f32 + rng.random::<f32>()) * step);
    }
}

use crate::rng::standard_normal_f32 as standard_normal;

#[cfg(test)]
mod tests {
    use nalgebra::{Isometry3, Translation3};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::ids::FrameIndex;
    use crate::sensor::frame::CameraIntrinsics;
    use crate::sensor::pixel_box::PixelBox;

    /// A 4×2 view 2 m in front of a camera at (0, 0, -2): left half this object, right half other.
    fn view(frame: u64, depth: f32) -> ObjectView {
        let states = [
            PixelState::ThisObject,
            PixelState::ThisObject,
            PixelState::OtherObject,
            PixelState::OtherObject,
        ];
        ObjectView {
            frame: FrameIndex(frame),
            world_from_camera: Isometry3::from_parts(Translation3::new(0.0, 0.0, -2.0), Default::default()),
            intrinsics: CameraIntrinsics {
                width: 8,
                height: 4,
                fx: 4.0,
                fy: 4.0,
                cx: 4.0,
                cy: 2.0,
            },
            region: PixelBox {
                u_min: 2,
                v_min: 1,
                u_max: 5,
                v_max: 2,
            },
            rgb: vec![[255, 0, 51]; 8],
            depth_m: vec![depth; 8],
            states: [states, states].concat(),
        }
    }

    #[test]
    fn a_ray_budget_becomes_pixels_per_keyframe_rounded_up() {
        assert_eq!(RaySamplerConfig::OBJECT.with_rays_per_step(120).pixels_per_keyframe, 24);
        assert_eq!(RaySamplerConfig::OBJECT.with_rays_per_step(121).pixels_per_keyframe, 25);
        assert_eq!(RaySamplerConfig::OBJECT.with_rays_per_step(360).pixels_per_keyframe, 72);
    }

    #[test]
    fn the_two_newest_views_always_take_part() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for _ in 0..50 {
            let chosen = choose_step_views(10, &[7, 9], 5, &mut rng);
            assert_eq!(chosen.len(), 5);
            assert_eq!(&chosen[..2], &[7, 9]);
            assert!(chosen[2..].iter().all(|s| *s != 7 && *s != 9 && *s < 10));
        }
        assert_eq!(
            choose_step_views(1, &[0], 5, &mut rng),
            vec![0; 5],
            "one view is reused"
        );
        assert!(choose_step_views(0, &[], 5, &mut rng).is_empty());
    }

    #[test]
    fn samples_follow_the_pixel_state_and_lie_on_the_pixel_ray() {
        let views = [view(0, 2.0), view(1, 2.0)];
        let refs: Vec<&ObjectView> = views.iter().collect();
        let origin = Point3::new(0.0, 0.0, 1.0);
        let cfg = RaySamplerConfig::OBJECT;
        let rays = sample_training_rays(&refs, &[0, 1], &origin, &cfg, &mut ChaCha8Rng::seed_from_u64(3));
        rays.validate().expect("consistent arrays");
        assert_eq!(rays.num_rays(), 120);
        assert_eq!(rays.samples_per_ray, 10);
        for r in 0..rays.num_rays() {
            let z = &rays.z[r * 10..(r + 1) * 10];
            assert!(z.windows(2).all(|w| w[0] <= w[1]), "sorted {z:?}");
            assert!(
                z[0] >= 0.0 && z[0] <= 1.9 + 1e-6,
                "free sample before the band: {}",
                z[0]
            );
            match rays.states[r] {
                PixelState::ThisObject => assert!(z[1..].iter().all(|&zi| (zi - 2.0).abs() <= 0.1 + 1e-6)),
                _ => assert!(z[1..].iter().all(|&zi| (1.9 - 1e-6..=2.05 + 1e-6).contains(&zi))),
            }
            // Camera at z = −2 looking along +z; the field frame's origin is at z = 1, so a
            // sample at depth zi has field-frame z = −2 + zi − 1.
            for (j, p) in rays.points[r * 10..(r + 1) * 10].iter().enumerate() {
                assert!((p[2] - (z[j] - 3.0)).abs() < 1e-5, "point {p:?} depth {}", z[j]);
            }
            assert_eq!(rays.rgb[r], [1.0, 0.0, 0.2]);
        }
        let own = rays.states.iter().filter(|s| **s == PixelState::ThisObject).count();
        assert!(
            (30..=90).contains(&own),
            "pixels are drawn across the whole box: {own} own of 120"
        );
    }

    #[test]
    fn invalid_depth_samples_up_to_the_deepest_valid_ray() {
        let views = [view(0, 3.0), view(1, 0.0)];
        let refs: Vec<&ObjectView> = views.iter().collect();
        let cfg = RaySamplerConfig {
            keyframes_per_step: 2,
            ..RaySamplerConfig::OBJECT
        };
        let rays = sample_training_rays(
            &refs,
            &[0, 1],
            &Point3::origin(),
            &cfg,
            &mut ChaCha8Rng::seed_from_u64(4),
        );
        let invalid: Vec<usize> = (0..rays.num_rays()).filter(|&r| rays.depth_m[r] == 0.0).collect();
        assert_eq!(invalid.len(), 24, "the second view's pixels have no depth");
        for r in invalid {
            let z = &rays.z[r * 10..(r + 1) * 10];
            assert!(z.iter().all(|&zi| (0.0..=3.0).contains(&zi)), "{z:?}");
            assert!(z[9] > 2.7, "the last stratum reaches the deepest valid ray");
        }
    }

    #[test]
    fn the_same_seed_draws_the_same_rays() {
        let views = [view(0, 2.0), view(1, 2.5), view(2, 1.5)];
        let refs: Vec<&ObjectView> = views.iter().collect();
        let draw = |seed| {
            let cfg = RaySamplerConfig::OBJECT;
            sample_training_rays(
                &refs,
                &[1, 2],
                &Point3::origin(),
                &cfg,
                &mut ChaCha8Rng::seed_from_u64(seed),
            )
        };
        assert_eq!(draw(9), draw(9));
        assert_ne!(draw(9), draw(10));
    }
}
