//! A 2D instance segmenter's masks (Mask R-CNN-like), written without reference to catmap's own
//! Kinect-like mask model ([`super::kinect`]).
//!
//! In this order, per frame, objects in id order:
//! 1. **Missed objects, small ones more often**: an object covering a share s of the image is
//!    not segmented with probability `miss_floor` + `miss_small` · exp(−s / `small_share`)
//!    (0.47 at 0.1 % of the image, 0.15 at 0.5 %, 0.02 at 5 %): detectors' recall falls for small
//!    objects (COCO's AP_small is about half AP_large for Mask R-CNN).
//! 2. **Similar classes confused**: with probability `confusion_probability` the mask carries a
//!    class of the object's group ([`similar_classes`]: chair–stool–sofa, table–nightstand–
//!    cabinet, cabinet–shelf–nightstand–box, bed–sofa).
//! 3. **Borders off along their length**: each mask's border moves by an offset that varies
//!    smoothly along the image (a sinusoid of wavelength 40–160 px about a mean, within
//!    ±`border_px`, at 640 px wide): grown here onto whatever lies beside it, shrunk there.
//!    Masks are painted from the farthest object to the nearest, so a nearer mask wins.
//! 4. **Touching objects merged**: two masks that share at least `merge_min_contact_px` border
//!    pixels whose depths differ by less than `merge_depth_step_m` become one mask (the larger's
//!    id and class) with probability `merge_probability`.
//! 5. **A large object split in two**: a mask covering more than `split_min_share` of the image is
//!    cut across its longer axis through its centre with probability `split_probability`; the far
//!    half gets an id of its own.
//! 6. **Spurious masks**: a Poisson number (mean `spurious_per_frame`) of ellipses with radii of
//!    `spurious_radius_px` on floor, wall or unlabelled pixels, each with one of the scene's object
//!    classes and an id of its own.
//!
//! Ids of their own (split halves, spurious masks) are new in every frame (1000 and up), so with
//! consistent ids they name nothing seen in another frame.

use std::collections::BTreeMap;

use rand::RngExt;

use super::is_object;
use crate::dataset::classes::replica;
use crate::ids::ClassId;
use crate::synth::render::RenderedFrame;

/// The segmenter's parameters (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmenterNoise {
    /// Largest border offset, pixels at 640 px wide (2).
    pub border_px: f32,
    /// Chance of a miss however large the object (0.02).
    pub miss_floor: f32,
    /// Extra chance of a miss for a vanishingly small object (0.6).
    pub miss_small: f32,
    /// Image share over which the extra chance falls by e (0.003).
    pub small_share: f32,
    /// Chance a mask carries a similar class (0.05).
    pub confusion_probability: f32,
    /// Chance two touching masks become one (0.2).
    pub merge_probability: f32,
    /// Border pixels two masks must share to touch (8, at 640 px wide).
    pub merge_min_contact_px: usize,
    /// Largest depth step across a touching border, metres (0.15).
    pub merge_depth_step_m: f32,
    /// Smallest image share of a mask that may be split (0.06).
    pub split_min_share: f32,
    /// Chance such a mask is split (0.15).
    pub split_probability: f32,
    /// Mean number of spurious masks per frame (0.3).
    pub spurious_per_frame: f32,
    /// Radii of a spurious mask's ellipse, pixels at 640 px wide (8 to 40).
    pub spurious_radius_px: (f32, f32),
}

impl Default for SegmenterNoise {
    fn default() -> Self {
        Self {
            border_px: 2.0,
            miss_floor: 0.02,
            miss_small: 0.6,
            small_share: 0.003,
            confusion_probability: 0.05,
            merge_probability: 0.2,
            merge_min_contact_px: 8,
            merge_depth_step_m: 0.15,
            split_min_share: 0.06,
            split_probability: 0.15,
            spurious_per_frame: 0.3,
            spurious_radius_px: (8.0, 40.0),
        }
    }
}

/// The classes a segmenter may say instead of `class` (none for a class without a group).
pub fn similar_classes(class: ClassId) -> Vec<ClassId> {
    use replica::{BED, BOX, CABINET, CHAIR, NIGHTSTAND, SHELF, SOFA, STOOL, TABLE};
    const GROUPS: [&[ClassId]; 4] = [
        &[CHAIR, STOOL, SOFA],
        &[TABLE, NIGHTSTAND, CABINET],
        &[CABINET, SHELF, NIGHTSTAND, BOX],
        &[BED, SOFA],
    ];
    let mut similar: Vec<ClassId> = GROUPS
        .iter()
        .filter(|g| g.contains(&class))
        .flat_map(|g| g.iter().copied())
        .filter(|&c| c != class)
        .collect();
    similar.sort_unstable();
    similar.dedup();
    similar
}

/// One object's mask as the segmenter gives it, before painting.
struct Mask {
    id: u16,
    class: ClassId,
    pixels: Vec<usize>,
    mean_depth: f32,
}

impl SegmenterNoise {
    /// Degrades `frame`'s masks (module doc); `position` makes the frame's own ids new.
    pub fn degrade(&self, frame: &mut RenderedFrame, position: usize, classes: &[ClassId], rng: &mut impl rand::Rng) {
        let (w, h) = (frame.intrinsics.width as usize, frame.intrinsics.height as usize);
        let scale = w as f32 / 640.0;
        let mut objects: BTreeMap<u16, Vec<usize>> = BTreeMap::new();
        for i in 0..frame.instance_ids.len() {
            if is_object(frame, i) {
                objects.entry(frame.instance_ids[i]).or_default().push(i);
            }
        }
        let mut fresh = FreshIds::new(position);
        let mut masks: Vec<Mask> = Vec::new();
        for (&id, own) in &objects {
            let share = own.len() as f32 / (w * h) as f32;
            let missed = rng.random::<f32>() < self.miss_floor + self.miss_small * (-share / self.small_share).exp();
            let confused = rng.random::<f32>() < self.confusion_probability;
            let offset = BorderOffset::draw(self.border_px * scale, scale, rng);
            let class = frame.classes[own[0]];
            let similar = similar_classes(class);
            let said = if confused && !similar.is_empty() {
                similar[rng.random_range(0..similar.len())]
            } else {
                class
            };
            if missed {
                continue;
            }
            let inside = |i: usize| frame.instance_ids[i] == id && is_object(frame, i);
            let pixels = offset.apply(own, &inside, w, h);
            let depths: Vec<f32> = own.iter().map(|&i| frame.depth_m[i]).filter(|&d| d > 0.0).collect();
            let mean_depth = depths.iter().sum::<f32>() / depths.len().max(1) as f32;
            masks.push(Mask {
                id,
                class: said,
                pixels,
                mean_depth,
            });
        }
        for own in objects.values() {
            for &i in own {
                frame.instance_ids[i] = 0;
                frame.classes[i] = ClassId(0);
            }
        }
        masks.sort_by(|a, b| b.mean_depth.total_cmp(&a.mean_depth).then(a.id.cmp(&b.id)));
        for m in &masks {
            for &i in &m.pixels {
                frame.instance_ids[i] = m.id;
                frame.classes[i] = m.class;
            }
        }
        self.merge_touching(frame, scale, rng);
        self.split_large(frame, &mut fresh, rng);
        self.add_spurious(frame, classes, scale, &mut fresh, rng);
    }

    /// Step 4.
    fn merge_touching(&self, frame: &mut RenderedFrame, scale: f32, rng: &mut impl rand::Rng) {
        let w = frame.intrinsics.width as usize;
        let n = frame.instance_ids.len();
        let mut contact: BTreeMap<(u16, u16), usize> = BTreeMap::new();
        let mut size: BTreeMap<u16, usize> = BTreeMap::new();
        for i in 0..n {
            if !is_object(frame, i) {
                continue;
            }
            *size.entry(frame.instance_ids[i]).or_default() += 1;
            for j in [(i % w + 1 < w).then(|| i + 1), (i + w < n).then(|| i + w)]
                .into_iter()
                .flatten()
            {
                let (a, b) = (frame.instance_ids[i], frame.instance_ids[j]);
                let (da, db) = (frame.depth_m[i], frame.depth_m[j]);
                if is_object(frame, j) && a != b && da > 0.0 && db > 0.0 && (da - db).abs() < self.merge_depth_step_m {
                    *contact.entry((a.min(b), a.max(b))).or_default() += 1;
                }
            }
        }
        let least = ((self.merge_min_contact_px as f32 * scale).round() as usize).max(1);
        let mut merged: Vec<u16> = Vec::new();
        for (&(a, b), &count) in &contact {
            if count < least
                || merged.contains(&a)
                || merged.contains(&b)
                || rng.random::<f32>() >= self.merge_probability
            {
                continue;
            }
            let (keep, lose) = if size[&a] >= size[&b] { (a, b) } else { (b, a) };
            let keep_class = (0..n)
                .find(|&i| frame.instance_ids[i] == keep && is_object(frame, i))
                .map(|i| frame.classes[i]);
            if let Some(class) = keep_class {
                for i in 0..n {
                    if frame.instance_ids[i] == lose && is_object(frame, i) {
                        frame.instance_ids[i] = keep;
                        frame.classes[i] = class;
                    }
                }
            }
            merged.extend([a, b]);
        }
    }

    /// Step 5.
    fn split_large(&self, frame: &mut RenderedFrame, fresh: &mut FreshIds, rng: &mut impl rand::Rng) {
        let (w, n) = (frame.intrinsics.width as usize, frame.instance_ids.len());
        let mut objects: BTreeMap<u16, Vec<usize>> = BTreeMap::new();
        for i in 0..n {
            if is_object(frame, i) {
                objects.entry(frame.instance_ids[i]).or_default().push(i);
            }
        }
        for own in objects.values() {
            if (own.len() as f32) < self.split_min_share * n as f32 || rng.random::<f32>() >= self.split_probability {
                continue;
            }
            let count = own.len() as f64;
            let (mu, mv) = own.iter().fold((0.0, 0.0), |(a, b), &i| {
                (a + (i % w) as f64 / count, b + (i / w) as f64 / count)
            });
            let (mut suu, mut svv) = (0.0, 0.0);
            for &i in own {
                suu += ((i % w) as f64 - mu).powi(2);
                svv += ((i / w) as f64 - mv).powi(2);
            }
            let along_u = suu >= svv;
            let id = fresh.next();
            for &i in own {
                let far_half = if along_u {
                    (i % w) as f64 > mu
                } else {
                    (i / w) as f64 > mv
                };
                if far_half {
                    frame.instance_ids[i] = id;
                }
            }
        }
    }

    /// Step 6.
    fn add_spurious(
        &self,
        frame: &mut RenderedFrame,
        classes: &[ClassId],
        scale: f32,
        fresh: &mut FreshIds,
        rng: &mut impl rand::Rng,
    ) {
        let (w, h) = (frame.intrinsics.width as usize, frame.intrinsics.height as usize);
        let mut count = 0;
        let (limit, mut product) = ((-self.spurious_per_frame).exp(), rng.random::<f32>());
        while product > limit && count < 8 {
            count += 1;
            product *= rng.random::<f32>();
        }
        for _ in 0..count {
            let (lo, hi) = self.spurious_radius_px;
            let (ra, rb) = (rng.random_range(lo..=hi) * scale, rng.random_range(lo..=hi) * scale);
            let (cu, cv) = (rng.random_range(0..w) as f32, rng.random_range(0..h) as f32);
            let angle = rng.random_range(0.0..std::f32::consts::PI);
            if classes.is_empty() {
                continue;
            }
            let class = classes[rng.random_range(0..classes.len())];
            let id = fresh.next();
            let (c, s) = (angle.cos(), angle.sin());
            let reach = ra.max(rb).ceil() as i64;
            for dv in -reach..=reach {
                for du in -reach..=reach {
                    let (x, y) = (cu as i64 + du, cv as i64 + dv);
                    if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                        continue;
                    }
                    let (a, b) = (du as f32 * c + dv as f32 * s, -(du as f32) * s + dv as f32 * c);
                    let i = y as usize * w + x as usize;
                    if (a / ra).powi(2) + (b / rb).powi(2) <= 1.0 && !is_object(frame, i) {
                        frame.instance_ids[i] = id;
                        frame.classes[i] = class;
                    }
                }
            }
        }
    }
}

/// Step 3's offset: mean + amplitude · sin(2π (u cos φ + v sin φ) / λ + ψ), within ± the largest.
struct BorderOffset {
    largest: f32,
    mean: f32,
    amplitude: f32,
    direction: (f32, f32),
    wavelength: f32,
    phase: f32,
}

impl BorderOffset {
    fn draw(largest: f32, scale: f32, rng: &mut impl rand::Rng) -> Self {
        let angle = rng.random_range(0.0..std::f32::consts::TAU);
        Self {
            largest,
            mean: rng.random_range(-0.5..=0.5) * largest,
            amplitude: rng.random_range(0.25..=0.75) * largest,
            direction: (angle.cos(), angle.sin()),
            wavelength: rng.random_range(40.0..=160.0) * scale,
            phase: rng.random_range(0.0..std::f32::consts::TAU),
        }
    }

    fn at(&self, u: usize, v: usize) -> f32 {
        let t = (u as f32 * self.direction.0 + v as f32 * self.direction.1) / self.wavelength;
        (self.mean + self.amplitude * (std::f32::consts::TAU * t + self.phase).sin()).clamp(-self.largest, self.largest)
    }

    /// The mask `own` (pixels where `inside` holds) with its border moved: an inside pixel stays
    /// when it lies farther than −offset from every outside pixel, an outside pixel joins when it
    /// lies within +offset of an inside one.
    fn apply(&self, own: &[usize], inside: &dyn Fn(usize) -> bool, w: usize, h: usize) -> Vec<usize> {
        let reach = self.largest.ceil() as i64;
        let (mut u0, mut v0, mut u1, mut v1) = (usize::MAX, usize::MAX, 0, 0);
        for &i in own {
            (u0, v0, u1, v1) = (u0.min(i % w), v0.min(i / w), u1.max(i % w), v1.max(i / w));
        }
        let grow = |x: usize, lo: usize| x.saturating_sub(reach as usize).max(lo);
        let mut kept = Vec::new();
        for v in grow(v0, 0)..=(v1 + reach as usize).min(h - 1) {
            for u in grow(u0, 0)..=(u1 + reach as usize).min(w - 1) {
                let i = v * w + u;
                let is_in = inside(i);
                let offset = self.at(u, v);
                let mut nearest = f32::INFINITY;
                for dv in -reach..=reach {
                    for du in -reach..=reach {
                        let (x, y) = (u as i64 + du, v as i64 + dv);
                        if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                            continue;
                        }
                        if inside(y as usize * w + x as usize) != is_in {
                            nearest = nearest.min(((du * du + dv * dv) as f32).sqrt());
                        }
                    }
                }
                let keep = if is_in { nearest > -offset } else { nearest <= offset };
                if keep {
                    kept.push(i);
                }
            }
        }
        kept
    }
}

/// Ids of the frame's own masks: 1000 + 16 × the frame's position + a counter, below 61 000.
struct FreshIds {
    next: u32,
}

impl FreshIds {
    fn new(position: usize) -> Self {
        Self {
            next: (position as u32 % 3750) * 16,
        }
    }

    fn next(&mut self) -> u16 {
        let id = 1000 + self.next % 60_000;
        self.next += 1;
        id as u16
    }
}
