//! An upright box turned to its upright faces' normals (`objects.box_turn = "face_normals"`).
//!
//! The upright box's rectangle ([`super::upright_box`]) takes its turn from the footprint's
//! outermost points. With exact depth those lie on the faces; under a depth camera's noise they
//! are the noise's tails: the default scene's cabinet, 4.5–6 m from the cameras, got a box turned
//! 2.6° from its faces, and its unseen back, drawn to the box, was a plane turned as much (3 cm
//! off at its ends). Each point's face is the least-squares plane of its neighbours within
//! [`FACE_RADIUS_M`] — a plane when its least spread is at most [`FACE_FLATNESS`] of the next,
//! upright when its normal's height is at most [`FACE_MAX_NORMAL_Z`] — and every point of an
//! upright face within [`FACE_NORMAL_WINDOW_DEG`] of the rectangle's sides votes how far its
//! face turns from them: the median averages the noise over the whole face.
//!
//! Only an object whose cloud is mostly upright faces is turned ([`FACE_MIN_SHARE`] of its
//! points voting, at least [`FACE_MIN_VOTES`] of them). Turned to their faces, the chairs and
//! armchairs (their faces a back, a seat's rim, arms: 20–45 % of their points once seen
//! around) mapped worse on the default scene — the ladder-backs 0.90 → 0.95–1.14 cm accuracy
//! with exact depth, the armchairs +0.1 cm under noise — although their boxes' turns came
//! nearer the truth; an armchair seen from its front is 90–100 % faces over its first ~1000
//! thinned points (≤ 870 voting), the cabinet 84–90 % over 1700–4900 (1450–4100 voting).

use nalgebra::{Point3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use super::local_plane::LocalPlane;
use super::nearest::PointIndex;

/// How an upright box is turned about up once its rectangle is fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoxTurn {
    /// As the rectangle around the footprint lies (exact depth: the default).
    #[default]
    Rectangle,
    /// To the median turn of the upright faces' normals, for an object mostly made of upright
    /// faces (module doc); as the rectangle otherwise.
    FaceNormals,
}

/// Radius of a point's face, metres.
pub const FACE_RADIUS_M: f64 = 0.06;

/// Fewest neighbours a point's face needs.
const MIN_FACE_NEIGHBOURS: usize = 8;

/// Largest ratio of a face's least spread to its next for it to count as a plane.
const FACE_FLATNESS: f64 = 0.2;

/// Largest height of an upright face's unit normal.
const FACE_MAX_NORMAL_Z: f64 = 0.3;

/// Faces turned farther than this from the rectangle's sides do not vote, degrees.
pub const FACE_NORMAL_WINDOW_DEG: f64 = 10.0;

/// Least share of the points that must vote for their faces to turn the box.
pub const FACE_MIN_SHARE: f64 = 0.75;

/// Fewest voting points for the faces to turn the box (at the 2 cm thinning of
/// `objects.bounds_voxel_m`: about 0.6 m² of upright faces).
pub const FACE_MIN_VOTES: usize = 1500;

impl BoxTurn {
    /// The first axis of a rectangle, `x`, turned as `self` says over `points` (centred, z up).
    pub fn turned(self, points: &[Vector3<f64>], x: Vector2<f64>) -> Vector2<f64> {
        match self {
            Self::Rectangle => x,
            Self::FaceNormals => turned_to_face_normals(points, x),
        }
    }
}

/// `x` turned by the median of how far the upright faces of `points` turn from its rectangle's
/// sides, over the faces within [`FACE_NORMAL_WINDOW_DEG`] of them; `x` itself unless at least
/// [`FACE_MIN_VOTES`] points and [`FACE_MIN_SHARE`] of them vote (module doc).
pub fn turned_to_face_normals(points: &[Vector3<f64>], x: Vector2<f64>) -> Vector2<f64> {
    let offsets = face_offsets(points, x.y.atan2(x.x));
    let share = offsets.len() as f64 / points.len().max(1) as f64;
    let Some(median) = median(offsets).filter(|_| share >= FACE_MIN_SHARE) else {
        return x;
    };
    let turned = x.y.atan2(x.x) + median;
    Vector2::new(turned.cos(), turned.sin())
}

/// How far (radians, within the window) each point's upright face turns from the sides of a
/// rectangle turned by `turn`; points not on such a face give none.
fn face_offsets(points: &[Vector3<f64>], turn: f64) -> Vec<f64> {
    let cloud: Vec<Point3<f32>> = points.iter().map(|p| Point3::from(p.cast::<f32>())).collect();
    let Ok(index) = PointIndex::new(&cloud) else {
        return Vec::new();
    };
    let quarter = std::f64::consts::FRAC_PI_2;
    let window = FACE_NORMAL_WINDOW_DEG.to_radians();
    cloud
        .iter()
        .filter_map(|p| {
            let near = index.within(p, FACE_RADIUS_M as f32);
            let normal = upright_face_normal(near.iter().map(|&j| points[j]))?;
            let off = (normal.y.atan2(normal.x) - turn).rem_euclid(quarter);
            let off = if off > quarter / 2.0 { off - quarter } else { off };
            (off.abs() <= window).then_some(off)
        })
        .collect()
}

/// The median of `offsets` when there are at least [`FACE_MIN_VOTES`].
fn median(mut offsets: Vec<f64>) -> Option<f64> {
    if offsets.len() < FACE_MIN_VOTES {
        return None;
    }
    offsets.sort_by(f64::total_cmp);
    Some(offsets[offsets.len() / 2])
}

/// The normal of the plane through `neighbours` when they lie on an upright face (module doc).
fn upright_face_normal(neighbours: impl Iterator<Item = Vector3<f64>> + Clone) -> Option<Vector3<f64>> {
    if neighbours.clone().count() < MIN_FACE_NEIGHBOURS {
        return None;
    }
    let plane = LocalPlane::fit(neighbours)?;
    let normal = plane.normal();
    let flat = plane.spreads[0] <= FACE_FLATNESS * plane.spreads[1];
    (flat && normal.z.abs() <= FACE_MAX_NORMAL_Z).then_some(normal)
}

#[cfg(test)]
#[path = "face_normals_turn_tests.rs"]
mod tests;
