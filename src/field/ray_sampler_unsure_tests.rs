//! Unit tests of what the ray sampler (`ray_sampler.rs`) draws for unsure pixels
//! ([`UnsurePixels`]).

use super::tests::{draw_unboxed, view};
use super::*;

/// `view(0, depth)` with every fourth pixel unsure and a noise allowance of `noise` × d².
fn quarter_unsure(depth: f32, noise: f32) -> ObjectView {
    let mut v = view(0, depth);
    v.depth_noise_per_m2 = noise;
    for (i, s) in v.states.iter_mut().enumerate() {
        if i % 4 == 3 {
            *s = PixelState::Unsure;
        }
    }
    v
}

#[test]
fn unsure_pixels_teach_only_the_free_space_before_their_return() {
    // Surface 1.5 m away, noise allowance 0.02 × 1.5² = 4.5 cm: an unsure ray's samples all lie
    // before 1.5 − 0.045 − 0.1 (the band), whoever's surface the pixel shows, its surface
    // samples in the band before that.
    let unsure = quarter_unsure(1.5, 0.02);
    let cfg = RaySamplerConfig::OBJECT;
    let rays = draw_unboxed(&[&unsure], &[0], &cfg, 3);
    rays.validate().expect("consistent arrays");
    let drawn = cfg.keyframes_per_step * cfg.pixels_per_keyframe;
    assert_eq!(rays.num_rays(), drawn, "every draw gives a ray");
    let s = rays.samples_per_ray;
    let before = 1.5 - 0.02 * 1.5 * 1.5 - cfg.surface_band_m;
    let unsure_rays: Vec<&[f32]> = (0..rays.num_rays())
        .filter(|&r| rays.states[r] == PixelState::Unsure)
        .map(|r| &rays.z[r * s..(r + 1) * s])
        .collect();
    assert!(
        unsure_rays.len() > drawn / 8 && unsure_rays.len() < drawn / 2,
        "a quarter of the pixels are unsure: {} of {drawn}",
        unsure_rays.len()
    );
    for z in &unsure_rays {
        assert!(z.windows(2).all(|w| w[0] <= w[1]), "sorted {z:?}");
        assert!(z.iter().all(|&zi| (0.0..=before + 1e-5).contains(&zi)), "{z:?}");
        let last = &z[s - cfg.surface_samples..];
        assert!(
            last.iter().all(|&zi| zi >= before - cfg.surface_band_m - 1e-5),
            "the surface samples lie in the band before the free end: {z:?}"
        );
    }
    assert_eq!(
        PixelState::Unsure.opacity_target(),
        Some(0.0),
        "free: rendered opacity 0"
    );
    assert!(
        !PixelState::Unsure.reads_colour(),
        "its colour and depth are not the object's"
    );
    // Own pixels still sample their surface: the allowance is the unsure rays' alone.
    let own = (0..rays.num_rays())
        .find(|&r| rays.states[r] == PixelState::ThisObject)
        .expect("own ray");
    assert!(rays.z[own * s + s - 1] > 1.45, "{:?}", &rays.z[own * s..(own + 1) * s]);
}

#[test]
fn unsure_pixels_without_depth_or_skipped_give_no_ray() {
    let cfg = RaySamplerConfig::OBJECT;
    let no_depth = ObjectView {
        states: vec![PixelState::Unsure; 8],
        depth_m: vec![0.0; 8],
        ..view(0, 1.5)
    };
    assert_eq!(draw_unboxed(&[&no_depth], &[0], &cfg, 3).num_rays(), 0);
    // Nearer than the band and the allowance: nothing before it to teach.
    let near = ObjectView {
        states: vec![PixelState::Unsure; 8],
        ..view(0, 0.09)
    };
    assert_eq!(draw_unboxed(&[&near], &[0], &cfg, 3).num_rays(), 0);
    let skipped = RaySamplerConfig {
        unsure_pixels: UnsurePixels::Skipped,
        ..cfg
    };
    let unsure = quarter_unsure(1.5, 0.0);
    let rays = draw_unboxed(&[&unsure], &[0], &skipped, 3);
    let drawn = skipped.keyframes_per_step * skipped.pixels_per_keyframe;
    assert!(!rays.states.contains(&PixelState::Unsure));
    assert!(
        rays.num_rays() < drawn && rays.num_rays() > drawn / 2,
        "a quarter of the pixels are unsure: {} rays of {drawn} draws",
        rays.num_rays()
    );
}
