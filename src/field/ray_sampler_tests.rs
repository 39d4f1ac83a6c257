//! Unit tests of the ray sampler (`ray_sampler.rs`).

use nalgebra::{Isometry3, Translation3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::ids::FrameIndex;
use crate::sensor::frame::CameraIntrinsics;
use crate::sensor::pixel_box::PixelBox;

/// A 4×2 view 2 m in front of a camera at (0, 0, -2): left half this object, right half other.
pub(super) fn view(frame: u64, depth: f32) -> ObjectView {
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
        depth_noise_per_m2: 0.0,
        deepest_return_m: depth,
    }
}

/// One step's rays from `refs` without an object box.
pub(super) fn draw_unboxed(refs: &[&ObjectView], recent: &[usize], cfg: &RaySamplerConfig, seed: u64) -> RaySamples {
    sample_training_rays(
        refs,
        recent,
        &Point3::origin(),
        None,
        cfg,
        &mut ChaCha8Rng::seed_from_u64(seed),
    )
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
    let rays = sample_training_rays(&refs, &[0, 1], &origin, None, &cfg, &mut ChaCha8Rng::seed_from_u64(3));
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
fn box_samples_carve_the_part_of_each_ray_inside_the_box_before_the_surface() {
    // The views' surface is at world z = 0 (depth 2 from the camera at z = −2); the object's
    // box spans z ∈ [−0.8, −0.2], depths 1.2–1.8: every ray crosses it before its band.
    let views = [view(0, 2.0), view(1, 2.0)];
    let refs: Vec<&ObjectView> = views.iter().collect();
    let object_box = OrientedBox {
        world_from_box: nalgebra::Isometry3::translation(0.0, 0.0, -0.5),
        half_extents: Vector3::new(2.0, 2.0, 0.3),
    };
    let draw = |box_free_samples| {
        let cfg = RaySamplerConfig {
            box_free_samples,
            ..RaySamplerConfig::OBJECT
        };
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        sample_training_rays(&refs, &[0, 1], &Point3::origin(), Some(&object_box), &cfg, &mut rng)
    };
    let carving = draw(3);
    carving.validate().expect("consistent arrays");
    assert_eq!(carving.samples_per_ray, 13);
    for r in 0..carving.num_rays() {
        let z = &carving.z[r * 13..(r + 1) * 13];
        assert!(z.windows(2).all(|w| w[0] <= w[1]), "sorted {z:?}");
        let in_box = z.iter().filter(|&&zi| (1.2 - 1e-5..=1.8 + 1e-5).contains(&zi)).count();
        assert!(in_box >= 3, "ray {r}: the three box samples lie in the box: {z:?}");
    }
    assert!(
        carving.carve.inside >= 3 * 120 && carving.carve.carving == carving.carve.inside,
        "every sample inside the box carves it: {:?}",
        carving.carve
    );
    // vMAP's sampler: one free sample per ray over [0, 1.9], inside the box 6/19 of the time.
    let vmap = draw(0);
    assert_eq!(vmap.samples_per_ray, 10);
    assert!(
        (20..=60).contains(&vmap.carve.carving),
        "one ray in three carves: {:?}",
        vmap.carve
    );
    let unboxed = draw_unboxed(&refs, &[0, 1], &RaySamplerConfig::OBJECT, 5);
    let vmap_uncounted = RaySamples {
        carve: CarveCounts::default(),
        solid_weight: 0.0,
        ..vmap
    };
    assert_eq!(unboxed, vmap_uncounted, "no box: vMAP's sampler, the same draws");
}

#[test]
fn rays_whose_colour_is_read_come_first() {
    let views = [view(0, 2.0), view(1, 2.0)];
    let refs: Vec<&ObjectView> = views.iter().collect();
    let cfg = RaySamplerConfig::OBJECT;
    let rays = draw_unboxed(&refs, &[0, 1], &cfg, 6);
    let first_other = rays
        .states
        .iter()
        .position(|s| *s == PixelState::OtherObject)
        .expect("some");
    assert!(first_other > 0, "some own rays");
    assert!(
        rays.states[first_other..].iter().all(|s| *s == PixelState::OtherObject),
        "own rays first"
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
    let rays = draw_unboxed(&refs, &[0, 1], &cfg, 4);
    let invalid: Vec<usize> = (0..rays.num_rays()).filter(|&r| rays.depth_m[r] == 0.0).collect();
    assert_eq!(invalid.len(), 24, "the second view's pixels have no depth");
    for r in invalid {
        let z = &rays.z[r * 10..(r + 1) * 10];
        assert!(z.iter().all(|&zi| (0.0..=3.0).contains(&zi)), "{z:?}");
        assert!(z[9] > 2.7, "the last stratum reaches the deepest valid ray");
    }
}

#[test]
fn another_objects_hole_at_a_depth_edge_is_free_only_before_the_nearest_return_beside_it() {
    // This object at 3 m on the left half, another object 1.5 m away on the right half, and a
    // hole (no depth) in one pixel of each: the other object's hole hid what lies behind it.
    let mut v = view(0, 3.0);
    for (i, d) in v.depth_m.iter_mut().enumerate() {
        if i % 4 >= 2 {
            *d = 1.5;
        }
    }
    v.depth_m[0] = 0.0;
    v.depth_m[3] = 0.0;
    let refs = [&v];
    let cfg = RaySamplerConfig {
        keyframes_per_step: 1,
        pixels_per_keyframe: 64,
        ..RaySamplerConfig::OBJECT
    };
    let rays = draw_unboxed(&refs, &[0], &cfg, 5);
    let s = rays.samples_per_ray;
    let holes = |state: PixelState| -> Vec<&[f32]> {
        (0..rays.num_rays())
            .filter(|&r| rays.depth_m[r] == 0.0 && rays.states[r] == state)
            .map(|r| &rays.z[r * s..(r + 1) * s])
            .collect()
    };
    let (other, own) = (holes(PixelState::OtherObject), holes(PixelState::ThisObject));
    assert!(!other.is_empty() && !own.is_empty(), "both holes drawn");
    let before_occluder = 1.5 - cfg.surface_band_m;
    for z in other {
        assert!(z.iter().all(|&zi| zi <= before_occluder), "{z:?}");
        assert!(
            z[s - 1] > 0.8 * before_occluder,
            "the ray is free up to the occluder: {z:?}"
        );
    }
    for z in own {
        assert!(
            z[s - 1] > 2.7,
            "this object's hole still reaches the deepest return: {z:?}"
        );
    }
}

#[test]
fn the_same_seed_draws_the_same_rays() {
    let views = [view(0, 2.0), view(1, 2.5), view(2, 1.5)];
    let refs: Vec<&ObjectView> = views.iter().collect();
    let draw = |seed| {
        let cfg = RaySamplerConfig::OBJECT;
        draw_unboxed(&refs, &[1, 2], &cfg, seed)
    };
    assert_eq!(draw(9), draw(9));
    assert_ne!(draw(9), draw(10));
}

/// The surface point of each ray of `rays` whose colour is read (its samples extended to the
/// measured depth).
fn surface_points(rays: &RaySamples) -> Vec<Point3<f32>> {
    let s = rays.samples_per_ray;
    (0..rays.num_rays())
        .filter(|&r| rays.states[r].reads_colour())
        .map(|r| {
            let (p, z) = (&rays.points[r * s..(r + 1) * s], &rays.z[r * s..(r + 1) * s]);
            let (a, b) = (Point3::from(p[0]), Point3::from(p[s - 1]));
            let dir = (b - a) / (z[s - 1] - z[0]);
            a + dir * (rays.depth_m[r] - z[0])
        })
        .collect()
}

#[test]
fn mirrored_rays_see_the_mirror_image_unless_a_view_saw_it_free() {
    use crate::objects::view_fixtures::{Solid, aabb, render};
    // A slab at x ∈ [0.1, 0.4] facing −y at y = 1, mirrored across x = 0; a screen (another
    // object) hides the mirror image from the camera in front.
    let scene = [
        Solid {
            aabb: aabb([0.1, 1.0, 0.0], [0.4, 1.1, 0.4]),
            is_object: true,
        },
        Solid {
            aabb: aabb([-0.8, 0.5, -0.5], [0.0, 0.55, 1.0]),
            is_object: false,
        },
    ];
    let plane = MirrorPlane::vertical(0.0, 0.0);
    let in_front = render([0.25, -1.0, 0.2], 0.0, &scene);
    let cfg = RaySamplerConfig {
        box_free_samples: 0,
        ..RaySamplerConfig::OBJECT
    }
    .with_rays_per_step(4000);
    let draw = |views: &[&ObjectView], seed| {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        sample_rays(views, &[0], &Point3::origin(), None, &cfg, Some(&plane), &mut rng)
    };
    let mirrored = draw(&[&in_front], 1);
    mirrored.validate().expect("consistent rays");
    assert!(
        mirrored.states.iter().all(|s| *s == PixelState::ThisObject),
        "only the object's own rays are reflected"
    );
    let surfaces = surface_points(&mirrored);
    assert!(surfaces.len() > 20, "{} mirrored rays of the slab", surfaces.len());
    for p in &surfaces {
        assert!(
            (-0.401..=-0.099).contains(&p.x) && (0.999..=1.101).contains(&p.y),
            "a mirrored surface point off the slab's mirror image: {p:?}"
        );
    }
    // A view from behind sees through the mirror image to the screen: the slab is not symmetric
    // about x = 0, and its mirrored rays are dropped.
    let through_the_image = render([-0.25, 2.5, 0.2], std::f32::consts::PI, &scene);
    let checked = draw(&[&in_front, &through_the_image], 1);
    assert_eq!(checked.num_rays(), 0, "{} kept", checked.num_rays());
}

#[test]
fn a_mirrored_ray_that_passes_a_thin_pole_before_its_surface_is_dropped() {
    use crate::objects::view_fixtures::{Solid, aabb, render};
    // A 2.6 cm pole seen from +x, 40 cm away; its axis is the plane x = 0.013.
    let scene = [Solid {
        aabb: aabb([0.0, 0.987, 0.0], [0.026, 1.013, 1.0]),
        is_object: true,
    }];
    let view = render([0.426, 1.0, 0.5], -std::f32::consts::FRAC_PI_2, &scene);
    let cfg = RaySamplerConfig {
        box_free_samples: 0,
        ..RaySamplerConfig::OBJECT
    }
    .with_rays_per_step(4000);
    let kept = |axis: f32| {
        let plane = MirrorPlane::vertical(0.0, axis);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        sample_rays(&[&view], &[0], &Point3::origin(), None, &cfg, Some(&plane), &mut rng).num_rays()
    };
    let pole_rays = view.states.iter().filter(|s| **s == PixelState::ThisObject).count() * 4000 / view.states.len();
    // Across the true axis a reflected ray ends on the pole's far side, through space the view
    // saw behind it; across a plane 2.2 cm off it ends behind the pole, passing through it.
    let (on_axis, off_axis) = (kept(0.013), kept(0.035));
    assert!(
        on_axis * 10 > pole_rays * 8,
        "on the axis {on_axis} of about {pole_rays} pole rays kept"
    );
    assert!(off_axis * 3 < on_axis, "off the axis {off_axis} kept, on it {on_axis}");
}

#[test]
fn own_pixel_draws_put_rays_on_a_thin_object_that_the_box_draws_rarely_hit() {
    use crate::objects::view_fixtures::{Solid, aabb, render};
    // A 10 cm post 1.2 m before the camera: 5 % of the 96×96 crop.
    let post = [Solid {
        aabb: aabb([-0.05, 1.15, -1.0], [0.05, 1.25, 1.0]),
        is_object: true,
    }];
    let view = render([0.0, 0.0, 0.0], 0.0, &post);
    let share = |own_pixel_draws: usize| {
        let cfg = RaySamplerConfig {
            keyframes_per_step: 1,
            own_pixel_draws,
            ..RaySamplerConfig::OBJECT
        };
        let (mut own, mut all) = (0, 0);
        for seed in 0..20 {
            let rays = draw_unboxed(&[&view], &[0], &cfg, seed);
            own += rays.states.iter().filter(|s| **s == PixelState::ThisObject).count();
            all += rays.states.len();
        }
        own as f32 / all as f32
    };
    let uniform = share(0);
    assert!(uniform < 0.12, "uniform in the box: {uniform}");
    let half = share(12);
    assert!(half > 0.3, "half the draws among own pixels: {half}");
    // Each own-pixel draw tries 16 pixels: 1 − 0.95¹⁶ ≈ 56 % of them land on the post.
    let all = share(24);
    assert!(all > 0.45 && all > half, "every draw among own pixels: {all}");

    // Through the keyframe window: only an object alone in its class (with a hidden space)
    // draws them.
    use crate::objects::config::KeyframeConfig;
    use crate::objects::hidden_space::HiddenSpaceCache;
    use crate::objects::keyframes::{KeyframeRole, KeyframeWindow};
    let mut window = KeyframeWindow::default();
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    window.offer(
        FrameIndex(0),
        view,
        KeyframeRole::Object,
        &KeyframeConfig::default(),
        &mut rng,
    );
    let cfg = RaySamplerConfig {
        keyframes_per_step: 1,
        own_pixel_draws: 24,
        ..RaySamplerConfig::OBJECT
    };
    let post_box = aabb([-0.05, 1.15, -1.0], [0.05, 1.25, 1.0]);
    let window_share = |alone: bool| {
        let mut cache = HiddenSpaceCache::default();
        let own: usize = (0..20)
            .map(|seed| {
                let hidden = alone.then_some((&mut cache, &post_box));
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                let rays = sample_window_rays(&window, &Point3::origin(), None, hidden, &[], &cfg, &mut rng);
                rays.states.iter().filter(|s| **s == PixelState::ThisObject).count()
            })
            .sum();
        own as f32 / (20.0 * 24.0)
    };
    assert!(window_share(true) > 0.45, "alone in its class: {}", window_share(true));
    assert!(window_share(false) < 0.12, "a member: {}", window_share(false));
}
