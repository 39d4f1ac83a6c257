//! The second mirror plane of a round object: the vertical plane through its axis of revolution
//! at right angles to its first plane.
//!
//! A round object (a lamp, a round stool) is symmetric about every vertical plane through its
//! axis. Seen from one side, the mirror search finds the plane along the views — it maps the
//! seen half onto itself — and no second plane: the plane across the views would map the seen
//! front onto the back no view saw, so its reflections match nothing. The back then comes from
//! the box alone, and a round footprint has no preferred turn: the default scene's lamp got a
//! box turned ~60° under a depth camera's noise, its unseen back drawn out to a box corner.
//! Here the axis is found from what was seen: it lies in the first plane, and about it every
//! height slice's points lie at one radius.

use nalgebra::{Point3, Vector3};

use super::mirror_symmetry::MirrorPlane;

/// Height of a slice, metres.
pub const SLICE_M: f32 = 0.05;

/// How far a point's distance to the axis may be from its slice's median for it to lie on the
/// slice's circle, metres.
pub const RADIUS_TOLERANCE_M: f32 = 0.02;

/// Least share of the points that must lie on their slice's circle.
pub const MIN_ROUND_SHARE: f32 = 0.8;

/// Least turn about the axis the points must cover (in 10° sectors), degrees.
pub const MIN_ARC_DEG: f32 = 120.0;

/// Step of the search for the axis along the first plane, metres.
const STEP_M: f32 = 0.005;

/// Fewest points the test needs.
const MIN_POINTS: usize = 100;

/// The vertical plane through the axis of revolution of `points` (z up) at right angles to
/// `first`, when they are round about an axis in `first` (module doc).
pub fn plane_across_axis(points: &[Point3<f32>], first: &MirrorPlane) -> Option<MirrorPlane> {
    if points.len() < MIN_POINTS {
        return None;
    }
    let n = Vector3::new(first.normal.x, first.normal.y, 0.0).try_normalize(1e-6)?;
    let along = Vector3::new(-n.y, n.x, 0.0);
    // Each point's place along the plane and distance off it, grouped by height slice (once).
    let mut slices: std::collections::BTreeMap<i64, Vec<(f32, f32)>> = std::collections::BTreeMap::new();
    for p in points {
        let placed = (p.coords.dot(&along), p.coords.dot(&n) - first.offset);
        slices.entry((p.z / SLICE_M).floor() as i64).or_default().push(placed);
    }
    let slices: Vec<Vec<(f32, f32)>> = slices.into_values().collect();
    let (lo, hi) = slices
        .iter()
        .flatten()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &(s, _)| {
            (lo.min(s), hi.max(s))
        });
    let steps = ((hi - lo) / STEP_M).ceil() as usize;
    let mut radii = Vec::new();
    let (on_circles, t) = (0..=steps)
        .map(|k| lo + k as f32 * STEP_M)
        .map(|t| (on_their_circles(&slices, t, &mut radii), t))
        .fold((0, lo), |best, c| if c.0 > best.0 { c } else { best });
    if (on_circles as f32) < MIN_ROUND_SHARE * points.len() as f32 || arc_deg(&slices, t) < MIN_ARC_DEG {
        return None;
    }
    Some(MirrorPlane {
        normal: along,
        offset: t,
    })
}

/// How many points lie within [`RADIUS_TOLERANCE_M`] of their slice's median distance to the
/// axis at `t` along the plane (`radii`: a buffer reused between calls).
fn on_their_circles(slices: &[Vec<(f32, f32)>], t: f32, radii: &mut Vec<f32>) -> usize {
    slices
        .iter()
        .map(|slice| {
            radii.clear();
            radii.extend(slice.iter().map(|&(s, w)| (s - t).hypot(w)));
            radii.sort_by(f32::total_cmp);
            let median = radii[radii.len() / 2];
            radii
                .iter()
                .filter(|r| (*r - median).abs() <= RADIUS_TOLERANCE_M)
                .count()
        })
        .sum()
}

/// The turn about the axis at `t` the points cover, in whole 10° sectors, degrees.
fn arc_deg(slices: &[Vec<(f32, f32)>], t: f32) -> f32 {
    let mut sectors = [false; 36];
    for &(s, w) in slices.iter().flatten() {
        let angle = w.atan2(s - t).to_degrees().rem_euclid(360.0);
        sectors[(angle / 10.0) as usize % 36] = true;
    }
    10.0 * sectors.iter().filter(|&&s| s).count() as f32
}

#[cfg(test)]
#[path = "round_axis_tests.rs"]
pub(crate) mod tests;
