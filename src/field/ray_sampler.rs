//! The depth-guided ray sampler (METHOD.md §2): which pixels of an object's keyframes one
//! training step uses, and where along each pixel's ray the field is sampled.
//!
//! Per step, `keyframes_per_step` views take part — the (up to) two newest keyframes always,
//! the rest drawn uniformly from the older ones — and each gives `pixels_per_keyframe` pixels
//! drawn uniformly inside the view's stored (enlarged) 2D box. Along the ray
//! `r(z) = o + z·R·((u − cx)/fx, (v − cy)/fy, 1)` (z is camera depth) with measured depth `d`:
//! - `free_samples` stratified in `[0, d − band]` (free space before the surface), and
//!   `box_free_samples` stratified on the part of that interval inside the object's box when a
//!   box is given and the ray crosses it there (else in `[0, d − band]` too; see
//!   [`super::free_space`]);
//! - if the pixel is the object's (or unknown): `surface_samples` sorted at
//!   `d + clip(N(0, (band/3)²), ±band)`;
//! - if it shows another object or the background: `surface_samples` stratified in
//!   `[d − band, d + behind]` — the ray stops just behind the occluder;
//! - if its label is unsure ([`UnsurePixels::FreeBeforeReturn`]): the ray is sampled as if it
//!   returned at d − a·d² (the view's depth noise allowance), its `surface_samples` stratified
//!   in the band before that, `[d − a·d² − 2·band, d − a·d² − band]`: free space, whoever's
//!   surface it met;
//! - invalid depth: all samples stratified in `[0, max valid depth of the step's rays]`; for
//!   another object's pixel with a depth within [`NO_RETURN_RADIUS_PX`] (a depth camera's hole
//!   at a depth edge), in `[0, nearest of those depths − band]`: the surface beside the hole hid
//!   what lies behind it, and a ray through to the step's deepest return carved an object's
//!   unseen legs behind a table's edge.
//!
//! The rays are returned with those of this object's (and unknown) pixels first: the others'
//! colour is never read, and a step skips their colour branch.

use nalgebra::{Point3, Vector3};
use rand::{Rng, RngExt};

use super::free_space::{CarveCounts, carving_interval, ray_box_interval};
use super::samples::RaySamples;
use super::solid_prior::{PriorRays, append_prior_rays};
use crate::geometry::mirror_symmetry::MirrorPlane;
use crate::geometry::oriented_box::OrientedBox;
use crate::objects::cell_evidence::{GLIMPSE_MARGIN_M, NO_RETURN_RADIUS_PX, ViewEvidence, view_evidence};
use crate::objects::hidden_space::{CellRules, FREE_CLEARANCE_M, HiddenSpace, HiddenSpaceCache};
use crate::objects::keyframes::KeyframeWindow;
use crate::objects::object_view::{ObjectView, PixelState};

pub use super::ray_sampler_config::{RaySamplerConfig, UnsurePixels};

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

/// Draws per pixel before an own-pixel draw keeps what it has
/// ([`RaySamplerConfig::own_pixel_draws`]).
pub const OWN_PIXEL_TRIES: usize = 16;

/// The rays of one training step of the field at `field_origin` whose views are `window`'s
/// keyframes (its newest ones always take part; see [`sample_training_rays`]).
/// With `hidden` (a cache and the box fitted to the object's observed cloud: an object alone in
/// its class), `own_pixel_draws` of each keyframe's pixels are drawn among the object's own, and
/// `hidden_solid_rays` prior rays follow, drawn in the cells of that box no view saw into (the
/// cache is brought up to date first), and for each of its `mirror` planes (the best first)
/// `mirror_rays` keyframe rays reflected across it.
pub fn sample_window_rays(
    window: &KeyframeWindow<ObjectView>,
    field_origin: &Point3<f32>,
    object_box: Option<&OrientedBox>,
    hidden: Option<(&mut HiddenSpaceCache, &OrientedBox)>,
    mirror: &[MirrorPlane],
    cfg: &RaySamplerConfig,
    rng: &mut impl Rng,
) -> RaySamples {
    let views: Vec<&ObjectView> = window.slots().iter().map(|s| &s.data).collect();
    let recent = window.recent_slots();
    // Own-pixel draws are for objects alone in their class (those with a hidden space): members
    // of a class learn their thin parts from their twins, and with draws among their own pixels
    // default seed 2's chairs lost free space around them (completion 1.10 → 1.21 cm).
    let cfg = &cfg.with_own_pixel_draws(if hidden.is_some() { cfg.own_pixel_draws() } else { 0 });
    let mut rays = sample_training_rays(&views, recent, field_origin, object_box, cfg, rng);
    if hidden.is_some() && cfg.mirror_rays() > 0 {
        let mirrored_cfg = cfg.with_rays_per_step(cfg.mirror_rays());
        for plane in mirror {
            let mirrored = sample_rays(&views, recent, field_origin, None, &mirrored_cfg, Some(plane), rng);
            rays = rays.followed_by(mirrored).with_colour_rays_first();
        }
    }
    let counts = PriorRays {
        hidden_solid: cfg.solid_prior_rays(),
        below_support: cfg.below_support_rays(),
        seen_free: cfg.seen_free_rays(),
        weight: cfg.hidden_solid_weight,
    };
    if let Some((cache, fitted_box)) = hidden
        && counts.hidden_solid + counts.below_support + counts.seen_free > 0
    {
        let rules = CellRules {
            hidden: cfg.hidden_cells,
            unseen: cfg.unseen_cells,
            free: cfg.free_cells,
        };
        let space = cache.current(&views, fitted_box, mirror.first(), rules);
        append_prior_rays(&mut rays, space, &views, counts, field_origin, rng);
    }
    rays
}

/// The rays of one step of a category member: its keyframe rays carving `meshed_box` (the
/// region its mesh is extracted in; no own-pixel draws, no mirror), then with `shared` (the cells
/// of its box no member of its field saw into, [`crate::categories::member_hidden`])
/// `solid_rays` solid-prior rays drawn in them.
pub fn sample_member_rays(
    window: &KeyframeWindow<ObjectView>,
    field_origin: &Point3<f32>,
    meshed_box: &OrientedBox,
    shared: Option<&HiddenSpace>,
    (cfg, solid_rays): (&RaySamplerConfig, usize),
    rng: &mut impl Rng,
) -> RaySamples {
    let mut rays = sample_window_rays(window, field_origin, Some(meshed_box), None, &[], cfg, rng);
    if let Some(space) = shared.filter(|_| solid_rays > 0) {
        let views: Vec<&ObjectView> = window.slots().iter().map(|s| &s.data).collect();
        let counts = PriorRays {
            hidden_solid: solid_rays,
            below_support: 0,
            seen_free: 0,
            weight: cfg.hidden_solid_weight,
        };
        append_prior_rays(&mut rays, space, &views, counts, field_origin, rng);
    }
    rays
}

/// Draws one step's rays for one field from its keyframe `views` (`recent` = indices of the two
/// newest in `views`). Sample points are returned relative to `field_origin` (world minus
/// origin), the frame the field is defined in. `object_box` (world) is the region the field is
/// meshed in: the box samples carve it, and the returned [`RaySamples::carve`] counts the samples
/// inside it (no box: no box samples, no counts).
pub fn sample_training_rays(
    views: &[&ObjectView],
    recent: &[usize],
    field_origin: &Point3<f32>,
    object_box: Option<&OrientedBox>,
    cfg: &RaySamplerConfig,
    rng: &mut impl Rng,
) -> RaySamples {
    sample_rays(views, recent, field_origin, object_box, cfg, None, rng)
}

/// [`sample_training_rays`], each ray reflected across `reflect` when given. Then only rays of
/// the object's pixels with valid depth are kept, and not those whose reflected surface point a
/// view saw free by [`GLIMPSE_MARGIN_M`] (the object is not symmetric there) or that pass the
/// object's observed surface before it ([`passes_the_observed_surface`]): a reflected ray of
/// another object's pixel asks for free space all the way to that object, and one that grazed the
/// floor beside the object, reflected across a plane a degree off, cuts through its base.
fn sample_rays(
    views: &[&ObjectView],
    recent: &[usize],
    field_origin: &Point3<f32>,
    object_box: Option<&OrientedBox>,
    cfg: &RaySamplerConfig,
    reflect: Option<&MirrorPlane>,
    rng: &mut impl Rng,
) -> RaySamples {
    let chosen = choose_step_views(views.len(), recent, cfg.keyframes_per_step, rng);
    let mut pixels = Vec::with_capacity(chosen.len() * cfg.pixels_per_keyframe);
    for &v in &chosen {
        let view = views[v];
        let (w, h) = (view.region.width(), view.region.height());
        for k in 0..cfg.pixels_per_keyframe {
            let tries = if k < cfg.own_pixel_draws() { OWN_PIXEL_TRIES } else { 1 };
            let (mut du, mut dv) = (0, 0);
            for _ in 0..tries {
                du = rng.random_range(0..w);
                dv = rng.random_range(0..h);
                if view.states[(dv * w + du) as usize] == PixelState::ThisObject {
                    break;
                }
            }
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
        carve: CarveCounts::default(),
        solid_weight: 0.0,
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
        // An unsure pixel's ray is sampled as if it returned at its depth less the noise
        // allowance: all its samples then lie before the surface, whoever's it is.
        let depth = match (state, cfg.unsure_pixels) {
            (PixelState::Unsure, UnsurePixels::Skipped) => continue,
            (PixelState::Unsure, UnsurePixels::FreeBeforeReturn) => {
                let before = depth - view.depth_noise_m(depth);
                // Also no depth (0): nothing before it to teach.
                if before <= cfg.surface_band_m {
                    continue;
                }
                before
            }
            _ => depth,
        };
        let (camera, dir) = pixel_ray(view, u, row);
        let (camera, dir) = match reflect {
            Some(plane) => (plane.reflect(&camera), plane.reflect_vector(&dir)),
            None => (camera, dir),
        };
        if reflect.is_some() {
            let seen_free = |p: &Point3<f32>| {
                views
                    .iter()
                    .any(|v| view_evidence(v, p, GLIMPSE_MARGIN_M) == ViewEvidence::Free)
            };
            if !(state.reads_colour() && depth > 0.0) || seen_free(&(camera + dir * depth)) {
                continue;
            }
        }
        let free_end = depth - cfg.surface_band_m;
        let crossing = object_box.and_then(|b| ray_box_interval(b, &camera, &dir));
        let carve = crossing
            .filter(|_| depth > 0.0 && cfg.carving_samples() > 0)
            .and_then(|c| carving_interval(c, free_end, MIN_CARVE_M));
        let reach = match (depth > 0.0, state.reads_colour()) {
            (false, false) => view
                .nearest_return_around(u, row, NO_RETURN_RADIUS_PX)
                .map_or(max_depth, |d| (d - cfg.surface_band_m).max(f32::MIN_POSITIVE)),
            _ => max_depth,
        };
        depths_along_ray(depth, state, reach, carve, cfg, rng, &mut z);
        if reflect.is_some() && passes_the_observed_surface(views, &camera, &dir, &z, depth) {
            continue;
        }

        let origin = camera - field_origin.coords;
        for &zi in &z {
            let p = origin + dir * zi;
            out.points.push([p.x, p.y, p.z]);
        }
        if let Some((t_in, t_out)) = crossing {
            for &zi in z.iter().filter(|&&zi| (t_in..=t_out).contains(&zi)) {
                out.carve.inside += 1;
                out.carve.carving += u64::from(depth > 0.0 && zi < free_end);
            }
        }
        out.z.extend_from_slice(&z);
        out.depth_m.push(depth);
        let c = view.rgb[i];
        out.rgb.push(c.map(|x| f32::from(x) / 255.0));
        out.states.push(state);
    }
    out.with_colour_rays_first()
}

/// Whether a sample of the ray from `camera` along `dir` before its surface at `depth` (by more
/// than [`FREE_CLEARANCE_M`]) lies within [`FREE_CLEARANCE_M`] of the object's surface as a view
/// sees it: a reflected ray that passes the real object on its way asks its thin parts (a lamp's
/// 2.6 cm pole, beside which a plane 1 cm off puts the pole's mirror image) to be empty.
fn passes_the_observed_surface(
    views: &[&ObjectView],
    camera: &Point3<f32>,
    dir: &Vector3<f32>,
    z: &[f32],
    depth: f32,
) -> bool {
    z.iter().filter(|&&zi| zi < depth - FREE_CLEARANCE_M).any(|&zi| {
        let p = camera + dir * zi;
        views
            .iter()
            .any(|v| view_evidence(v, &p, FREE_CLEARANCE_M) == ViewEvidence::AtObjectSurface)
    })
}

/// The camera centre and the ray direction (camera z = 1) of full-frame pixel (`u`, `row`).
fn pixel_ray(view: &ObjectView, u: u32, row: u32) -> (Point3<f32>, Vector3<f32>) {
    let k = &view.intrinsics;
    let dir_camera = Vector3::new((u as f32 - k.cx) / k.fx, (row as f32 - k.cy) / k.fy, 1.0);
    let dir = view.world_from_camera.rotation * dir_camera;
    (Point3::from(view.world_from_camera.translation.vector), dir)
}

/// The shortest stretch of a ray inside the box worth carving, metres of camera depth.
const MIN_CARVE_M: f32 = 1e-3;

/// The sorted sample depths of one ray (see the module doc), written into `z`; `carve` is the
/// ray's carving interval in the object's box, if any; a ray without depth is sampled up to
/// `reach`.
fn depths_along_ray(
    depth: f32,
    state: PixelState,
    reach: f32,
    carve: Option<(f32, f32)>,
    cfg: &RaySamplerConfig,
    rng: &mut impl Rng,
    z: &mut Vec<f32>,
) {
    z.clear();
    let band = cfg.surface_band_m;
    if depth <= 0.0 {
        let far = if reach > 0.0 { reach } else { band };
        stratified(0.0, far, cfg.samples_per_ray(), rng, z);
        return;
    }
    let free_end = (depth - band).max(0.0);
    stratified(0.0, free_end, cfg.free_samples, rng, z);
    let (near, far) = carve.unwrap_or((0.0, free_end));
    stratified(near, far, cfg.carving_samples(), rng, z);
    z.sort_by(f32::total_cmp);
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
        // Another object's ray stopped short: its last samples lie in the band before the
        // point it is free up to, not around its return.
        PixelState::Unsure => {
            stratified((free_end - band).max(0.0), free_end, cfg.surface_samples, rng, z);
            z.sort_by(f32::total_cmp);
        }
        // Views hold no prior rays; were one there, it would only teach free space.
        PixelState::OtherObject | PixelState::HiddenSolid | PixelState::BelowSupport | PixelState::SeenFree => {
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
#[path = "ray_sampler_tests.rs"]
mod tests;

#[cfg(test)]
#[path = "ray_sampler_unsure_tests.rs"]
mod unsure_tests;
