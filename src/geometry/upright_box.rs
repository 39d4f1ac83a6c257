//! Upright boxes: furniture stands on the floor, so its box stands on world z and only its turn
//! about z is fitted.
//!
//! [`fit_upright_box`] turns the box so that the rectangle around the points' footprint has the
//! least area. That rectangle is ambiguous when an object is seen from one corner: its footprint
//! is an L (two faces and part of the top), and the rectangle along the L's diagonal is about as
//! small as the right one — a little less once a corner of the L is missing. Under a segmenter's
//! masks the default scene's cabinet got a box turned 28° from its faces, 0.92 × 0.40 m for
//! 0.80 × 0.49 m.
//!
//! [`fit_upright_box_on_faces`] also asks how close the points lie to the rectangle's sides (the
//! closeness criterion of Zhang et al., "Efficient L-shape fitting for vehicle detection using
//! laser scanners", IV 2017): each point scores 1 / max(d, [`SIDE_DISTANCE_FLOOR_M`]), `d` its
//! distance to the nearest side. A furniture's faces are its box's sides, and a face counts once
//! per voxel of its height, so the faces outweigh the top. Where the least footprint's turn
//! scores below [`FACES_OFF_SIDES_RATIO`] of the best turn's, the faces do not lie on its sides
//! and the best turn wins; otherwise the least footprint stays (a round lamp or stool has no
//! faces to go by, and its least footprint is what the rest of the pipeline has always used).
//!
//! Both draw the footprint (turn and sides) from the points more than [`BASE_SLAB_M`] above the
//! lowest ([`footprint_points`]); the height spans every point. A segmenter's mask grows onto the
//! floor around an object's feet, and those floor pixels, seen in a few frames each, put points
//! a few centimetres beside the object at floor height: under the default scene's segmenter-like
//! masks two armchairs' boxes were 6 cm too deep. A leg or a base rises above the slab, so the
//! footprint of an object standing on the floor loses nothing.

use nalgebra::{Point3, Vector2, Vector3};

use super::face_normals_turn::BoxTurn;
use super::oriented_box::{OrientedBox, centred_cloud, fit_around_axis};
use crate::error::Result;

/// A point nearer a side than this scores as if this near, metres: the thinned cloud's points
/// are voxel centroids, a centimetre or so off their face.
pub const SIDE_DISTANCE_FLOOR_M: f64 = 0.01;

/// The least footprint's turn is kept unless its closeness score falls below this fraction of
/// the best turn's (module doc). Seen whole, every object of the default scene scores 0.96–1.0
/// at its least footprint; the cabinet seen from one corner scored 0.39.
pub const FACES_OFF_SIDES_RATIO: f64 = 0.8;

/// Points this close above the lowest point are left out of an upright box's footprint, metres
/// (module doc): a floor point's voxel centroid lies within a centimetre of the floor.
pub const BASE_SLAB_M: f64 = 0.015;

/// Turns tried over the quarter circle (a rectangle repeats every 90°).
const COARSE_TURNS: usize = 360;

/// The upright box of `points` with the least footprint: its z along world z, turned about it so
/// that the rectangle around the points' projection on the floor has the least area (axes as
/// [`super::oriented_box::fit_minimum_volume_box`]'s). A partly seen object's minimum-volume box
/// may lean (a bed seen from its foot and one side, 13°); furniture stands upright. Errors on an
/// empty or non-finite cloud.
pub fn fit_upright_box(points: &[Point3<f32>]) -> Result<OrientedBox> {
    let (mean, centred) = centred_cloud(points)?;
    let footprint = footprint_points(&centred);
    let mut fit = fit_around_axis(&footprint, Vector3::z());
    fit.measure_upright(&footprint, &centred);
    Ok(fit.into_box(mean))
}

/// The points more than [`BASE_SLAB_M`] above the lowest of `points`; all of them when none is
/// (a flat object).
pub fn footprint_points(points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let Some(top) = base_slab_top(points.iter().map(|p| p.z)) else {
        return points.to_vec();
    };
    let above: Vec<Vector3<f64>> = points.iter().filter(|p| p.z > top).copied().collect();
    if above.is_empty() { points.to_vec() } else { above }
}

/// The top of the floor slab under points at `heights` (world up, metres): [`BASE_SLAB_M`] above
/// the lowest; `None` when no height is finite. Points at or below it are slab.
pub fn base_slab_top(heights: impl IntoIterator<Item = f64>) -> Option<f64> {
    let floor = heights.into_iter().fold(f64::INFINITY, f64::min);
    floor.is_finite().then_some(floor + BASE_SLAB_M)
}

/// The upright box of `points` turned so that its observed faces lie on its sides where the
/// least footprint's turn leaves them off (module doc), then as `turn` says
/// ([`super::face_normals_turn`]). Errors as [`fit_upright_box`] does.
pub fn fit_upright_box_on_faces(points: &[Point3<f32>], turn: BoxTurn) -> Result<OrientedBox> {
    let (mean, centred) = centred_cloud(points)?;
    let above = footprint_points(&centred);
    let mut fit = fit_around_axis(&above, Vector3::z());
    let footprint: Vec<Vector2<f64>> = above.iter().map(|p| Vector2::new(p.x, p.y)).collect();
    let least = Vector2::new(fit.axes[0].x, fit.axes[0].y);
    let x = turn.turned(&centred, turn_with_faces_on_sides(&footprint, least));
    fit.axes = [Vector3::new(x.x, x.y, 0.0), Vector3::new(-x.y, x.x, 0.0), Vector3::z()];
    fit.measure_upright(&above, &centred);
    Ok(fit.into_box(mean))
}

/// The first axis of the rectangle around `footprint`: `least` (the least-area turn) unless its
/// [`closeness`] falls below [`FACES_OFF_SIDES_RATIO`] of the closest turn's.
pub fn turn_with_faces_on_sides(footprint: &[Vector2<f64>], least: Vector2<f64>) -> Vector2<f64> {
    let best = closest_turn(footprint);
    if closeness(footprint, least) < FACES_OFF_SIDES_RATIO * closeness(footprint, best) {
        best
    } else {
        least
    }
}

/// The turn whose rectangle's sides the points lie closest to: every 0.25° over a quarter
/// circle, then every 0.025° within a step of the best (the first of equals).
fn closest_turn(footprint: &[Vector2<f64>]) -> Vector2<f64> {
    let step = std::f64::consts::FRAC_PI_2 / COARSE_TURNS as f64;
    let best_of = |angles: &mut dyn Iterator<Item = f64>| {
        angles
            .map(|a| (closeness(footprint, Vector2::new(a.cos(), a.sin())), a))
            .fold((f64::NEG_INFINITY, 0.0), |best, c| if c.0 > best.0 { c } else { best })
            .1
    };
    let coarse = best_of(&mut (0..COARSE_TURNS).map(|k| k as f64 * step));
    let fine = best_of(&mut (-10..=10).map(|k| coarse + f64::from(k) * step / 10.0));
    Vector2::new(fine.cos(), fine.sin())
}

/// Σ 1 / max(d, [`SIDE_DISTANCE_FLOOR_M`]) over the points, `d` a point's distance to the
/// nearest side of the rectangle around them with first axis `x` (unit).
pub fn closeness(footprint: &[Vector2<f64>], x: Vector2<f64>) -> f64 {
    let y = Vector2::new(-x.y, x.x);
    let local = |p: &Vector2<f64>| Vector2::new(p.dot(&x), p.dot(&y));
    let (lo, hi) = footprint.iter().fold(
        (Vector2::repeat(f64::INFINITY), Vector2::repeat(f64::NEG_INFINITY)),
        |(lo, hi), p| (lo.inf(&local(p)), hi.sup(&local(p))),
    );
    footprint
        .iter()
        .map(|p| {
            let q = local(p);
            let d = (q - lo).inf(&(hi - q)).min();
            1.0 / d.max(SIDE_DISTANCE_FLOOR_M)
        })
        .sum()
}

#[cfg(test)]
#[path = "upright_box_tests.rs"]
mod tests;
